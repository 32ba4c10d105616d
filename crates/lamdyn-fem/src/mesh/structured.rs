//! Structured meshes over a rectangle: flat plates and doubly curved shallow shells.
//!
//! The rectangle [−L_x/2, L_x/2] × [−L_y/2, L_y/2] is split into n_x × n_y elements. The shallow
//! shell lifts it onto the elliptic paraboloid (a dome)
//!
//! z(x, y) = −x²/(2R_x) − y²/(2R_y),
//!
//! with exact unit normals n ∝ (x/R_x, y/R_y, 1) as directors; an infinite radius is flat in that
//! direction, a negative one curves the other way (R_x, R_y < 0: a bowl; signs apart: a saddle).
//! Nodes are numbered row by row (x fastest), elements likewise, counter-clockwise seen from +z.
//! Optional grading clusters nodes towards the free edges, where a Mindlin plate has a boundary
//! layer of width about t/√(12k) (method-notes §5); edge layers resolve it better: `edge_layers`
//! elements at each edge whose widths grow geometrically from `edge_layer_m` to the interior's
//! uniform size ([`axis_coordinates`]).
//!
//! With `element = "mitc9"` each element gets mid-side nodes at the midpoints of its edges in
//! plan and a centre node (lifted onto the dome with their exact normals): the elements stay
//! rectangles in plan, so the MITC9 tying is exact there.

use super::Mesh;
use crate::element::ElementOrder;
use crate::error::{FemError, check_positive};
use crate::vec3::{V3, unit};
use serde::{Deserialize, Serialize};

/// A rectangle and its subdivision.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// Radius of curvature in the x-z plane, m (infinite or absent: flat; negative: curved
    /// towards +z, a bowl).
    #[serde(default = "infinite")]
    pub radius_x_m: f64,
    /// Radius of curvature in the y-z plane, m (infinite or absent: flat; negative: curved
    /// towards +z).
    #[serde(default = "infinite")]
    pub radius_y_m: f64,
    /// Edge grading in [0, 1): 0 is uniform, larger values cluster nodes towards the edges
    /// (see [`graded`]).
    #[serde(default)]
    pub grading: f64,
    /// Element family: `"mitc4"` (default) or `"mitc9"`.
    #[serde(default, rename = "element")]
    pub order: ElementOrder,
    /// Elements in the geometric layer at each edge (0: none).
    #[serde(default)]
    pub edge_layers: usize,
    /// Width of the outermost layer element, m (used when `edge_layers` > 0).
    #[serde(default)]
    pub edge_layer_m: f64,
    /// x coordinates (m, centred on the rectangle) that node lines must pass through, e.g. the
    /// measurement grid's: each moves the nearest interior element edge onto it (see
    /// [`snap_lines`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lines_x_m: Vec<f64>,
    /// y coordinates that node lines must pass through.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lines_y_m: Vec<f64>,
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
            order: ElementOrder::Linear,
            edge_layers: 0,
            edge_layer_m: 0.0,
            lines_x_m: Vec::new(),
            lines_y_m: Vec::new(),
        }
    }

    /// The same rectangle with node lines through the given x and y coordinates (m, centred on
    /// the rectangle), e.g. a measurement grid's ([`snap_lines`]).
    pub fn with_node_lines(mut self, xs_m: Vec<f64>, ys_m: Vec<f64>) -> Self {
        self.lines_x_m = xs_m;
        self.lines_y_m = ys_m;
        self
    }

    /// The same rectangle with elements of `order`.
    pub fn with_order(mut self, order: ElementOrder) -> Self {
        self.order = order;
        self
    }

    /// The same rectangle with `layers` elements at each edge growing geometrically from
    /// `first_m` (see [`axis_coordinates`]).
    pub fn with_edge_layers(mut self, layers: usize, first_m: f64) -> Self {
        self.edge_layers = layers;
        self.edge_layer_m = first_m;
        self
    }

    /// The same rectangle lifted onto a shallow dome of radii (R_x, R_y).
    pub fn curved(mut self, radius_x_m: f64, radius_y_m: f64) -> Self {
        self.radius_x_m = radius_x_m;
        self.radius_y_m = radius_y_m;
        self
    }

    /// The exact mid-surface z = −x²/(2R_x) − y²/(2R_y) as a [`super::refine::Surface`]: a
    /// point's (x, y) → the dome's point above it and its unit normal ∝ (x/R_x, y/R_y, 1).
    pub fn surface(&self) -> impl Fn(V3) -> (V3, V3) + Sync + use<> {
        let (kx, ky) = (1.0 / self.radius_x_m, 1.0 / self.radius_y_m);
        move |p: V3| {
            let [x, y, _] = p;
            (
                [x, y, -0.5 * (kx * x * x + ky * y * y)],
                unit([kx * x, ky * y, 1.0]),
            )
        }
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
            if r.is_nan() || r.abs() < l {
                return Err(FemError::InvalidParameter {
                    context: ctx.into(),
                    field: field.into(),
                    value: format!("{r}"),
                    requirement: format!(
                        "must be at least the span ({l} m) in size for a shallow shell (negative: \
                         curved the other way, a bowl); use inf for flat"
                    ),
                });
            }
        }
        if self.edge_layers > 0 {
            check_positive(ctx, "edge_layer_m", self.edge_layer_m)?;
            if self.grading != 0.0 {
                return Err(FemError::InvalidParameter {
                    context: ctx.into(),
                    field: "grading".into(),
                    value: format!("{}", self.grading),
                    requirement: "must be 0 with edge_layers (choose one way to refine the edges)"
                        .into(),
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
    /// shorter in size than the span, grading outside [0, 1), or edge layers that do not fit.
    pub fn build(&self) -> Result<Mesh, FemError> {
        self.validate()?;
        let (nx, ny) = (self.elements_x, self.elements_y);
        let xs = self.axis("x", nx, self.length_x_m, &self.lines_x_m)?;
        let ys = self.axis("y", ny, self.length_y_m, &self.lines_y_m)?;
        // Node lines: every element edge, and for MITC9 the midpoints between them.
        // Node-line steps per element.
        let p = match self.order {
            ElementOrder::Linear => 1,
            ElementOrder::Quadratic => 2,
        };
        let lines = |c: &[f64]| -> Vec<f64> {
            if p == 1 {
                c.to_vec()
            } else {
                let mut out: Vec<f64> = c
                    .windows(2)
                    .flat_map(|w| [w[0], 0.5 * (w[0] + w[1])])
                    .collect();
                out.extend(c.last());
                out
            }
        };
        let (lx, ly) = (lines(&xs), lines(&ys));
        let lift = self.surface();
        let mut nodes = Vec::with_capacity(lx.len() * ly.len());
        let mut directors = Vec::with_capacity(nodes.capacity());
        for &y in &ly {
            for &x in &lx {
                let (point, normal) = lift([x, y, 0.0]);
                nodes.push(point);
                directors.push(normal);
            }
        }
        let row = lx.len();
        let id = |i: usize, j: usize| j * row + i;
        let mut connectivity = Vec::with_capacity(self.order.nodes() * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                super::push_grid_element(&mut connectivity, id, (p * i, p * j), p);
            }
        }
        let mut mesh = Mesh::of_order(self.order, nodes, Some(directors), connectivity)?;
        let (ex, ey) = (lx.len() - 1, ly.len() - 1);
        mesh.add_node_group("corners", vec![id(0, 0), id(ex, 0), id(ex, ey), id(0, ey)])?;
        let mut boundary: Vec<usize> = (0..=ex).flat_map(|i| [id(i, 0), id(i, ey)]).collect();
        boundary.extend((1..ey).flat_map(|j| [id(0, j), id(ex, j)]));
        boundary.sort_unstable();
        mesh.add_node_group("boundary", boundary)?;
        Ok(mesh)
    }

    /// The n + 1 element-edge coordinates along one side of length l, centred on 0, with node
    /// lines moved onto `through` ([`snap_lines`]).
    fn axis(&self, name: &str, n: usize, l: f64, through: &[f64]) -> Result<Vec<f64>, FemError> {
        let coords = if self.edge_layers == 0 {
            (0..=n)
                .map(|i| 0.5 * l * graded(2.0 * i as f64 / n as f64 - 1.0, self.grading))
                .collect()
        } else {
            axis_coordinates(n, l, self.edge_layers, self.edge_layer_m).map_err(|why| {
                FemError::InvalidParameter {
                    context: "rectangle".into(),
                    field: "edge_layers".into(),
                    value: format!(
                        "{} layers from {} m along {name} ({n} elements over {l} m)",
                        self.edge_layers, self.edge_layer_m
                    ),
                    requirement: why.to_string(),
                }
            })?
        };
        let protected = self.edge_layers;
        snap_lines(coords, through, protected).map_err(|why| FemError::InvalidParameter {
            context: "rectangle".into(),
            field: format!("lines_{name}_m"),
            value: format!("{through:?}"),
            requirement: why.to_string(),
        })
    }
}

/// Why element edges cannot be graded or moved as asked ([`axis_coordinates`],
/// [`snap_lines`]); its text is the requirement, for the caller's error naming the field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GridError {
    /// Fewer elements along a side than the edge layers at both ends and an interior need.
    TooFewElements {
        /// Layers at each edge.
        layers: usize,
    },
    /// The first layer is already as wide as a uniform element.
    FirstLayerTooWide {
        /// The first layer's width, m.
        first_m: f64,
        /// A uniform element's width, m.
        uniform_m: f64,
    },
    /// No geometric growth of the layers fits the side.
    NoGrowth,
    /// A coordinate outside the side or on its edge.
    Outside {
        /// The coordinate, m.
        at_m: f64,
        /// The side's ends, m.
        side_m: [f64; 2],
    },
    /// No interior edge is left to move.
    NoMovableEdge,
    /// Two coordinates need the same element edge.
    EdgeTaken {
        /// The coordinate, m.
        at_m: f64,
        /// The edge, m.
        edge_m: f64,
    },
    /// A coordinate more than half an element from the nearest movable edge.
    TooFar {
        /// The coordinate, m.
        at_m: f64,
        /// The edge, m.
        edge_m: f64,
    },
    /// The moved edges would cross.
    Crossing,
}

impl std::fmt::Display for GridError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::TooFewElements { layers } => write!(
                f,
                "needs more than {} elements along the side for {layers} layers at each edge and \
                 an interior",
                2 * layers
            ),
            Self::FirstLayerTooWide { first_m, uniform_m } => write!(
                f,
                "the first layer ({first_m} m) must be thinner than a uniform element ({uniform_m} \
                 m)"
            ),
            Self::NoGrowth => f.write_str("no geometric growth fits the side"),
            Self::Outside { at_m, side_m } => write!(
                f,
                "{at_m} m lies outside the side ({} m to {} m) or on its edge",
                side_m[0], side_m[1]
            ),
            Self::NoMovableEdge => f.write_str("no interior element edge is left to move"),
            Self::EdgeTaken { at_m, edge_m } => write!(
                f,
                "{at_m} m needs the same element edge ({edge_m} m) as another coordinate: use more \
                 elements"
            ),
            Self::TooFar { at_m, edge_m } => write!(
                f,
                "{at_m} m is more than half an element from the nearest movable edge ({edge_m} m): \
                 use more elements"
            ),
            Self::Crossing => f.write_str("moved edges would cross: use more elements"),
        }
    }
}

impl std::error::Error for GridError {}

/// Moves element edges onto the coordinates `through`: each goes to the nearest edge that is
/// not a boundary, not among the `protected` edge layers at either end, and not taken by
/// another coordinate; an edge may move by at most half the width of the element on the side it
/// moves into, so that no element shrinks below half its width and the order is kept.
///
/// # Errors
/// [`GridError`]: a coordinate outside the side, two coordinates that need the same edge (the
/// mesh is too coarse for the grid), or a move that would squeeze an element to under half.
pub fn snap_lines(
    mut x: Vec<f64>,
    through: &[f64],
    protected: usize,
) -> Result<Vec<f64>, GridError> {
    let n = x.len() - 1;
    let (lo, hi) = (x[0], x[n]);
    let first = 1 + protected;
    let last = n.saturating_sub(1 + protected);
    let mut taken = vec![false; n + 1];
    let original = x.clone();
    for &c in through {
        if !(c.is_finite() && c > lo && c < hi) {
            return Err(GridError::Outside {
                at_m: c,
                side_m: [lo, hi],
            });
        }
        if first > last {
            return Err(GridError::NoMovableEdge);
        }
        let k = (first..=last)
            .min_by(|&a, &b| (original[a] - c).abs().total_cmp(&(original[b] - c).abs()))
            .unwrap_or(first);
        if taken[k] {
            return Err(GridError::EdgeTaken {
                at_m: c,
                edge_m: original[k],
            });
        }
        let room = if c >= original[k] {
            0.5 * (original[k + 1] - original[k])
        } else {
            0.5 * (original[k] - original[k - 1])
        };
        if (c - original[k]).abs() > room + 1e-12 * (hi - lo) {
            return Err(GridError::TooFar {
                at_m: c,
                edge_m: original[k],
            });
        }
        taken[k] = true;
        x[k] = c;
    }
    if x.windows(2).any(|w| w[1] <= w[0]) {
        return Err(GridError::Crossing);
    }
    Ok(x)
}

/// Element-edge coordinates over [−l/2, l/2] with `layers` elements at each end whose widths
/// grow geometrically, w_k = w_0 qᵏ (k = 0 at the edge), and n − 2·layers uniform interior
/// elements of width h. The ratio q ≥ 1 is the one that makes the layers meet the interior
/// smoothly, w_0 q^layers = h, with 2 Σ w_k + (n − 2 layers) h = l (found by bisection).
///
/// # Errors
/// [`GridError`] when the layers do not fit: fewer than one interior element, or a first layer
/// already as wide as a uniform element (no refinement to make).
pub fn axis_coordinates(
    n: usize,
    l: f64,
    layers: usize,
    first_m: f64,
) -> Result<Vec<f64>, GridError> {
    if 2 * layers >= n {
        return Err(GridError::TooFewElements { layers });
    }
    let interior = (n - 2 * layers) as f64;
    let layer_sum = |q: f64| (0..layers).map(|k| first_m * q.powi(k as i32)).sum::<f64>();
    // Mismatch between the next layer's width and the interior width.
    let mismatch = |q: f64| first_m * q.powi(layers as i32) - (l - 2.0 * layer_sum(q)) / interior;
    if mismatch(1.0) >= 0.0 {
        return Err(GridError::FirstLayerTooWide {
            first_m,
            uniform_m: l / n as f64,
        });
    }
    let (mut lo, mut hi) = (1.0, 2.0);
    while mismatch(hi) < 0.0 {
        hi *= 2.0;
        if hi > 1e6 {
            return Err(GridError::NoGrowth);
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mismatch(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let q = 0.5 * (lo + hi);
    let h = (l - 2.0 * layer_sum(q)) / interior;
    let mut widths: Vec<f64> = (0..layers).map(|k| first_m * q.powi(k as i32)).collect();
    widths.extend(std::iter::repeat_n(h, n - 2 * layers));
    widths.extend((0..layers).rev().map(|k| first_m * q.powi(k as i32)));
    let mut x = Vec::with_capacity(n + 1);
    let mut at = -0.5 * l;
    x.push(at);
    for w in &widths[..n - 1] {
        at += w;
        x.push(at);
    }
    x.push(0.5 * l);
    Ok(x)
}
