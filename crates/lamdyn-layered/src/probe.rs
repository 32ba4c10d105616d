//! Points of the top surface where a layered model is observed or driven: a sensor or a
//! hammer at any point of the surface, not only at a node.
//!
//! A point is located on the top face (ζ = +1) of a hexahedron of the top layer: the natural
//! coordinates (ξ, η) are those that bring the face's serendipity map x(ξ, η) = Σ_a N_a(ξ, η, 1)
//! x_a nearest the point (Gauss–Newton on |x(ξ, η) − p|², the face's eight nodes a), and the
//! point's displacement along a unit direction d is u·d = Σ_a N_a d·u_a [Zienkiewicz & Taylor,
//! *The Finite Element Method*, vol. 1, §8.7]. The same weights spread a unit force along d over
//! the face's nodes (the consistent nodal load of a point force), so the receptance between two
//! points is symmetric. A point is on the surface when it lies within the face (|ξ|, |η| ≤ 1 up
//! to a relative 1e-6) and the distance to it is at most a tolerance: a sensor glued on the top
//! of a laminate whose mid-surface is given is `thickness / 2` off, so callers pass that.

use crate::error::LayeredError;
use crate::hex20::shape;
use crate::mesh::HexMesh;
use std::collections::HashSet;

/// Local indices (C3D20 order) of the eight nodes of an element's top face ζ = +1.
const TOP_FACE: [usize; 8] = [4, 5, 6, 7, 12, 13, 14, 15];

/// Where a point lies on the top surface and how it reads or loads the model's dofs.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceProbe {
    /// (dof, weight): u·d = Σ weight · u_dof.
    entries: Vec<(usize, f64)>,
    /// Distance from the given point to the surface point found, m.
    pub distance_m: f64,
}

impl SurfaceProbe {
    /// Locates `point` (m) on the top surface of `mesh` and reads the displacement along
    /// `direction` (any length; normalised here) there.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] naming `what` for a zero or non-finite direction, a mesh
    /// without a top surface, or a point farther than `tolerance_m` from it (with the distance).
    pub fn locate(
        mesh: &HexMesh,
        point: [f64; 3],
        direction: [f64; 3],
        tolerance_m: f64,
        what: &str,
    ) -> Result<Self, LayeredError> {
        let d = unit(direction).ok_or_else(|| {
            LayeredError::Invalid(format!(
                "{what}: direction {direction:?} is not a unit axis"
            ))
        })?;
        let (face, xi, distance) = nearest_face_point(mesh, point)
            .ok_or_else(|| LayeredError::Invalid(format!("{what}: the mesh has no top surface")))?;
        if distance.is_nan() || distance > tolerance_m {
            return Err(LayeredError::Invalid(format!(
                "{what} at ({:.4}, {:.4}, {:.4}) m is {distance:.3e} m from the model's top \
                 surface (tolerance {tolerance_m:.1e} m): not on the part",
                point[0], point[1], point[2]
            )));
        }
        let (n, _) = shape([xi[0], xi[1], 1.0]);
        let element = &mesh.elements[face];
        let mut entries = Vec::with_capacity(24);
        for &a in &TOP_FACE {
            for (c, &dc) in d.iter().enumerate() {
                if n[a] != 0.0 && dc != 0.0 {
                    entries.push((3 * element[a] + c, n[a] * dc));
                }
            }
        }
        Ok(Self {
            entries,
            distance_m: distance,
        })
    }

    /// The (dof, weight) pairs of u·d.
    pub fn entries(&self) -> &[(usize, f64)] {
        &self.entries
    }

    /// A unit force along the direction at the point, as a load vector over `n_dofs` dofs.
    pub fn load(&self, n_dofs: usize) -> Vec<f64> {
        let mut f = vec![0.0; n_dofs];
        for &(dof, w) in &self.entries {
            f[dof] += w;
        }
        f
    }
}

fn unit(d: [f64; 3]) -> Option<[f64; 3]> {
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (l.is_finite() && l > 0.0).then(|| [d[0] / l, d[1] / l, d[2] / l])
}

/// The elements whose top face lies on the top surface (its four corners are top nodes).
fn top_faces(mesh: &HexMesh) -> Vec<usize> {
    let top: HashSet<usize> = mesh.top.iter().map(|(n, _)| *n).collect();
    (0..mesh.elements.len())
        .filter(|&e| (4..8).all(|a| top.contains(&mesh.elements[e][a])))
        .collect()
}

/// The top face nearest `p`: (element, (ξ, η), distance).
fn nearest_face_point(mesh: &HexMesh, p: [f64; 3]) -> Option<(usize, [f64; 2], f64)> {
    let faces = top_faces(mesh);
    nearest_among(mesh, &faces, p, true).or_else(|| nearest_among(mesh, &faces, p, false))
}

/// The nearest of `faces` to `p`; with `near_only`, faces whose bounding box grown by its own
/// size does not reach `p` are skipped (a point off the part then finds none).
fn nearest_among(
    mesh: &HexMesh,
    faces: &[usize],
    p: [f64; 3],
    near_only: bool,
) -> Option<(usize, [f64; 2], f64)> {
    let mut best: Option<(usize, [f64; 2], f64)> = None;
    for &e in faces {
        let x: Vec<[f64; 3]> = TOP_FACE
            .iter()
            .map(|&a| mesh.nodes[mesh.elements[e][a]])
            .collect();
        // Skip faces whose bounding box, grown by its own size, does not reach p.
        let size = (0..3)
            .map(|c| {
                let (lo, hi) = min_max(x.iter().map(|q| q[c]));
                hi - lo
            })
            .fold(0.0, f64::max);
        if near_only
            && (0..3).any(|c| {
                let (lo, hi) = min_max(x.iter().map(|q| q[c]));
                p[c] < lo - size || p[c] > hi + size
            })
        {
            continue;
        }
        let (xi, d) = project_on_face(&x, p);
        if best.as_ref().is_none_or(|b| d < b.2) {
            best = Some((e, xi, d));
        }
    }
    best
}

fn min_max(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    })
}

/// The face point nearest `p` within the face: (ξ, η) clamped to [−1, 1]² by projected
/// Gauss–Newton, and the distance.
fn project_on_face(x: &[[f64; 3]], p: [f64; 3]) -> ([f64; 2], f64) {
    let map = |xi: [f64; 2]| {
        let (n, dn) = shape([xi[0], xi[1], 1.0]);
        let mut pos = [0.0; 3];
        let mut jac = [[0.0; 2]; 3];
        for (k, &a) in TOP_FACE.iter().enumerate() {
            for c in 0..3 {
                pos[c] += n[a] * x[k][c];
                jac[c][0] += dn[a][0] * x[k][c];
                jac[c][1] += dn[a][1] * x[k][c];
            }
        }
        (pos, jac)
    };
    let mut xi = [0.0, 0.0];
    for _ in 0..30 {
        let (pos, j) = map(xi);
        let r = [pos[0] - p[0], pos[1] - p[1], pos[2] - p[2]];
        // Normal equations of the 3 × 2 Jacobian.
        let a = [
            [dot3(j, 0, 0), dot3(j, 0, 1)],
            [dot3(j, 0, 1), dot3(j, 1, 1)],
        ];
        let g = [
            (0..3).map(|c| j[c][0] * r[c]).sum::<f64>(),
            (0..3).map(|c| j[c][1] * r[c]).sum::<f64>(),
        ];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        if det.is_nan() || det == 0.0 {
            break;
        }
        let step = [
            (a[1][1] * g[0] - a[0][1] * g[1]) / det,
            (a[0][0] * g[1] - a[1][0] * g[0]) / det,
        ];
        let next = [
            (xi[0] - step[0]).clamp(-1.0, 1.0),
            (xi[1] - step[1]).clamp(-1.0, 1.0),
        ];
        let moved = (next[0] - xi[0]).abs().max((next[1] - xi[1]).abs());
        xi = next;
        if moved < 1e-12 {
            break;
        }
    }
    let (pos, _) = map(xi);
    let d = (0..3).map(|c| (pos[c] - p[c]).powi(2)).sum::<f64>().sqrt();
    (xi, d)
}

fn dot3(j: [[f64; 2]; 3], a: usize, b: usize) -> f64 {
    (0..3).map(|c| j[c][a] * j[c][b]).sum()
}

/// Natural coordinates of the top face's nodes (for tests).
#[cfg(test)]
fn face_node(k: usize) -> [f64; 2] {
    let c = crate::hex20::NODES[TOP_FACE[k]];
    [c[0], c[1]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{LayerMesh, LayeredPlateSpec};

    fn plate(radius_m: f64) -> HexMesh {
        LayeredPlateSpec {
            length_m: 0.6,
            width_m: 0.4,
            nx: 6,
            ny: 4,
            radius_x_m: radius_m,
            radius_y_m: radius_m,
            layers: vec![
                LayerMesh {
                    thickness_m: 3e-3,
                    elements: 1,
                },
                LayerMesh {
                    thickness_m: 1e-3,
                    elements: 1,
                },
            ],
            edge_grading: 0.0,
        }
        .build()
        .unwrap()
    }

    /// At a top node the probe reads that node alone (weight 1 along the direction); the face
    /// node coordinates are the C3D20 ones.
    #[test]
    fn a_probe_at_a_node_reads_that_node() {
        let mesh = plate(f64::INFINITY);
        let (node, _) = mesh.top[7];
        let p = SurfaceProbe::locate(&mesh, mesh.nodes[node], [0.0, 0.0, 2.0], 1e-9, "s").unwrap();
        let on: Vec<_> = p.entries().iter().filter(|e| e.1.abs() > 1e-12).collect();
        assert_eq!(on.len(), 1, "{:?}", p.entries());
        assert_eq!(on[0].0, 3 * node + 2);
        assert!((on[0].1 - 1.0).abs() < 1e-12);
        assert_eq!(face_node(0), [-1.0, -1.0]);
    }

    /// Between nodes the weights interpolate a quadratic field exactly, also on a curved
    /// surface, and sum to one; a point off the part is refused with its distance.
    #[test]
    fn probes_interpolate_between_nodes_and_refuse_points_off_the_part() {
        for radius in [f64::INFINITY, 2.0] {
            let mesh = plate(radius);
            let field = |q: [f64; 3]| 1.0 + 2.0 * q[0] - q[1] + 3.0 * q[0] * q[1] + q[0] * q[0];
            // The surface point nearest (x, y, 0): its coordinates interpolated by the weights.
            let on_surface = |x: f64, y: f64| {
                let p =
                    SurfaceProbe::locate(&mesh, [x, y, 0.0], [0.0, 0.0, 1.0], 1.0, "z").unwrap();
                let coordinate = |c: usize| {
                    p.entries()
                        .iter()
                        .map(|&(dof, w)| w * mesh.nodes[dof / 3][c])
                        .sum::<f64>()
                };
                [coordinate(0), coordinate(1), coordinate(2)]
            };
            let [x, y, z] = on_surface(0.123, 0.071);
            let p = SurfaceProbe::locate(&mesh, [x, y, z], [1.0, 0.0, 0.0], 1e-9, "s").unwrap();
            let read: f64 = p
                .entries()
                .iter()
                .map(|&(dof, w)| w * field(mesh.nodes[dof / 3]))
                .sum();
            let sum: f64 = p.entries().iter().map(|e| e.1).sum();
            assert!((sum - 1.0).abs() < 1e-12, "weights sum to {sum}");
            // On a flat plate the face map is affine in (x, y): the quadratic field is exact.
            if radius.is_infinite() {
                assert!(
                    (read - field([x, y, z])).abs() < 1e-12,
                    "{read} vs {}",
                    field([x, y, z])
                );
            }
            let err = SurfaceProbe::locate(&mesh, [0.9, 0.1, z], [0.0, 0.0, 1.0], 1e-3, "sensor 4")
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("sensor 4") && err.contains("not on the part"),
                "{err}"
            );
        }
    }
}
