//! Shell elements. The shared continuum-shell kernel is [`shell`]; each element is a tying
//! scheme in its own file. [`REGISTRY`] names the element types so that invariant tests
//! (zero-energy modes, patch tests, symmetry, mass) run over all of them.

mod quad4_mitc;
mod quad9_mitc;
pub mod shell;

pub use quad4_mitc::{Mitc4, NODE_RS, Quad4Mitc, bilinear_shape};
pub use quad9_mitc::{Mitc9, NODE_RS_9, Quad9Mitc, biquadratic_shape};
pub use shell::{DRILLING_FACTOR, SHEAR_CORRECTION};

use serde::{Deserialize, Serialize};

/// Degrees of freedom per node in the global system: u_x, u_y, u_z (m), θ_x, θ_y, θ_z (rad).
pub const DOFS_PER_NODE: usize = 6;

/// A dense square element matrix over the 6 dofs per node of an element, row-major; `m[i][j]`
/// is entry (i, j).
#[derive(Debug, Clone, PartialEq)]
pub struct ElementMatrix {
    n: usize,
    data: Vec<f64>,
}

impl ElementMatrix {
    /// The n × n zero matrix.
    pub fn zeros(n: usize) -> Self {
        Self {
            n,
            data: vec![0.0; n * n],
        }
    }

    /// Number of rows (and columns).
    pub fn size(&self) -> usize {
        self.n
    }
}

impl std::ops::Index<usize> for ElementMatrix {
    type Output = [f64];
    fn index(&self, row: usize) -> &[f64] {
        &self.data[row * self.n..(row + 1) * self.n]
    }
}

impl std::ops::IndexMut<usize> for ElementMatrix {
    fn index_mut(&mut self, row: usize) -> &mut [f64] {
        &mut self.data[row * self.n..(row + 1) * self.n]
    }
}

/// The element family of a mesh: 4-node MITC4 or 9-node MITC9 quadrilaterals.
/// In model files: `element = "mitc4"` or `"mitc9"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ElementOrder {
    /// 4-node bilinear quadrilaterals, MITC4 (the paper's element).
    #[default]
    #[serde(rename = "mitc4")]
    Linear,
    /// 9-node biquadratic quadrilaterals, MITC9.
    #[serde(rename = "mitc9")]
    Quadratic,
}

impl ElementOrder {
    /// Nodes per element: 4 or 9.
    pub fn nodes(self) -> usize {
        match self {
            Self::Linear => 4,
            Self::Quadratic => 9,
        }
    }

    /// The polynomial degree k along an edge: 1 (MITC4) or 2 (MITC9), also the node
    /// intervals per element side.
    pub fn degree(self) -> usize {
        match self {
            Self::Linear => 1,
            Self::Quadratic => 2,
        }
    }

    /// The element's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Linear => "MITC4",
            Self::Quadratic => "MITC9",
        }
    }

    /// Natural coordinates (r_k, s_k) of the element's nodes.
    pub fn node_rs(self) -> &'static [[f64; 2]] {
        match self {
            Self::Linear => &NODE_RS,
            Self::Quadratic => &NODE_RS_9,
        }
    }

    /// The element's in-plane Gauss rule per direction: (point, weight).
    pub fn gauss(self) -> &'static [(f64, f64)] {
        match self {
            Self::Linear => <Mitc4 as shell::Scheme<4>>::GAUSS,
            Self::Quadratic => <Mitc9 as shell::Scheme<9>>::GAUSS,
        }
    }

    /// Shape functions h_k(r, s) and their r and s derivatives, one entry per node.
    pub fn shape(self, r: f64, s: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        match self {
            Self::Linear => {
                let (h, hr, hs) = bilinear_shape(r, s);
                (h.to_vec(), hr.to_vec(), hs.to_vec())
            }
            Self::Quadratic => {
                let (h, hr, hs) = biquadratic_shape(r, s);
                (h.to_vec(), hr.to_vec(), hs.to_vec())
            }
        }
    }
}

/// One element of a mesh, of either family.
// Built on the stack for one element at a time in assembly; boxing the 9-node variant would add
// an allocation per element for no saving.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub enum ShellElement {
    /// A MITC4 element.
    Quad4(Quad4Mitc),
    /// A MITC9 element.
    Quad9(Quad9Mitc),
}

impl ShellElement {
    /// Element stiffness over the global dofs (see [`shell::MitcShell::stiffness`]).
    ///
    /// # Errors
    /// [`ElementDefect::Inverted`] for a Jacobian that is not positive at an integration point.
    pub fn stiffness(&self, mat: &ShellMaterial) -> Result<ElementMatrix, ElementDefect> {
        match self {
            Self::Quad4(e) => e.stiffness(mat),
            Self::Quad9(e) => e.stiffness(mat),
        }
    }

    /// Consistent mass over the global dofs.
    pub fn mass(&self, mat: &ShellMaterial) -> ElementMatrix {
        match self {
            Self::Quad4(e) => e.mass(mat),
            Self::Quad9(e) => e.mass(mat),
        }
    }

    /// Checks the Jacobian at the nodes and Gauss points of the mid-surface.
    ///
    /// # Errors
    /// [`ElementDefect`] with the parametric position of the first bad point.
    pub fn check_geometry(&self) -> Result<(), ElementDefect> {
        match self {
            Self::Quad4(e) => e.check_geometry(),
            Self::Quad9(e) => e.check_geometry(),
        }
    }
}

/// Homogeneous isotropic shell material and thickness.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShellMaterial {
    /// Young's modulus E, Pa.
    pub young_pa: f64,
    /// Poisson ratio ν.
    pub poisson: f64,
    /// Density ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Thickness t, m.
    pub thickness_m: f64,
}

impl ShellMaterial {
    /// Shear modulus G = E / (2(1+ν)), Pa.
    pub fn shear_pa(&self) -> f64 {
        self.young_pa / (2.0 * (1.0 + self.poisson))
    }
}

/// Why an element's geometry is unusable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElementDefect {
    /// Zero (or nearly zero) area at a point of the element: repeated or collinear nodes.
    Degenerate {
        /// Parametric position (r, s) where it was found.
        at: [f64; 2],
    },
    /// Negative Jacobian: node order folds the element, or the nodal directors point against
    /// the element's normal.
    Inverted {
        /// Parametric position (r, s) where it was found.
        at: [f64; 2],
    },
}

/// The element types, for tests and reports.
pub const REGISTRY: &[&str] = &["Quad4Mitc", "Quad9Mitc"];
