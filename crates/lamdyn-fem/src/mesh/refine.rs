//! Uniform refinement: every element split into m × m, the sequence of nested meshes a
//! Richardson extrapolation needs ([`crate::convergence`]).
//!
//! A new node sits at x(r, s) = Σ h_k(r, s) x_k of its element's geometric map (bilinear for
//! MITC4, biquadratic for MITC9) at r, s on an even grid, its director at the normalised
//! Σ h_k d_k. Every node of the coarse mesh is a node of the refined one, at the same position.
//! A [`Surface`] replaces both by the exact surface's point and normal: the rectangle generator
//! gives its dome this way, so that a refined dome is the dome, not the coarse mesh's facets.
//! Without one, a refined 4-node mesh keeps the coarse facets, and a convergence study measures
//! the error against that faceted surface (9-node meshes keep their curved elements).
//! Node and element groups are not carried over.

use super::Mesh;
use crate::element::ElementOrder;
use crate::error::FemError;
use crate::vec3::{V3, unit};
use std::collections::HashMap;

/// The exact mid-surface as a function: a point near it → (the surface's point, its unit
/// normal).
pub type SurfaceFn = dyn Fn(V3) -> (V3, V3) + Sync;

/// A borrowed [`SurfaceFn`].
pub type Surface<'a> = &'a SurfaceFn;

/// Where a grid point of an element lies, so that neighbours find the same node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    /// A corner: the coarse node.
    Corner(usize),
    /// On the edge between coarse corners (lo, hi), `k` steps from `lo`.
    Edge(usize, usize, usize),
    /// Inside element `e` at grid point (a, b).
    Inner(usize, usize, usize),
}

impl Mesh {
    /// The mesh with every element split into `m` × `m` elements of the same order (m = 1: a
    /// copy without groups), new nodes on `surface` when given (see the module's text).
    ///
    /// # Errors
    /// [`FemError::InvalidParameter`] for m = 0 or m > 64; [`FemError::InvalidMesh`] if the
    /// refined mesh fails [`Mesh::of_order`]'s checks (it cannot when the coarse one passed).
    pub fn subdivided(&self, m: usize, surface: Option<Surface<'_>>) -> Result<Mesh, FemError> {
        if !(1..=64).contains(&m) {
            return Err(FemError::InvalidParameter {
                context: "refinement".into(),
                field: "subdivisions".into(),
                value: m.to_string(),
                requirement: "must lie in 1..=64".into(),
            });
        }
        let order = self.order();
        let q = match order {
            ElementOrder::Linear => 1,
            ElementOrder::Quadratic => 2,
        };
        let n = q * m; // grid steps per element side
        let mut index: HashMap<Key, usize> = HashMap::new();
        let mut nodes = Vec::new();
        let mut directors = Vec::new();
        let mut connectivity = Vec::with_capacity(self.connectivity.len() * m * m);
        for e in 0..self.n_elements() {
            let conn = self.element_nodes(e);
            let corners = self.corners(e);
            let mut grid = vec![0usize; (n + 1) * (n + 1)];
            for b in 0..=n {
                for a in 0..=n {
                    let key = grid_key(e, &corners, n, a, b);
                    grid[b * (n + 1) + a] = *index.entry(key).or_insert_with(|| {
                        let r = -1.0 + 2.0 * a as f64 / n as f64;
                        let s = -1.0 + 2.0 * b as f64 / n as f64;
                        let (x, d) = self.map_point(order, conn, r, s, key, surface);
                        nodes.push(x);
                        directors.push(d);
                        nodes.len() - 1
                    });
                }
            }
            let at = |a: usize, b: usize| grid[b * (n + 1) + a];
            for j in 0..m {
                for i in 0..m {
                    super::push_grid_element(&mut connectivity, at, (q * i, q * j), q);
                }
            }
        }
        Mesh::of_order(order, nodes, Some(directors), connectivity)
    }

    /// Position and director of the point (r, s) of an element.
    fn map_point(
        &self,
        order: ElementOrder,
        conn: &[usize],
        r: f64,
        s: f64,
        key: Key,
        surface: Option<Surface<'_>>,
    ) -> (V3, V3) {
        if let Key::Corner(c) = key {
            return (self.nodes()[c], self.directors()[c]);
        }
        let (h, _, _) = order.shape(r, s);
        let mut x = [0.0; 3];
        let mut d = [0.0; 3];
        for (k, &node) in conn.iter().enumerate() {
            for c in 0..3 {
                x[c] += h[k] * self.nodes()[node][c];
                d[c] += h[k] * self.directors()[node][c];
            }
        }
        match surface {
            Some(f) => f(x),
            None => (x, unit(d)),
        }
    }
}

/// The key of grid point (a, b) of element `e` (n steps per side): corners by node, edge
/// points by their edge's corners and the distance from the lower-numbered corner, so that
/// both elements along an edge name the same node.
fn grid_key(e: usize, corners: &[usize; 4], n: usize, a: usize, b: usize) -> Key {
    let corner = |c: usize| Key::Corner(corners[c]);
    match (a, b) {
        (0, 0) => return corner(0),
        (x, 0) if x == n => return corner(1),
        (x, y) if x == n && y == n => return corner(2),
        (0, y) if y == n => return corner(3),
        _ => {}
    }
    // Edges counter-clockwise: (from corner, to corner, steps from `from`).
    let edge = if b == 0 {
        Some((0, 1, a))
    } else if a == n {
        Some((1, 2, b))
    } else if b == n {
        Some((2, 3, n - a))
    } else if a == 0 {
        Some((3, 0, n - b))
    } else {
        None
    };
    match edge {
        Some((from, to, k)) => {
            let (p, q) = (corners[from], corners[to]);
            if p < q {
                Key::Edge(p, q, k)
            } else {
                Key::Edge(q, p, n - k)
            }
        }
        None => Key::Inner(e, a, b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::RectangleSpec;

    #[test]
    fn refined_rectangle_is_the_finer_rectangle() {
        for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
            let spec = RectangleSpec::flat(0.9, 0.6, 3, 2)
                .with_order(order)
                .curved(3.0, 5.0);
            let coarse = spec.build().unwrap();
            let lift = spec.surface();
            let fine = coarse.subdivided(2, Some(&lift)).unwrap();
            let direct = RectangleSpec {
                elements_x: 6,
                elements_y: 4,
                ..spec
            }
            .build()
            .unwrap();
            assert_eq!(fine.nodes().len(), direct.nodes().len());
            assert_eq!(fine.n_elements(), direct.n_elements());
            assert!((fine.area() - direct.area()).abs() < 1e-14);
            // Every node of the direct mesh is a node of the refined one, with its director.
            let loc = crate::mesh::Locator::new(&fine, 1e-12);
            for (x, d) in direct.nodes().iter().zip(direct.directors()) {
                let (k, dist) = loc.nearest(*x);
                assert!(dist < 1e-14, "{order:?}: node {x:?} missing ({dist})");
                let dd = fine.directors()[k];
                assert!((0..3).all(|c| (dd[c] - d[c]).abs() < 1e-14));
            }
        }
    }

    #[test]
    fn coarse_nodes_are_kept_and_edges_shared() {
        let coarse = RectangleSpec::flat(1.0, 1.0, 2, 2)
            .with_order(ElementOrder::Quadratic)
            .build()
            .unwrap();
        let fine = coarse.subdivided(3, None).unwrap();
        // (2·2·3 + 1)² nodes: neighbours share every edge node (a duplicate would add nodes and
        // fail the mesh's shared-mid-side check).
        assert_eq!(fine.nodes().len(), 13 * 13);
        assert_eq!(fine.n_elements(), 36);
        for (i, x) in coarse.nodes().iter().enumerate() {
            assert!(fine.nodes().iter().any(|y| y == x), "coarse node {i} moved");
        }
    }

    #[test]
    fn refusal_of_zero_subdivisions() {
        let mesh = RectangleSpec::flat(1.0, 1.0, 2, 2).build().unwrap();
        let err = mesh.subdivided(0, None).unwrap_err().to_string();
        assert!(err.contains("subdivisions"), "{err}");
    }
}
