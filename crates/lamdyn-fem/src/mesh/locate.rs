//! Mapping measurement points to mesh nodes: the nearest node, within a tolerance.

use super::Mesh;
use crate::error::FemError;
use crate::vec3::{V3, norm, sub};

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
        let mut loc = Self {
            mesh,
            tolerance_m,
            origin: lo,
            cell,
            dims,
            buckets: Vec::new(),
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
