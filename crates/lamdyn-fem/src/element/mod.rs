//! Shell elements. One element per file; [`REGISTRY`] pairs each element type with a name so
//! that invariant tests (zero-energy modes, patch tests, symmetry, mass) run over all of them.

mod quad4_mitc;

pub use quad4_mitc::{DRILLING_FACTOR, NODE_RS, Quad4Mitc, SHEAR_CORRECTION, bilinear_shape};

use serde::{Deserialize, Serialize};

/// Degrees of freedom per node in the global system: u_x, u_y, u_z (m), θ_x, θ_y, θ_z (rad).
pub const DOFS_PER_NODE: usize = 6;

/// A dense element matrix over the 24 global dofs of a 4-node element, row-major.
pub type ElementMatrix = [[f64; 24]; 24];

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
pub const REGISTRY: &[&str] = &["Quad4Mitc"];
