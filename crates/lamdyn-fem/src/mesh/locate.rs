//! Mapping measurement points to the mesh: the nearest node, or the nearest point of the
//! mid-surface with the element's shape functions there ([`Locator::on_surface`]).

use super::Mesh;
use crate::error::FemError;
use crate::vec3::{V3, add, dot, norm, scale, sub};

/// The point of the mesh's mid-surface nearest a given point.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfacePoint {
    /// Element index.
    pub element: usize,
    /// Natural coordinates (r, s) in [−1, 1]².
    pub rs: [f64; 2],
    /// The element's nodes and their shape-function values h_k(r, s) (summing to 1): a field
    /// given at the nodes is Σ h_k u_k there.
    pub weights: Vec<(usize, f64)>,
    /// Distance from the given point to the surface point, m.
    pub distance_m: f64,
}

/// Finds the nearest node to a point, refusing points farther than a tolerance.
///
/// # Complexity
/// Bucketed in a uniform grid of the bounding box: about O(1) per query for meshes of evenly
/// sized elements, O(n) at worst.
#[derive(Debug, Clone)]
pub struct Locator<'m> {
    mesh: &'m Mesh,
    tolerance_m: f64,
    origin: V3,
    cell: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<usize>>,
    node_elements: Vec<Vec<usize>>,
    largest_element_m: f64,
}

impl<'m> Locator<'m> {
    /// A locator over `mesh` accepting points within `tolerance_m` of a node.
    pub fn new(mesh: &'m Mesh, tolerance_m: f64) -> Self {
        let nodes = mesh.nodes();
        let mut lo = nodes[0];
        let mut hi = nodes[0];
        for p in nodes {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        let span = norm(sub(hi, lo)).max(f64::MIN_POSITIVE);
        // About one node per cell in the plane of a shell mesh.
        let cell = (span / (nodes.len() as f64).sqrt()).max(span * 1e-6);
        let dims = [0, 1, 2].map(|c| (((hi[c] - lo[c]) / cell).floor() as usize + 1).min(4096));
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut node_elements = vec![Vec::new(); nodes.len()];
        let mut largest_element_m: f64 = 0.0;
        for (e, conn) in mesh.elements().enumerate() {
            for &n in conn {
                node_elements[n].push(e);
            }
            let diagonal = |a: usize, b: usize| norm(sub(nodes[conn[a]], nodes[conn[b]]));
            largest_element_m = largest_element_m.max(diagonal(0, 2)).max(diagonal(1, 3));
        }
        let mut loc = Self {
            mesh,
            tolerance_m,
            origin: lo,
            cell,
            dims,
            buckets: Vec::new(),
            node_elements,
            largest_element_m,
        };
        for (i, p) in nodes.iter().enumerate() {
            buckets[loc.bucket_of(loc.cell_of(*p))].push(i);
        }
        loc.buckets = buckets;
        loc
    }

    /// The same locator with another tolerance, m.
    pub fn with_tolerance(mut self, tolerance_m: f64) -> Self {
        self.tolerance_m = tolerance_m;
        self
    }

    fn cell_of(&self, p: V3) -> [usize; 3] {
        [0, 1, 2].map(|c| {
            (((p[c] - self.origin[c]) / self.cell).floor().max(0.0) as usize).min(self.dims[c] - 1)
        })
    }

    fn bucket_of(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// The nearest node to `p` and its distance, searching outwards ring by ring.
    pub fn nearest(&self, p: V3) -> (usize, f64) {
        let c = self.cell_of(p);
        let mut best = (usize::MAX, f64::INFINITY);
        let max_ring = *self.dims.iter().max().unwrap_or(&1);
        for ring in 0..=max_ring {
            for k in c[2].saturating_sub(ring)..=(c[2] + ring).min(self.dims[2] - 1) {
                for j in c[1].saturating_sub(ring)..=(c[1] + ring).min(self.dims[1] - 1) {
                    for i in c[0].saturating_sub(ring)..=(c[0] + ring).min(self.dims[0] - 1) {
                        for &n in &self.buckets[self.bucket_of([i, j, k])] {
                            let d = norm(sub(self.mesh.nodes()[n], p));
                            if d < best.1 || (d == best.1 && n < best.0) {
                                best = (n, d);
                            }
                        }
                    }
                }
            }
            // Every node outside this ring is at least ring·cell away.
            if best.0 != usize::MAX && best.1 <= ring as f64 * self.cell {
                break;
            }
        }
        best
    }

    /// The nodes within `radius` of `p`.
    fn within(&self, p: V3, radius: f64) -> Vec<usize> {
        let c = self.cell_of(p);
        let reach = (radius / self.cell).ceil() as usize + 1;
        let mut out = Vec::new();
        for k in c[2].saturating_sub(reach)..=(c[2] + reach).min(self.dims[2] - 1) {
            for j in c[1].saturating_sub(reach)..=(c[1] + reach).min(self.dims[1] - 1) {
                for i in c[0].saturating_sub(reach)..=(c[0] + reach).min(self.dims[0] - 1) {
                    out.extend(
                        self.buckets[self.bucket_of([i, j, k])]
                            .iter()
                            .filter(|&&n| norm(sub(self.mesh.nodes()[n], p)) <= radius),
                    );
                }
            }
        }
        out
    }

    /// The point of the mid-surface nearest `p`: over the elements that can hold it (those with
    /// a node within the nearest node's distance plus the largest element diagonal), the point
    /// x(r, s) = Σ h_k(r, s) x_k of each element nearest `p`, found by Gauss–Newton on
    /// |x(r, s) − p|² with (r, s) kept in [−1, 1]²; the nearest of those.
    pub fn on_surface(&self, p: V3) -> SurfacePoint {
        let (n0, d0) = self.nearest(p);
        let mut candidates: Vec<usize> = self
            .within(p, d0 + self.largest_element_m)
            .into_iter()
            .flat_map(|n| self.node_elements[n].iter().copied())
            .collect();
        candidates.sort_unstable();
        candidates.dedup();
        // The nearest node, as a node of one of its elements.
        let element = self.node_elements[n0].first().copied().unwrap_or(0);
        let conn = self.mesh.element_nodes(element);
        let local = conn.iter().position(|&n| n == n0).unwrap_or(0);
        let at_node = SurfacePoint {
            element,
            rs: self.mesh.order().node_rs()[local],
            weights: conn
                .iter()
                .enumerate()
                .map(|(k, &n)| (n, f64::from(u8::from(k == local))))
                .collect(),
            distance_m: d0,
        };
        candidates
            .into_iter()
            .map(|e| self.nearest_in_element(e, p))
            .fold(at_node, |best, q| {
                if q.distance_m < best.distance_m - 1e-12 * self.largest_element_m {
                    q
                } else {
                    best
                }
            })
    }

    /// The point of element `e` nearest `p` (see [`Self::on_surface`]).
    fn nearest_in_element(&self, e: usize, p: V3) -> SurfacePoint {
        let conn = self.mesh.element_nodes(e);
        let order = self.mesh.order();
        let x: Vec<V3> = conn.iter().map(|&n| self.mesh.nodes()[n]).collect();
        let point = |rs: [f64; 2]| {
            let (h, hr, hs) = order.shape(rs[0], rs[1]);
            let mut out = [[0.0; 3]; 3];
            for k in 0..x.len() {
                out[0] = add(out[0], scale(h[k], x[k]));
                out[1] = add(out[1], scale(hr[k], x[k]));
                out[2] = add(out[2], scale(hs[k], x[k]));
            }
            out
        };
        let mut rs = [0.0, 0.0];
        for _ in 0..30 {
            let [xp, xr, xs] = point(rs);
            let d = sub(p, xp);
            let (a, b, c) = (dot(xr, xr), dot(xr, xs), dot(xs, xs));
            let (gr, gs) = (dot(xr, d), dot(xs, d));
            let det = a * c - b * b;
            if det.is_nan() || det <= 0.0 {
                break;
            }
            let step = [(c * gr - b * gs) / det, (a * gs - b * gr) / det];
            let next = [
                (rs[0] + step[0]).clamp(-1.0, 1.0),
                (rs[1] + step[1]).clamp(-1.0, 1.0),
            ];
            let moved = (next[0] - rs[0]).abs().max((next[1] - rs[1]).abs());
            rs = next;
            if moved < 1e-13 {
                break;
            }
        }
        let (h, _, _) = order.shape(rs[0], rs[1]);
        SurfacePoint {
            element: e,
            rs,
            weights: conn.iter().copied().zip(h).collect(),
            distance_m: norm(sub(p, point(rs)[0])),
        }
    }

    /// Maps each point to its nearest node.
    ///
    /// # Errors
    /// [`FemError::Locate`] for the first point that is not finite or is farther than the
    /// tolerance from every node.
    pub fn locate_all(&self, points: &[V3]) -> Result<Vec<usize>, FemError> {
        points
            .iter()
            .enumerate()
            .map(|(index, p)| {
                let fail = |reason: String| FemError::Locate {
                    index,
                    x: p[0],
                    y: p[1],
                    z: p[2],
                    reason,
                };
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(fail("not a finite point".into()));
                }
                let (n, d) = self.nearest(*p);
                if d > self.tolerance_m {
                    return Err(fail(format!(
                        "nearest node {n} is {d:.4e} m away, beyond the tolerance of {:.4e} m",
                        self.tolerance_m
                    )));
                }
                Ok(n)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::bilinear_shape;
    use crate::mesh::structured::RectangleSpec;
    use crate::vec3::cross;

    fn dome() -> Mesh {
        RectangleSpec {
            length_x_m: 0.9,
            length_y_m: 0.8,
            elements_x: 9,
            elements_y: 7,
            radius_x_m: 3.0,
            radius_y_m: 5.0,
            grading: 0.4,
            ..RectangleSpec::flat(1.0, 1.0, 1, 1)
        }
        .build()
        .unwrap()
    }

    /// A point x(r, s) of an element of a doubly curved, graded mesh, moved along the surface
    /// normal by δ, is found in that element at (r, s), at distance δ; the weights sum to one
    /// and reproduce any field linear in the node positions (the isoparametric identity
    /// Σ h_k x_k = x).
    #[test]
    fn points_on_a_curved_mesh_are_found_with_their_natural_coordinates() {
        let mesh = dome();
        let loc = Locator::new(&mesh, 1e-3);
        for (e, rs, delta) in [
            (0, [0.3, -0.7], 0.0),
            (17, [-0.95, 0.2], 1e-3),
            (40, [0.5, 0.5], -2e-3),
            (62, [1.0, 1.0], 0.0),
        ] {
            let x = mesh.corners(e).map(|n| mesh.nodes()[n]);
            let (h, hr, hs) = bilinear_shape(rs[0], rs[1]);
            let mut at = [0.0; 3];
            let (mut xr, mut xs) = ([0.0; 3], [0.0; 3]);
            for k in 0..4 {
                at = add(at, scale(h[k], x[k]));
                xr = add(xr, scale(hr[k], x[k]));
                xs = add(xs, scale(hs[k], x[k]));
            }
            let n = cross(xr, xs);
            let p = add(at, scale(delta / norm(n), n));
            let q = loc.on_surface(p);
            assert!((q.distance_m - delta.abs()).abs() < 1e-9, "{q:?}");
            let back = q
                .weights
                .iter()
                .fold([0.0; 3], |s, (k, w)| add(s, scale(*w, mesh.nodes()[*k])));
            assert!(norm(sub(back, at)) < 1e-9, "{q:?}");
            assert!((q.weights.iter().map(|w| w.1).sum::<f64>() - 1.0).abs() < 1e-12);
            if rs != [1.0, 1.0] {
                assert_eq!(q.element, e);
                assert!((q.rs[0] - rs[0]).abs() < 1e-9 && (q.rs[1] - rs[1]).abs() < 1e-9);
            }
        }
    }

    /// A point beyond the plate's edge maps to the edge, its distance the overhang.
    #[test]
    fn a_point_off_the_edge_maps_to_the_edge() {
        let mesh = RectangleSpec {
            length_x_m: 1.0,
            length_y_m: 1.0,
            elements_x: 4,
            elements_y: 4,
            radius_x_m: f64::INFINITY,
            radius_y_m: f64::INFINITY,
            grading: 0.0,
            ..RectangleSpec::flat(1.0, 1.0, 1, 1)
        }
        .build()
        .unwrap();
        let q = Locator::new(&mesh, 1e-3).on_surface([0.53, 0.1, 0.0]);
        assert!((q.distance_m - 0.03).abs() < 1e-12, "{q:?}");
    }
}
