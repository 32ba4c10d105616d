//! Structured meshes over a rectangle: flat plates and doubly curved shallow shells.
//!
//! The rectangle [−L_x/2, L_x/2] × [−L_y/2, L_y/2] is split into n_x × n_y elements. The shallow
//! shell lifts it onto the elliptic paraboloid (a dome)
//!
//! z(x, y) = −x²/(2R_x) − y²/(2R_y),
//!
//! with exact unit normals n ∝ (x/R_x, y/R_y, 1) as directors; an infinite radius is flat in that
//! direction. Nodes are numbered row by row (x fastest), elements likewise, counter-clockwise
//! seen from +z. Optional grading clusters nodes towards the free edges, where a Mindlin plate
//! has a boundary layer of width about t/√(12k) (method-notes §5).

use super::Mesh;
use crate::error::{FemError, check_positive};
use crate::vec3::unit;
use serde::{Deserialize, Serialize};

/// A rectangle and its subdivision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectangleSpec {
    /// Length along x, m.
    pub length_x_m: f64,
    /// Length along y, m.
    pub length_y_m: f64,
    /// Elements along x.
    pub elements_x: usize,
    /// Elements along y.
    pub elements_y: usize,
    /// Radius of curvature in the x-z plane, m (infinite or absent: flat).
    #[serde(default = "infinite")]
    pub radius_x_m: f64,
    /// Radius of curvature in the y-z plane, m (infinite or absent: flat).
    #[serde(default = "infinite")]
    pub radius_y_m: f64,
    /// Edge grading in [0, 1): 0 is uniform, larger values cluster nodes towards the edges
    /// (see [`graded`]).
    #[serde(default)]
    pub grading: f64,
}

fn infinite() -> f64 {
    f64::INFINITY
}

/// Maps ξ ∈ [−1, 1] to [−1, 1], clustering points towards ±1 as g grows:
/// ξ ↦ ξ + g·sin(πξ)/π (monotone for 0 ≤ g < 1, endpoints and centre fixed).
pub fn graded(xi: f64, g: f64) -> f64 {
    xi + g * (std::f64::consts::PI * xi).sin() / std::f64::consts::PI
}

impl RectangleSpec {
    /// A flat rectangle.
    pub fn flat(length_x_m: f64, length_y_m: f64, elements_x: usize, elements_y: usize) -> Self {
        Self {
            length_x_m,
            length_y_m,
            elements_x,
            elements_y,
            radius_x_m: f64::INFINITY,
            radius_y_m: f64::INFINITY,
            grading: 0.0,
        }
    }

    /// The same rectangle lifted onto a shallow dome of radii (R_x, R_y).
    pub fn curved(mut self, radius_x_m: f64, radius_y_m: f64) -> Self {
        self.radius_x_m = radius_x_m;
        self.radius_y_m = radius_y_m;
        self
    }

    /// The same rectangle with edge grading `g` (see [`graded`]).
    pub fn with_grading(mut self, g: f64) -> Self {
        self.grading = g;
        self
    }

    fn validate(&self) -> Result<(), FemError> {
        let ctx = "rectangle";
        check_positive(ctx, "length_x_m", self.length_x_m)?;
        check_positive(ctx, "length_y_m", self.length_y_m)?;
        for (field, n) in [
            ("elements_x", self.elements_x),
            ("elements_y", self.elements_y),
        ] {
            if !(1..=2000).contains(&n) {
                return Err(FemError::InvalidParameter {
                    context: ctx.into(),
                    field: field.into(),
                    value: n.to_string(),
                    requirement: "must lie in 1..=2000".into(),
                });
            }
        }
        for (field, r, l) in [
            ("radius_x_m", self.radius_x_m, self.length_x_m),
            ("radius_y_m", self.radius_y_m, self.length_y_m),
        ] {
            if r.is_nan() || r <= 0.0 || r < l {
                return Err(FemError::InvalidParameter {
                    context: ctx.into(),
                    field: field.into(),
                    value: format!("{r}"),
                    requirement: format!(
                        "must be positive and at least the span ({l} m) for a shallow shell; use inf for flat"
                    ),
                });
            }
        }
        if !(0.0..1.0).contains(&self.grading) {
            return Err(FemError::InvalidParameter {
                context: ctx.into(),
                field: "grading".into(),
                value: format!("{}", self.grading),
                requirement: "must lie in [0, 1)".into(),
            });
        }
        Ok(())
    }

    /// Builds the mesh, with node groups `corners` and `boundary`.
    ///
    /// # Errors
    /// [`FemError::InvalidParameter`] for non-positive lengths, counts outside 1..=2000, radii
    /// shorter than the span, or grading outside [0, 1).
    pub fn build(&self) -> Result<Mesh, FemError> {
        self.validate()?;
        let (nx, ny) = (self.elements_x, self.elements_y);
        let coord = |i: usize, n: usize, l: f64| {
            0.5 * l * graded(2.0 * i as f64 / n as f64 - 1.0, self.grading)
        };
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
        let mut directors = Vec::with_capacity(nodes.capacity());
        for j in 0..=ny {
            for i in 0..=nx {
                let x = coord(i, nx, self.length_x_m);
                let y = coord(j, ny, self.length_y_m);
                let (kx, ky) = (1.0 / self.radius_x_m, 1.0 / self.radius_y_m);
                nodes.push([x, y, -0.5 * (kx * x * x + ky * y * y)]);
                directors.push(unit([kx * x, ky * y, 1.0]));
            }
        }
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut elements = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut mesh = Mesh::with_directors(nodes, directors, elements)?;
        mesh.add_node_group("corners", vec![id(0, 0), id(nx, 0), id(nx, ny), id(0, ny)])?;
        let mut boundary: Vec<usize> = (0..=nx).flat_map(|i| [id(i, 0), id(i, ny)]).collect();
        boundary.extend((1..ny).flat_map(|j| [id(0, j), id(nx, j)]));
        boundary.sort_unstable();
        mesh.add_node_group("boundary", boundary)?;
        Ok(mesh)
    }
}
