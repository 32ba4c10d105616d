//! Sensors and excitations on the FE mesh: a channel (point and direction) becomes a vector over
//! the global dofs (or of the nearest node alone).
//!
//! **On the surface** the channel's point is projected on the mid-surface (element e, natural
//! coordinates (r, s), [`Locator::on_surface`]). The in-plane part of the displacement is the
//! element's bilinear interpolation Σ h_k u_k. The normal part w = n·u is interpolated with the
//! nodal slopes as well: a bending wave between nodes is curved, and the bilinear value at an
//! element's centre is off by about (kh)²/8 (8 % for the 80 Hz modes of the paper's plate on a
//! 24 × 24 mesh). The slopes come from the rotations, ∂w/∂r = x_r·(n × θ) (a fibre along the
//! director n turns with θ), and w is interpolated with the 12-term Adini–Clough–Melosh
//! polynomial in (r, s), which takes w, ∂w/∂r and ∂w/∂s at the four nodes and reproduces
//! every cubic in r and s:
//!
//! N_k = ⅛(1 + r₀)(1 + s₀)(2 + r₀ + s₀ − r² − s²), N_rk = ⅛ r_k (1 + r₀)²(r₀ − 1)(1 + s₀),
//! N_sk = ⅛ s_k (1 + r₀)(1 + s₀)²(s₀ − 1), with r₀ = r r_k, s₀ = s s_k.
//!
//! On a 9-node (MITC9) mesh every component is the element's biquadratic interpolation
//! Σ h_k(r, s) u_k, which already bends between nodes.

use crate::error::{FitError, inconsistent};
use lamdyn_fem::element::{ElementOrder, NODE_RS, bilinear_shape};
use lamdyn_fem::mesh::{Locator, Mesh, SurfacePoint};
use lamdyn_fem::vec3::{cross, dot, unit};
use lamdyn_frf::Channel;
use serde::{Deserialize, Serialize};

/// How a channel is placed on the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorMapping {
    /// The nearest point of the mid-surface, the displacement there interpolated with the
    /// element's shape functions: u(p) = Σ h_k(r, s) u_k.
    #[default]
    Surface,
    /// The nearest node's displacement.
    NearestNode,
}

/// Where channels go on a mesh: how, and how far from it they may lie.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPlacement {
    /// Largest distance from a channel's point to where it is placed, m.
    pub tolerance_m: f64,
    /// To the mid-surface or the nearest node.
    pub mapping: SensorMapping,
}

/// A channel on the mesh: response pᵀu, or a unit force along its direction distributed as p
/// (work-equivalent).
#[derive(Debug, Clone, PartialEq)]
pub struct Probe {
    /// The entries (dof, weight) of p over the 6-dof-per-node system (some weights may be 0).
    pub weights: Vec<(usize, f64)>,
    /// Distance from the channel's point to where it was placed, m.
    pub distance_m: f64,
}

impl Probe {
    /// A probe on one node's translations along `direction`.
    pub fn at_node(node: usize, direction: [f64; 3]) -> Self {
        Self {
            weights: (0..3).map(|c| (6 * node + c, direction[c])).collect(),
            distance_m: 0.0,
        }
    }

    /// The entries (dof, weight) of the probe's vector (a dof may appear more than once; the
    /// weights add).
    pub fn entries(&self) -> &[(usize, f64)] {
        &self.weights
    }

    /// pᵀ x for a vector over the dofs.
    pub fn dot(&self, x: impl Fn(usize) -> f64) -> f64 {
        self.weights
            .iter()
            .filter(|(_, w)| *w != 0.0)
            .map(|(d, w)| w * x(*d))
            .sum()
    }

    /// A probe along `direction` at a point of the mid-surface (module docs).
    pub fn on_surface(mesh: &Mesh, q: &SurfacePoint, direction: [f64; 3]) -> Self {
        if mesh.order() == ElementOrder::Quadratic {
            return Self {
                weights: q
                    .weights
                    .iter()
                    .flat_map(|&(n, h)| (0..3).map(move |c| (6 * n + c, h * direction[c])))
                    .collect(),
                distance_m: q.distance_m,
            };
        }
        let conn = mesh.corners(q.element);
        let x = conn.map(|n| mesh.nodes()[n]);
        let tangents = |r: f64, s: f64| {
            let (_, hr, hs) = bilinear_shape(r, s);
            let mut t = [[0.0; 3]; 2];
            for k in 0..4 {
                for c in 0..3 {
                    t[0][c] += hr[k] * x[k][c];
                    t[1][c] += hs[k] * x[k][c];
                }
            }
            t
        };
        let [r, s] = q.rs;
        let (h, _, _) = bilinear_shape(r, s);
        let [xr, xs] = tangents(r, s);
        let normal = unit(cross(xr, xs));
        let dn = dot(direction, normal);
        let mut weights = vec![(6 * conn[0], 0.0); 24];
        for k in 0..4 {
            let [rk, sk] = NODE_RS[k];
            let (r0, s0) = (r * rk, s * sk);
            let n_w = (1.0 + r0) * (1.0 + s0) * (2.0 + r0 + s0 - r * r - s * s) / 8.0;
            let n_r = rk * (1.0 + r0).powi(2) * (r0 - 1.0) * (1.0 + s0) / 8.0;
            let n_s = sk * (1.0 + r0) * (1.0 + s0).powi(2) * (s0 - 1.0) / 8.0;
            let [tr, ts] = tangents(rk, sk);
            let director = mesh.directors()[conn[k]];
            // w_r = x_r·(n × θ) = θ·(x_r × n).
            let (gr, gs) = (cross(tr, director), cross(ts, director));
            for c in 0..3 {
                weights[6 * k + c] = (
                    6 * conn[k] + c,
                    h[k] * direction[c] + (n_w - h[k]) * dn * normal[c],
                );
                weights[6 * k + 3 + c] = (6 * conn[k] + 3 + c, dn * (n_r * gr[c] + n_s * gs[c]));
            }
        }
        Self {
            weights,
            distance_m: q.distance_m,
        }
    }
}

/// One line on where the probes lie: the mapping and the largest distance from a channel's
/// point to its place on the mesh.
pub fn placement_line(mapping: SensorMapping, probes: &[Probe]) -> String {
    let largest = probes.iter().map(|p| p.distance_m).fold(0.0, f64::max);
    let to = match mapping {
        SensorMapping::Surface => "the mid-surface (shape functions)",
        SensorMapping::NearestNode => "the nearest nodes",
    };
    format!(
        "{} channels on {to}, at most {:.3} mm away",
        probes.len(),
        largest * 1e3
    )
}

/// Maps channels to the mesh's surface within `tolerance_m` ([`SensorMapping::Surface`]).
///
/// # Errors
/// As [`probes_with`].
pub fn probes(mesh: &Mesh, channels: &[Channel], tolerance_m: f64) -> Result<Vec<Probe>, FitError> {
    probes_with(mesh, channels, tolerance_m, SensorMapping::Surface)
}

/// Maps channels to the mesh: to the nearest point of the mid-surface or the nearest node,
/// refusing a channel farther than `tolerance_m` from it.
///
/// # Errors
/// [`FitError::Inconsistent`] naming the channel whose point is off the mesh.
pub fn probes_with(
    mesh: &Mesh,
    channels: &[Channel],
    tolerance_m: f64,
    mapping: SensorMapping,
) -> Result<Vec<Probe>, FitError> {
    let locator = Locator::new(mesh, tolerance_m);
    channels
        .iter()
        .map(|c| {
            let off = |reason: String| {
                inconsistent(
                    &format!("channel '{}'", c.name),
                    format!("{reason} (sensor off the mesh?)"),
                )
            };
            match mapping {
                SensorMapping::NearestNode => {
                    let node = locator
                        .locate_all(&[c.point_m])
                        .map_err(|e| off(e.to_string()))?[0];
                    let mut p = Probe::at_node(node, c.direction);
                    p.distance_m = locator.nearest(c.point_m).1;
                    Ok(p)
                }
                SensorMapping::Surface => {
                    if !c.point_m.iter().all(|v| v.is_finite()) {
                        return Err(off("not a finite point".into()));
                    }
                    let q = locator.on_surface(c.point_m);
                    if q.distance_m > tolerance_m {
                        let [x, y, z] = c.point_m;
                        return Err(off(format!(
                            "point at ({x}, {y}, {z}) m: {:.4e} m from the mid-surface (element \
                             {}), beyond the tolerance of {tolerance_m:.4e} m",
                            q.distance_m, q.element
                        )));
                    }
                    Ok(Probe::on_surface(mesh, &q, c.direction))
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lamdyn_fem::mesh::structured::RectangleSpec;

    fn flat(n: usize) -> Mesh {
        RectangleSpec::flat(0.9, 0.8, n, n).build().unwrap()
    }

    /// u_z = w(x, y) with rotations θ = (∂w/∂y, −∂w/∂x, 0) (so that n × θ = ∇w) at every node.
    fn field(mesh: &Mesh, w: impl Fn(f64, f64) -> [f64; 3]) -> Vec<f64> {
        mesh.nodes()
            .iter()
            .flat_map(|p| {
                let [v, wx, wy] = w(p[0], p[1]);
                [0.0, 0.0, v, wy, -wx, 0.0]
            })
            .collect()
    }

    /// A rigid rotation is reproduced at any point (the slopes' sign and the cubic terms
    /// cancel), and so is a cubic bending field that the bilinear interpolation misses.
    #[test]
    fn surface_probes_reproduce_rotations_and_cubic_bending() {
        let mesh = flat(6);
        let loc = Locator::new(&mesh, 1.0);
        type Field<'a> = &'a dyn Fn(f64, f64) -> [f64; 3];
        let cases: [(Field, &str); 2] = [
            (&|x, y| [0.3 * x - 0.2 * y + 0.1, 0.3, -0.2], "rigid"),
            (
                &|x, y| {
                    [
                        x * x * x - 2.0 * x * y * y,
                        3.0 * x * x - 2.0 * y * y,
                        -4.0 * x * y,
                    ]
                },
                "cubic",
            ),
        ];
        for (w, name) in cases {
            let u = field(&mesh, w);
            for p in [[0.01, 0.02, 0.0], [0.2123, -0.3111, 0.0], [-0.4, 0.35, 0.0]] {
                let q = loc.on_surface(p);
                let probe = Probe::on_surface(&mesh, &q, [0.0, 0.0, 1.0]);
                let got = probe.dot(|d| u[d]);
                let want = w(p[0], p[1])[0];
                assert!(
                    (got - want).abs() < 1e-12,
                    "{name} at {p:?}: {got} vs {want}"
                );
                let bilinear: f64 = q.weights.iter().map(|(n, h)| h * u[6 * n + 2]).sum();
                if name == "cubic" {
                    assert!((bilinear - want).abs() > 1e-5, "{name}: {bilinear} {want}");
                }
            }
        }
        // In-plane directions see the bilinear in-plane displacement only.
        let q = loc.on_surface([0.2, 0.1, 0.0]);
        let probe = Probe::on_surface(&mesh, &q, [1.0, 0.0, 0.0]);
        let u: Vec<f64> = mesh
            .nodes()
            .iter()
            .flat_map(|p| [2.0 * p[0] + p[1], 0.0, 5.0, 1.0, 1.0, 1.0])
            .collect();
        assert!((probe.dot(|d| u[d]) - 0.5).abs() < 1e-12);
    }
}
