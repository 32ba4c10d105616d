//! The part's plan: what the layered model extrudes through its layers.
//!
//! - [`Plan::Rectangle`]: a rectangle, flat or a shallow dome, meshed with a structured grid
//!   of n_x × n_y elements graded towards the free edges ([`crate::mesh::LayeredPlateSpec`]).
//! - [`Plan::Surface`]: any mesh of 4-node or 9-node quadrilaterals of the laminate's
//!   mid-thickness surface (a Gmsh file read by [`lamdyn_fem::mesh::gmsh`], the same mesh a
//!   shell model of the part uses), each element split m × m
//!   ([`lamdyn_fem::mesh::Mesh::subdivided`]: new nodes on the elements' own geometric map,
//!   bilinear or biquadratic, directors interpolated and normalised).
//!
//! Extrusion of a surface ([`extrude_surface`]): every (sub)element becomes one 20-node
//! hexahedron per layer element through the thickness. A plan point x with unit director d
//! (the shell normal: averaged over the elements at a node of the Gmsh mesh) gives the nodes
//! x + s d at the heights s of the stack, mid-thickness at s = 0, so every layer keeps its
//! thickness along d as on the structured dome. The hexahedron's mid-edge nodes in plane are
//! the 9-node element's mid-side nodes, or the midpoints of a 4-node element's straight edges
//! (director: the normalised mean of its corners'). Corners counter-clockwise seen from the
//! directors' side (what [`lamdyn_fem::mesh::Mesh`] checks) and ζ along d make a
//! right-handed, positive-Jacobian hexahedron.
//!
//! On either plan a level of the convergence ladder is given by `elements: [usize; 2]`: the
//! rectangle's n_x × n_y, or a surface's subdivision [m, m] (h ∝ 1/m, so that
//! [`crate::convergence`]'s Richardson extrapolation reads both the same way).

use crate::error::LayeredError;
use crate::hex20::NODES;
use crate::mesh::{HexMesh, LayerMesh, LayeredPlateSpec, check_layers, heights};
use lamdyn_fem::element::ElementOrder;
use lamdyn_fem::mesh::Mesh;
use std::collections::HashMap;

/// The plan of the layered model (module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum Plan {
    /// A rectangle over [−a/2, a/2] × [−b/2, b/2], flat or a shallow dome.
    Rectangle {
        /// Plan lengths a, b along x and y, m.
        plan_m: [f64; 2],
        /// Radii of curvature along x and y, m (infinite: straight).
        radii_m: [f64; 2],
        /// Edge grading of the in-plane mesh ([`crate::mesh`]; 0: uniform).
        edge_grading: f64,
    },
    /// A quadrilateral mesh of the mid-thickness surface (a Gmsh file), m.
    Surface(Box<Mesh>),
}

impl Plan {
    /// The layered hexahedral mesh of this plan with `layers`, bottom to top: `elements` are
    /// the rectangle's n_x × n_y, or a surface's subdivision [m, m] (module docs).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] naming the field: a non-positive size, thickness or count, a
    /// surface subdivision that is not [m, m] with m in 1..=16.
    pub fn mesh(
        &self,
        elements: [usize; 2],
        layers: &[LayerMesh],
    ) -> Result<HexMesh, LayeredError> {
        match self {
            Plan::Rectangle {
                plan_m,
                radii_m,
                edge_grading,
            } => LayeredPlateSpec {
                length_m: plan_m[0],
                width_m: plan_m[1],
                nx: elements[0],
                ny: elements[1],
                radius_x_m: radii_m[0],
                radius_y_m: radii_m[1],
                edge_grading: *edge_grading,
                layers: layers.to_vec(),
            }
            .build(),
            Plan::Surface(surface) => {
                let [m, n] = elements;
                if m != n || !(1..=16).contains(&m) {
                    return Err(LayeredError::Invalid(format!(
                        "subdivision {elements:?} of the plan's elements: give [m, m] with m in \
                         1..=16"
                    )));
                }
                let fine = surface
                    .subdivided(m, None)
                    .map_err(|e| LayeredError::Invalid(format!("plan mesh: {e}")))?;
                extrude_surface(&fine, layers)
            }
        }
    }

    /// One line for a report: the plan and how its levels are counted.
    pub fn describe(&self) -> String {
        match self {
            Plan::Rectangle {
                plan_m,
                radii_m,
                edge_grading,
            } => format!(
                "rectangle {} x {} m, radii {} / {} m, edge grading {edge_grading}",
                plan_m[0], plan_m[1], radii_m[0], radii_m[1]
            ),
            Plan::Surface(s) => format!(
                "mid-surface mesh of {} {}-node quadrilaterals ({} nodes), each split m x m",
                s.n_elements(),
                s.order().nodes(),
                s.nodes().len()
            ),
        }
    }

    /// The label of one level's `elements` ("12 x 12" or "split 2 x 2").
    pub fn level_label(&self, elements: [usize; 2]) -> String {
        match self {
            Plan::Rectangle { .. } => format!("{} x {}", elements[0], elements[1]),
            Plan::Surface(_) => format!("split {} x {}", elements[0], elements[1]),
        }
    }
}

/// The in-plane points of a surface mesh the hexahedra use: position, unit director, and
/// whether the point is an element corner (it then has nodes at every height) or a mid-edge
/// point (nodes at the layer elements' faces only).
struct PlanPoints {
    position: Vec<[f64; 3]>,
    director: Vec<[f64; 3]>,
    corner: Vec<bool>,
    /// Per element: corners 0–3 counter-clockwise, then the mid-edge points of edges 0-1, 1-2,
    /// 2-3, 3-0.
    elements: Vec<[usize; 8]>,
}

/// The corner and mid-edge points of `surface` (module docs).
fn plan_points(surface: &Mesh) -> PlanPoints {
    let nodes = surface.nodes();
    let dirs = surface.directors();
    // Plan point of each mesh node (usize::MAX: none yet; a 9-node centre never gets one).
    let mut index = vec![usize::MAX; nodes.len()];
    let mut mids: HashMap<(usize, usize), usize> = HashMap::new();
    let mut p = PlanPoints {
        position: Vec::new(),
        director: Vec::new(),
        corner: Vec::new(),
        elements: Vec::with_capacity(surface.n_elements()),
    };
    let point = |p: &mut PlanPoints, x: [f64; 3], d: [f64; 3], corner: bool| {
        p.position.push(x);
        p.director.push(d);
        p.corner.push(corner);
        p.position.len() - 1
    };
    for e in 0..surface.n_elements() {
        let conn = surface.element_nodes(e);
        let mut out = [0usize; 8];
        let mut of_node = |p: &mut PlanPoints, n: usize, corner: bool| {
            if index[n] == usize::MAX {
                index[n] = point(p, nodes[n], dirs[n], corner);
            }
            index[n]
        };
        for c in 0..4 {
            out[c] = of_node(&mut p, conn[c], true);
        }
        for edge in 0..4 {
            let (a, b) = (conn[edge], conn[(edge + 1) % 4]);
            out[4 + edge] = match surface.order() {
                ElementOrder::Quadratic => of_node(&mut p, conn[4 + edge], false),
                ElementOrder::Linear => *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let x = std::array::from_fn(|k| 0.5 * (nodes[a][k] + nodes[b][k]));
                    let d: [f64; 3] = std::array::from_fn(|k| dirs[a][k] + dirs[b][k]);
                    let norm = d.iter().map(|v| v * v).sum::<f64>().sqrt();
                    point(&mut p, x, d.map(|v| v / norm), false)
                }),
            };
        }
        p.elements.push(out);
    }
    p
}

/// The plan point of a hexahedron node with in-plane coordinates (ξ, η) ∈ {−1, 0, 1}²: its
/// position in [`PlanPoints::elements`]' order.
fn plan_slot(xi: f64, eta: f64) -> usize {
    match (xi as i32, eta as i32) {
        (-1, -1) => 0,
        (1, -1) => 1,
        (1, 1) => 2,
        (-1, 1) => 3,
        (0, -1) => 4,
        (1, 0) => 5,
        (0, 1) => 6,
        _ => 7, // (−1, 0)
    }
}

/// The layered mesh of a quadrilateral mid-surface mesh (module docs).
///
/// # Errors
/// [`LayeredError::Invalid`] naming the layer for a non-positive thickness or count.
pub fn extrude_surface(surface: &Mesh, layers: &[LayerMesh]) -> Result<HexMesh, LayeredError> {
    check_layers(layers)?;
    let points = plan_points(surface);
    let (s, fine_layer) = heights(layers);
    let fz = s.len();
    let mut id = vec![usize::MAX; points.position.len() * fz];
    let mut nodes = Vec::new();
    let (mut top, mut bottom) = (Vec::new(), Vec::new());
    for k in 0..fz {
        for (p, (x, d)) in points.position.iter().zip(&points.director).enumerate() {
            if k % 2 == 1 && !points.corner[p] {
                continue;
            }
            id[p * fz + k] = nodes.len();
            if k == fz - 1 {
                top.push((nodes.len(), *d));
            } else if k == 0 {
                bottom.push((nodes.len(), d.map(|v| -v)));
            }
            nodes.push(std::array::from_fn(|c| x[c] + s[k] * d[c]));
        }
    }
    let nz = fz / 2;
    let mut elements = Vec::with_capacity(points.elements.len() * nz);
    let mut layer = Vec::with_capacity(elements.capacity());
    for ek in 0..nz {
        for plan in &points.elements {
            let conn: [usize; 20] = std::array::from_fn(|a| {
                let c = NODES[a];
                let p = plan[plan_slot(c[0], c[1])];
                id[p * fz + 2 * ek + (c[2] + 1.0) as usize]
            });
            elements.push(conn);
            layer.push(fine_layer[ek]);
        }
    }
    Ok(HexMesh {
        nodes,
        elements,
        layer,
        top,
        bottom,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use lamdyn_fem::mesh::structured::RectangleSpec;

    fn layers() -> Vec<LayerMesh> {
        [(0.003, 1), (0.001, 2), (0.003, 1)]
            .map(|(t, n)| LayerMesh {
                thickness_m: t,
                elements: n,
            })
            .to_vec()
    }

    /// Each node of `a` is a node of `b` (and the counts agree), within `tol` m.
    fn same_nodes(a: &HexMesh, b: &HexMesh, tol: f64) {
        assert_eq!(a.nodes.len(), b.nodes.len());
        assert_eq!(a.elements.len(), b.elements.len());
        assert_eq!(a.top.len(), b.top.len());
        assert_eq!(a.bottom.len(), b.bottom.len());
        let mut sorted = b.nodes.clone();
        sorted.sort_by(|p, q| p.partial_cmp(q).unwrap());
        for p in &a.nodes {
            let near = sorted
                .iter()
                .map(|q| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt())
                .fold(f64::INFINITY, f64::min);
            assert!(near < tol, "node {p:?}: nearest {near}");
        }
    }

    /// A flat rectangle meshed as a surface, split m × m, is the structured n m × n m mesh:
    /// the same nodes, elements, top and bottom, for 4-node and 9-node plans.
    #[test]
    fn a_split_flat_surface_is_the_structured_mesh() {
        for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
            let surface = RectangleSpec::flat(0.6, 0.4, 3, 2)
                .with_order(order)
                .build()
                .unwrap();
            let plan = Plan::Surface(Box::new(surface));
            let rect = Plan::Rectangle {
                plan_m: [0.6, 0.4],
                radii_m: [f64::INFINITY; 2],
                edge_grading: 0.0,
            };
            for m in [1, 2] {
                let a = plan.mesh([m, m], &layers()).unwrap();
                let b = rect.mesh([3 * m, 2 * m], &layers()).unwrap();
                same_nodes(&a, &b, 1e-14);
                assert!(a.layer.iter().zip(&b.layer).all(|(x, y)| x == y));
            }
        }
    }

    /// A dome whose surface mesh has the exact surface's nodes and normals gives the
    /// structured dome's nodes, every layer its thickness along the normal.
    #[test]
    fn an_exact_dome_surface_is_the_structured_dome() {
        let spec = RectangleSpec::flat(0.6, 0.4, 3, 2)
            .with_order(ElementOrder::Quadratic)
            .curved(1.5, 2.5);
        let surface = spec.build().unwrap();
        let a = Plan::Surface(Box::new(surface))
            .mesh([1, 1], &layers())
            .unwrap();
        let b = Plan::Rectangle {
            plan_m: [0.6, 0.4],
            radii_m: [1.5, 2.5],
            edge_grading: 0.0,
        }
        .mesh([3, 2], &layers())
        .unwrap();
        same_nodes(&a, &b, 1e-12);
    }

    #[test]
    fn a_surface_level_is_split_m_by_m() {
        let surface = RectangleSpec::flat(0.6, 0.4, 3, 2).build().unwrap();
        let plan = Plan::Surface(Box::new(surface));
        let e = plan.mesh([2, 3], &layers()).unwrap_err().to_string();
        assert!(e.contains("[m, m]"), "{e}");
        let e = plan.mesh([0, 0], &layers()).unwrap_err().to_string();
        assert!(e.contains("1..=16"), "{e}");
        let mut bad = layers();
        bad[2].thickness_m = -1.0;
        let e = plan.mesh([1, 1], &bad).unwrap_err().to_string();
        assert!(e.contains("layer 3"), "{e}");
    }
}
