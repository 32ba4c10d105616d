//! Elastic supports of the tested part: grounded springs and dashpots at points of the bottom
//! surface (foam blocks, bungee cords, air cushions). They turn the free part's rigid-body
//! modes into support resonances, and they shift and damp the elastic modes; a model that
//! leaves them out reads those shifts as a stiffer or lossier core.
//!
//! Each support acts at its point of the plan on the bottom surface, along the global x, y and
//! z axes, through the shape functions of the bottom face that holds it ([`SupportTerm`]):
//! stiffness k (N/m) into K_s and viscous damping c (N·s/m) into C_s
//! ([`crate::system::LayeredSystem::add_supports`]; the reduced model projects both,
//! [`crate::reduced::ReducedModel::with_orders`]).
//!
//! A support with a contact patch (a foam block's face, [`PointSupport::patch_m`]) spreads k
//! and c evenly over a fixed grid of [`PATCH_POINTS`] × [`PATCH_POINTS`] points of the patch
//! (the midpoint rule of a uniform elastic bed). A point spring on a laminate with a soft
//! core is a load the meshes of an identification cannot resolve: the faces shear apart
//! around it over the length √(D_faces/S) (about 20 mm on the paper's roof, S the core's
//! shear stiffness), so the ladder of meshes converges irregularly there; a patch of a few
//! centimetres is both the physical support and a load the ladder resolves.

use crate::LayeredError;
use crate::hex20::{NODES, shape};
use crate::mesh::HexMesh;

/// One support (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSupport {
    /// Position as fractions (0..1) of the plan's extent along x and y.
    pub xy_fraction: [f64; 2],
    /// Stiffness along the global x, y, z axes, N/m.
    pub stiffness_n_m: [f64; 3],
    /// Viscous damping along the global x, y, z axes, N·s/m (causal, unlike a loss factor).
    pub damping_n_s_m: [f64; 3],
    /// Size of the contact patch along x and y, m, centred on the point ([0, 0]: a point; a
    /// size of 0 along one axis: a line). The stiffness and damping are the patch's totals.
    pub patch_m: [f64; 2],
}

/// Points per side of the grid that spreads a patch support (module docs).
pub const PATCH_POINTS: usize = 6;

impl PointSupport {
    /// Checks the support numbered `i` (from 0): its point inside the plate, its stiffness and
    /// damping finite and non-negative; the error names `supports[i]` and the field.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] with the reason.
    pub fn check(&self, i: usize) -> Result<(), LayeredError> {
        let [fx, fy] = self.xy_fraction;
        if !((0.0..=1.0).contains(&fx) && (0.0..=1.0).contains(&fy)) {
            return Err(LayeredError::Invalid(format!(
                "supports[{i}].xy_fraction = [{fx}, {fy}]: the support lies outside the plate \
                 (fractions of its plan must lie in [0, 1])"
            )));
        }
        let [px, py] = self.patch_m;
        if !(px.is_finite() && py.is_finite() && px >= 0.0 && py >= 0.0) {
            return Err(LayeredError::Invalid(format!(
                "supports[{i}].patch_m = [{px}, {py}]: the patch's size must be finite and \
                 non-negative (m)"
            )));
        }
        for (field, v) in [
            ("stiffness_n_m", self.stiffness_n_m),
            ("damping_n_s_m", self.damping_n_s_m),
        ] {
            if !v.iter().all(|k| k.is_finite() && *k >= 0.0) {
                return Err(LayeredError::Invalid(format!(
                    "supports[{i}].{field} = {v:?}: must be finite and non-negative (N/m, N s/m)"
                )));
            }
        }
        Ok(())
    }
}

impl PointSupport {
    /// The plan points (x, y in m) the support acts at on a plan spanning `lo` to `hi`: its
    /// point, or its patch's grid ([`PATCH_POINTS`]), each carrying an equal share.
    pub fn plan_points(&self, lo: [f64; 2], hi: [f64; 2]) -> Vec<[f64; 2]> {
        let [fx, fy] = self.xy_fraction;
        let centre = [lo[0] + fx * (hi[0] - lo[0]), lo[1] + fy * (hi[1] - lo[1])];
        patch_points(centre, self.patch_m)
    }
}

/// The plan's extent of `mesh` (its bottom surface): lowest and highest x and y, m.
fn plan_extent(mesh: &HexMesh) -> ([f64; 2], [f64; 2]) {
    mesh.bottom.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), (n, _)| {
            let p = mesh.nodes[*n];
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

/// One support's action along one global axis: a grounded spring k and dashpot c on the
/// displacement u(p) = Σ_a w_a u_a of its point p, the weights w_a = N_a(ξ, η) of the
/// bottom face that holds p. K_s gains k w wᵀ and C_s gains c w wᵀ: the same point on every
/// mesh, so a ladder of meshes converges (a spring on the nearest node moves with the mesh by
/// up to half an element, which on a glass laminate shifts the modes by more than the ladder's
/// tolerance).
#[derive(Debug, Clone, PartialEq)]
pub struct SupportTerm {
    /// (dof, weight) pairs.
    pub weights: Vec<(usize, f64)>,
    /// Stiffness, N/m.
    pub stiffness_n_m: f64,
    /// Viscous damping, N·s/m.
    pub damping_n_s_m: f64,
}

/// The terms (one per support and axis) of `supports` on the bottom surface of `mesh`
/// (module docs, [`SupportTerm`]).
///
/// # Errors
/// [`LayeredError::Invalid`] naming the support (`supports[i]`, from 0) for a point outside
/// the plate, or a negative or non-finite stiffness or damping.
pub fn support_terms(
    mesh: &HexMesh,
    supports: &[PointSupport],
) -> Result<Vec<SupportTerm>, LayeredError> {
    let (lo, hi) = plan_extent(mesh);
    let mut terms = Vec::new();
    for (i, s) in supports.iter().enumerate() {
        s.check(i)?;
        let points = s.plan_points(lo, hi);
        let share = 1.0 / points.len() as f64;
        for [x, y] in points {
            let face = bottom_point(mesh, [x, y]).ok_or_else(|| {
                LayeredError::Invalid(format!(
                    "supports[{i}]: no bottom face of the mesh holds ({x:.4}, {y:.4}) m (its patch \
                     {:?} m reaches beyond the plate?)",
                    s.patch_m
                ))
            })?;
            for c in 0..3 {
                terms.push(SupportTerm {
                    weights: face.iter().map(|&(n, w)| (3 * n + c, w)).collect(),
                    stiffness_n_m: share * s.stiffness_n_m[c],
                    damping_n_s_m: share * s.damping_n_s_m[c],
                });
            }
        }
    }
    Ok(terms)
}

/// The plan points a support acts at: its centre, or the midpoints of a [`PATCH_POINTS`]-wide
/// grid over each axis along which its patch has a size.
fn patch_points(centre: [f64; 2], patch_m: [f64; 2]) -> Vec<[f64; 2]> {
    let along = |c: f64, size: f64| -> Vec<f64> {
        if size > 0.0 {
            (0..PATCH_POINTS)
                .map(|k| c + size * ((k as f64 + 0.5) / PATCH_POINTS as f64 - 0.5))
                .collect()
        } else {
            vec![c]
        }
    };
    let ys = along(centre[1], patch_m[1]);
    along(centre[0], patch_m[0])
        .into_iter()
        .flat_map(|x| ys.iter().map(move |&y| [x, y]))
        .collect()
}

/// The bottom face holding the plan point `xy` and the shape functions there: (node, N_a) of
/// its eight nodes, found by Newton's method on the face's x, y map (the face is at ζ = ±1
/// of a bottom element: the one whose nodes all lie on the bottom surface).
fn bottom_point(mesh: &HexMesh, xy: [f64; 2]) -> Option<Vec<(usize, f64)>> {
    let bottom: std::collections::HashSet<usize> = mesh.bottom.iter().map(|b| b.0).collect();
    for conn in &mesh.elements {
        for zeta in [-1.0, 1.0] {
            let face: Vec<usize> = (0..20).filter(|&a| NODES[a][2] == zeta).collect();
            if !face.iter().all(|&a| bottom.contains(&conn[a])) {
                continue;
            }
            let mut xi = [0.0, 0.0];
            for _ in 0..20 {
                let (n, dn) = shape([xi[0], xi[1], zeta]);
                let (mut r, mut j) = ([-xy[0], -xy[1]], [[0.0; 2]; 2]);
                for &a in &face {
                    let p = mesh.nodes[conn[a]];
                    for d in 0..2 {
                        r[d] += n[a] * p[d];
                        for k in 0..2 {
                            j[d][k] += dn[a][k] * p[d];
                        }
                    }
                }
                let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                if det.abs() < 1e-300 {
                    break;
                }
                xi[0] -= (j[1][1] * r[0] - j[0][1] * r[1]) / det;
                xi[1] -= (-j[1][0] * r[0] + j[0][0] * r[1]) / det;
            }
            if xi.iter().all(|v| v.abs() <= 1.0 + 1e-9) {
                let (n, _) = shape([xi[0], xi[1], zeta]);
                return Some(face.iter().map(|&a| (conn[a], n[a])).collect());
            }
        }
    }
    None
}
