//! The description of an FE model as written in TOML (`lamdyn modes`, job files): mesh,
//! material, supports, solver settings, SI units.
//!
//! ```toml
//! [mesh]
//! kind = "rectangle"          # or: kind = "gmsh", file = "roof.msh", unit = "mm"
//! length_x_m = 0.923
//! length_y_m = 0.8632
//! elements_x = 40
//! elements_y = 40
//! radius_x_m = 4.0            # optional: a shallow dome; inf or absent is flat
//! radius_y_m = 6.0
//! element = "mitc9"           # optional: 9-node MITC9 elements (default "mitc4")
//! edge_layers = 3             # optional: geometric layers at the free edges, the outermost
//! edge_layer_m = 0.002        #   this wide (default: half the shell's thickness)
//! lines_x_m = [-0.4115, 0.0, 0.4115]  # optional: node lines through these x (and y) coordinates,
//! lines_y_m = [-0.3816, 0.0, 0.3816]  #   e.g. the measurement grid's (nearest edges moved)
//!
//! [material]
//! young_pa = 67.45e9
//! poisson = 0.22
//! density_kg_m3 = 2702.0
//! thickness_m = 0.00385
//!
//! [[supports]]                # optional elastic supports, at the node nearest the point
//! point_m = [0.3, 0.3, 0.0]
//! translational_n_per_m = [0.0, 0.0, 5.0e3]
//!
//! [solver]
//! modes = 20                  # lowest modes, rigid-body modes included
//! ```

use crate::assembly::NodeSpring;
use crate::element::{ElementOrder, ShellMaterial};
use crate::error::FemError;
use crate::mesh::refine::SurfaceFn;
use crate::mesh::structured::RectangleSpec;
use crate::mesh::{Locator, Mesh, gmsh};
use lamdyn_material::units::{self, Quantity};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// The mesh.
    pub mesh: MeshSpec,
    /// The shell material.
    pub material: ShellMaterial,
    /// Elastic supports.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub supports: Vec<SupportSpec>,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
}

/// Where the mesh comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MeshSpec {
    /// A structured rectangle, flat or a shallow dome ([`RectangleSpec`]; `edge_layer_m`
    /// absent or 0 with `edge_layers` > 0: half the shell's thickness).
    Rectangle(RectangleSpec),
    /// A Gmsh MSH file (2.2 or 4.1 ASCII), relative to the model file.
    Gmsh {
        /// Path of the file.
        file: String,
        /// Unit of the file's coordinates: "m" (default) or "mm".
        #[serde(default = "metres")]
        unit: String,
        /// The element the file must hold, `"mitc4"` (4-node quadrilaterals) or `"mitc9"`
        /// (9-node); absent: whichever it holds.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        element: Option<ElementOrder>,
    },
}

fn metres() -> String {
    "m".into()
}

/// An elastic support at the node nearest to a point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    /// The point, m.
    pub point_m: [f64; 3],
    /// Largest distance from the point to its node, m (default 1 mm).
    #[serde(default = "default_tolerance")]
    pub tolerance_m: f64,
    /// Translational stiffnesses, N/m.
    pub translational_n_per_m: [f64; 3],
    /// Rotational stiffnesses, N·m/rad.
    #[serde(default)]
    pub rotational_nm_per_rad: [f64; 3],
}

fn default_tolerance() -> f64 {
    1e-3
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Lowest modes wanted, rigid-body modes included.
    #[serde(default = "default_modes")]
    pub modes: usize,
    /// Fixed shift as a frequency, Hz (σ = −(2πf)²); absent: automatic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shift_hz: Option<f64>,
}

fn default_modes() -> usize {
    20
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            modes: default_modes(),
            shift_hz: None,
        }
    }
}

impl ModelSpec {
    /// Builds the mesh and the supports; a Gmsh path is taken relative to `base_dir`.
    ///
    /// # Errors
    /// [`FemError`] naming the field, file, node or support.
    pub fn build(&self, base_dir: &Path) -> Result<(Mesh, Vec<NodeSpring>), FemError> {
        self.check_units()?;
        let mesh = match &self.mesh {
            MeshSpec::Rectangle(rect) => {
                // Refused before the mesh is built: a 2000 x 2000 mesh takes seconds to make.
                let per_side = match rect.order {
                    ElementOrder::Linear => 1,
                    ElementOrder::Quadratic => 2,
                };
                crate::memory::check_modal_memory(
                    6 * (per_side * rect.elements_x + 1) * (per_side * rect.elements_y + 1),
                )?;
                let mut rect = rect.clone();
                if rect.edge_layers > 0 && rect.edge_layer_m == 0.0 {
                    rect.edge_layer_m = 0.5 * self.material.thickness_m;
                }
                rect.build()?
            }
            MeshSpec::Gmsh {
                file,
                unit,
                element,
            } => {
                let scale = match unit.as_str() {
                    "m" => 1.0,
                    "mm" => 1e-3,
                    other => {
                        return Err(FemError::InvalidParameter {
                            context: "mesh".into(),
                            field: "unit".into(),
                            value: other.into(),
                            requirement: "must be \"m\" or \"mm\"".into(),
                        });
                    }
                };
                let mesh = gmsh::read_msh(&base_dir.join(file), scale)?;
                if let Some(want) = element
                    && *want != mesh.order()
                {
                    return Err(FemError::InvalidParameter {
                        context: "mesh".into(),
                        field: "element".into(),
                        value: format!("{want:?}").to_lowercase(),
                        requirement: format!(
                            "'{file}' holds {}-node quadrilaterals ({}); {} needs {}-node ones \
                             (Gmsh: Mesh.ElementOrder = {}, Mesh.SecondOrderIncomplete = 0)",
                            mesh.order().nodes(),
                            mesh.order().name(),
                            want.name(),
                            want.nodes(),
                            if want.nodes() == 9 { 2 } else { 1 }
                        ),
                    });
                }
                mesh
            }
        };
        check_span(&mesh, self.material.thickness_m)?;
        let locator = Locator::new(&mesh, f64::INFINITY);
        let mut springs = Vec::new();
        for (i, s) in self.supports.iter().enumerate() {
            let ctx = format!("supports[{i}]");
            crate::error::check_positive(&ctx, "tolerance_m", s.tolerance_m)?;
            let node = locator
                .clone()
                .with_tolerance(s.tolerance_m)
                .locate_all(&[s.point_m])
                .map_err(|e| match e {
                    FemError::Locate {
                        x, y, z, reason, ..
                    } => FemError::InvalidParameter {
                        context: ctx.clone(),
                        field: "point_m".into(),
                        value: format!("[{x}, {y}, {z}]"),
                        requirement: format!("must lie on the mesh: {reason}"),
                    },
                    other => other,
                })?[0];
            springs.push(NodeSpring {
                node,
                translational_n_per_m: s.translational_n_per_m,
                rotational_nm_per_rad: s.rotational_nm_per_rad,
            });
        }
        Ok((mesh, springs))
    }

    /// The exact mid-surface of a rectangle model (its dome or plane), for refining it
    /// ([`crate::mesh::Mesh::subdivided`]); `None` for a mesh file, whose elements are the
    /// geometry.
    pub fn surface(&self) -> Option<Box<SurfaceFn>> {
        match &self.mesh {
            MeshSpec::Rectangle(rect) => Some(Box::new(rect.surface())),
            MeshSpec::Gmsh { .. } => None,
        }
    }

    /// The material and the rectangle's lengths in plausible SI ranges
    /// ([`lamdyn_material::units`]): catches mm, GPa and g/cm³ before any work.
    ///
    /// # Errors
    /// [`FemError::InvalidParameter`] naming the field and the unit probably meant.
    pub fn check_units(&self) -> Result<(), FemError> {
        let m = &self.material;
        let mut fields = vec![
            ("material", "young_pa", m.young_pa, Quantity::StiffModulus),
            (
                "material",
                "density_kg_m3",
                m.density_kg_m3,
                Quantity::Density,
            ),
            (
                "material",
                "thickness_m",
                m.thickness_m,
                Quantity::Thickness,
            ),
        ];
        if let MeshSpec::Rectangle(rect) = &self.mesh {
            fields.push(("mesh", "length_x_m", rect.length_x_m, Quantity::Length));
            fields.push(("mesh", "length_y_m", rect.length_y_m, Quantity::Length));
        }
        for (context, field, value, quantity) in fields {
            units::check(quantity, value).map_err(|why| FemError::InvalidParameter {
                context: context.into(),
                field: field.into(),
                value: format!("{value}"),
                requirement: why.to_string(),
            })?;
        }
        Ok(())
    }
}

/// The mesh's span (largest side of its bounding box) is a plausible length in m and larger
/// than the shell's thickness: a Gmsh file in mm read as m is a part hundreds of metres wide.
fn check_span(mesh: &Mesh, thickness_m: f64) -> Result<(), FemError> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in mesh.nodes() {
        for c in 0..3 {
            lo[c] = lo[c].min(x[c]);
            hi[c] = hi[c].max(x[c]);
        }
    }
    let span = (0..3).map(|c| hi[c] - lo[c]).fold(0.0, f64::max);
    let invalid = |requirement: String| FemError::InvalidParameter {
        context: "mesh".into(),
        field: "span".into(),
        value: format!("{span} m"),
        requirement,
    };
    units::check(Quantity::Length, span).map_err(|why| invalid(why.to_string()))?;
    if span < 5.0 * thickness_m {
        return Err(invalid(format!(
            "must be at least 5 shell thicknesses ({thickness_m} m) for a shell model"
        )));
    }
    Ok(())
}
