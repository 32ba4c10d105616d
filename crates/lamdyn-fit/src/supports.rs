//! Grounded supports of the shell model: springs and dashpots that do not scale with the
//! laminate's modulus (foam blocks, bungee cords, the model file's node springs).
//!
//! A support acts on the displacement u_b = bᵀx of its point along one axis (a [`Probe`]):
//! K_s = Σ k b bᵀ and C_s = Σ c b bᵀ. In the basis of the free model's kept modes Φ
//! (K0 Φ = M Φ Λ, Φᵀ M Φ = I) they are dense m × m matrices K̃ = Φᵀ K_s Φ, C̃ = Φᵀ C_s Φ, and
//! the modal coordinates q at ω solve
//!
//! Z(ω) q = Φᵀ Q,   Z(ω) = s(ω) Λ + K̃ + iω C̃ − ω² I,
//!
//! one dense LU per line instead of the free model's diagonal ([`crate::synthesis`]).
//!
//! **The basis.** A support on a thin plate is stiff beside the plate's own static stiffness at
//! its point (a foam block under 4 mm glass), so the plate deforms locally around it, a shape
//! the free modes converge to slowly (measured in docs/fit.md, "Supports").
//! The basis is therefore the free modes plus one static shape per support group g
//! (a support and axis): x_g = (K0 − σM)⁻¹ f_g, f_g = Σ_{b ∈ g} w_b b with w_b the term's
//! stiffness (its damping where it has none), the force pattern of the group moved rigidly.
//! The shapes are M-orthogonalised against the modes and among themselves (dependent ones
//! dropped), and Rayleigh–Ritz on (K0, M) in that space makes K0 diagonal again: Φ, Λ above
//! are the Ritz vectors and values. The residual terms are taken against this basis.
//!
//! **A pole's modulus.** At a pole p (Laplace variable, responses e^{pt}; iω → p, −ω² → p²),
//! Z is singular: det(s Λ + R) = 0 with R = K̃ + p C̃ + p² I, linear in s. With R regular,
//! s = 1/ν for ν an eigenvalue of −R⁻¹Λ; rigid-body rows of Λ give ν = 0 (no finite s).
//! Without supports this is s = −p²/λ_r, the free model's E* = E_ref (f/f_r)² e^{2i asin ζ}.
//!
//! **Supports on the plan.** A support of the layered model
//! ([`lamdyn_layered::supports::PointSupport`]: a point as fractions of the plan, a patch,
//! k and c per global axis) is placed on the mid-surface: the plan's extent is that of the
//! mesh's nodes, each point of its patch goes to the mid-surface point nearest (x, y, z_n)
//! with z_n the height of the node nearest in plan, and acts there through the element's
//! shape functions ([`Probe::on_surface`]). The support's offset from the mid-surface to the
//! bottom surface (half the thickness) is left out: it couples the in-plane springs to the
//! rotations, a small term beside the normal springs of a resting part.

use crate::error::{FitError, inconsistent};
use crate::probe::Probe;
use faer::{Mat, MatRef, c64};
use lamdyn_fem::assembly::{Assembly, NodeSpring};
use lamdyn_fem::eigen::ModalSolution;
use lamdyn_fem::eigen::factor::LltFactor;
use lamdyn_fem::mesh::{Locator, Mesh};
use lamdyn_fem::sparse::symmetric_matmul;
use lamdyn_layered::supports::PointSupport;
use num_complex::Complex64;
use std::collections::BTreeMap;

/// One grounded spring and dashpot on the displacement bᵀx of a probe (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct GroundedSupport {
    /// Where and along what it acts.
    pub probe: Probe,
    /// Stiffness, N/m (N·m/rad on a rotation).
    pub stiffness_n_m: f64,
    /// Viscous damping, N·s/m (N·m·s/rad on a rotation).
    pub damping_n_s_m: f64,
    /// The group it belongs to (one support along one axis, or one dof of a node spring):
    /// the basis gets one static shape per group (module docs).
    pub group: usize,
}

impl GroundedSupport {
    /// The six springs of a node spring of the model file, one per dof with a stiffness.
    pub fn from_node_spring(spring: &NodeSpring) -> Vec<Self> {
        let k = [spring.translational_n_per_m, spring.rotational_nm_per_rad].concat();
        k.iter()
            .enumerate()
            .filter(|(_, k)| **k != 0.0)
            .map(|(c, &k)| Self {
                probe: Probe {
                    weights: vec![(6 * spring.node + c, 1.0)],
                    distance_m: 0.0,
                },
                stiffness_n_m: k,
                damping_n_s_m: 0.0,
                group: 6 * spring.node + c,
            })
            .collect()
    }

    /// The supports of the layered model placed on the shell `mesh` (module docs): one term per
    /// patch point and axis with a stiffness or damping, each with its share of the patch.
    ///
    /// # Errors
    /// [`FitError::Layered`] for an invalid support (named `supports[i]`);
    /// [`FitError::Inconsistent`] for a point the mid-surface does not reach in plan.
    pub fn on_plan(mesh: &Mesh, supports: &[PointSupport]) -> Result<Vec<Self>, FitError> {
        let (lo, hi) = plan_extent(mesh);
        let reach = 0.01 * (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
        let locator = Locator::new(mesh, f64::INFINITY);
        let mut out = Vec::new();
        for (i, s) in supports.iter().enumerate() {
            s.check(i)?;
            let points = s.plan_points(lo, hi);
            let share = 1.0 / points.len() as f64;
            for [x, y] in points {
                let at = locator.on_surface([x, y, plan_height(mesh, [x, y])]);
                let placed = surface_position(mesh, &at.weights);
                let off = (placed[0] - x).hypot(placed[1] - y);
                if off > reach {
                    return Err(inconsistent(
                        "shell model's supports",
                        format!(
                            "supports[{i}]: the mid-surface does not reach ({x:.4}, {y:.4}) m in \
                             plan (nearest point {off:.4} m away; its patch {:?} m beyond the \
                             part?)",
                            s.patch_m
                        ),
                    ));
                }
                for axis in 0..3 {
                    let (k, c) = (s.stiffness_n_m[axis], s.damping_n_s_m[axis]);
                    if k == 0.0 && c == 0.0 {
                        continue;
                    }
                    let mut direction = [0.0; 3];
                    direction[axis] = 1.0;
                    out.push(Self {
                        probe: Probe::on_surface(mesh, &at, direction),
                        stiffness_n_m: k * share,
                        damping_n_s_m: c * share,
                        group: 3 * i + axis,
                    });
                }
            }
        }
        Ok(out)
    }
}

/// The plan's extent of the mesh's nodes: lowest and highest x and y, m.
fn plan_extent(mesh: &Mesh) -> ([f64; 2], [f64; 2]) {
    mesh.nodes().iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

/// The height z of the node nearest the plan point `xy` (distance in plan alone).
fn plan_height(mesh: &Mesh, xy: [f64; 2]) -> f64 {
    mesh.nodes()
        .iter()
        .min_by(|a, b| {
            let d = |p: &&[f64; 3]| (p[0] - xy[0]).hypot(p[1] - xy[1]);
            d(a).total_cmp(&d(b))
        })
        .map_or(0.0, |p| p[2])
}

/// Σ h_k x_k over a surface point's weights.
fn surface_position(mesh: &Mesh, weights: &[(usize, f64)]) -> [f64; 3] {
    let mut x = [0.0; 3];
    for &(n, h) in weights {
        for c in 0..3 {
            x[c] += h * mesh.nodes()[n][c];
        }
    }
    x
}

/// The supports in the free model's modal basis: K̃ = Φᵀ K_s Φ and C̃ = Φᵀ C_s Φ (m × m).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ModalSupports {
    pub(crate) stiffness: Mat<f64>,
    pub(crate) damping: Mat<f64>,
}

impl ModalSupports {
    /// Projects `supports` on the columns of `shapes` (n_dofs × m).
    pub(crate) fn project(
        shapes: MatRef<'_, f64>,
        supports: &[GroundedSupport],
    ) -> Result<Self, FitError> {
        let (n, m) = (shapes.nrows(), shapes.ncols());
        let mut stiffness = Mat::zeros(m, m);
        let mut damping = Mat::zeros(m, m);
        for (i, s) in supports.iter().enumerate() {
            let (k, c) = (s.stiffness_n_m, s.damping_n_s_m);
            if !(k.is_finite() && c.is_finite() && k >= 0.0 && c >= 0.0) {
                return Err(inconsistent(
                    "modal supports",
                    format!("support {i}: stiffness {k} and damping {c} must be finite, >= 0"),
                ));
            }
            if let Some((d, _)) = s.probe.entries().iter().find(|(d, _)| *d >= n) {
                return Err(inconsistent(
                    "modal supports",
                    format!("support {i} acts on dof {d}; the model has {n}"),
                ));
            }
            let b: Vec<f64> = (0..m).map(|r| s.probe.dot(|d| shapes[(d, r)])).collect();
            for r in 0..m {
                for t in 0..m {
                    stiffness[(r, t)] += k * b[r] * b[t];
                    damping[(r, t)] += c * b[r] * b[t];
                }
            }
        }
        Ok(Self { stiffness, damping })
    }

    /// Z(ω) = s Λ + K̃ + iω C̃ − ω² I (module docs).
    fn dynamic_stiffness(&self, lambda: &[f64], omega: f64, s: Complex64) -> Mat<c64> {
        let m = lambda.len();
        Mat::from_fn(m, m, |r, t| {
            let mut z = c64::new(self.stiffness[(r, t)], omega * self.damping[(r, t)]);
            if r == t {
                let diag = s * lambda[r] - omega * omega;
                z += c64::new(diag.re, diag.im);
            }
            z
        })
    }

    /// The modal coordinates Z(ω)⁻¹ F (m × columns of `forces`): LU with partial pivoting,
    /// sequential, so that the sums are the same on any thread count (the lines are the
    /// parallel work).
    pub(crate) fn solve(
        &self,
        lambda: &[f64],
        omega: f64,
        s: Complex64,
        forces: MatRef<'_, f64>,
    ) -> Mat<c64> {
        let rhs = Mat::from_fn(forces.nrows(), forces.ncols(), |r, j| {
            c64::new(forces[(r, j)], 0.0)
        });
        solve_sequential(self.dynamic_stiffness(lambda, omega, s), rhs)
    }

    /// The undamped modes at s = 1: eigenvalues of Λ + K̃ (rad²/s², increasing) and each
    /// one's share of its strain energy in the laminate, vᵀΛv / vᵀ(Λ + K̃)v (the rest is in the
    /// supports); `None` if the eigensolver fails.
    pub(crate) fn undamped(&self, lambda: &[f64]) -> Option<Vec<(f64, f64)>> {
        let m = lambda.len();
        let a = Mat::from_fn(m, m, |r, t| {
            self.stiffness[(r, t)] + if r == t { lambda[r] } else { 0.0 }
        });
        let evd = a.self_adjoint_eigen(faer::Side::Lower).ok()?;
        let (u, w) = (evd.U(), evd.S().column_vector());
        Some(
            (0..m)
                .map(|k| {
                    let laminate: f64 = (0..m).map(|r| lambda[r] * u[(r, k)] * u[(r, k)]).sum();
                    (w[k], if w[k] > 0.0 { laminate / w[k] } else { 0.0 })
                })
                .collect(),
        )
    }

    /// Every finite s with det(s Λ + K̃ + p C̃ + p² I) = 0 (module docs); empty if R is
    /// singular or the eigensolver fails.
    pub(crate) fn pole_scales(&self, lambda: &[f64], pole: Complex64) -> Vec<Complex64> {
        let m = lambda.len();
        let r = Mat::from_fn(m, m, |a, b| {
            let mut v = pole * self.damping[(a, b)] + self.stiffness[(a, b)];
            if a == b {
                v += pole * pole;
            }
            c64::new(v.re, v.im)
        });
        let lam = Mat::from_fn(m, m, |a, b| {
            c64::new(if a == b { -lambda[a] } else { 0.0 }, 0.0)
        });
        let t = solve_sequential(r, lam);
        if (0..m).any(|a| (0..m).any(|b| !(t[(a, b)].re.is_finite() && t[(a, b)].im.is_finite()))) {
            return Vec::new();
        }
        let top = lambda.iter().cloned().fold(0.0, f64::max);
        // Rigid rows give ν at rounding, about 2e-16 top/|p|²; a genuine ν is λ_r/|p|².
        let floor = 1e-12 * top / pole.norm_sqr();
        lamdyn_layered::seq::eigenvalues(t.as_ref())
            .into_iter()
            .filter(|nu| nu.norm() > floor)
            .map(|nu| 1.0 / nu)
            .collect()
    }
}

/// A⁻¹ B by LU with partial pivoting, sequential: the same bits on any thread count.
fn solve_sequential(mut a: Mat<c64>, mut b: Mat<c64>) -> Mat<c64> {
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::lu::partial_pivoting::{factor, solve};
    let m = a.nrows();
    let (mut perm, mut perm_inv) = (vec![0usize; m], vec![0usize; m]);
    let par = faer::Par::Seq;
    let mut mem = MemBuffer::new(StackReq::any_of(&[
        factor::lu_in_place_scratch::<usize, c64>(m, m, par, Default::default()),
        solve::solve_in_place_scratch::<usize, c64>(m, b.ncols(), par),
    ]));
    let stack = MemStack::new(&mut mem);
    let (_, row_perm) = factor::lu_in_place(
        a.as_mut(),
        &mut perm,
        &mut perm_inv,
        par,
        stack,
        Default::default(),
    );
    solve::solve_in_place(a.as_ref(), a.as_ref(), row_perm, b.as_mut(), par, stack);
    b
}

/// Relative size (in the M-norm) below which a static shape adds nothing new to the basis.
const DEPENDENT: f64 = 1e-10;

/// The free modes of `sol` with one static shape per support group, Rayleigh–Ritz on (K0, M)
/// (module docs): the Ritz values (rad²/s², increasing) and M-orthonormal vectors.
///
/// # Errors
/// Factorization and eigensolver failures.
pub(crate) fn ritz_basis(
    asm: &Assembly,
    sol: &ModalSolution,
    supports: &[GroundedSupport],
    factor: &LltFactor<'_>,
) -> Result<(Vec<f64>, Mat<f64>), FitError> {
    let n = asm.n_dofs();
    let phi = sol.shapes.as_ref();
    let mut x = group_forces(n, supports);
    factor.solve_in_place(x.as_mut());
    let mut mx = Mat::zeros(n, x.ncols());
    symmetric_matmul(asm.mass.as_ref(), x.as_ref(), mx.as_mut());
    let seq = lamdyn_layered::seq::mul;
    x -= seq(phi, seq(phi.transpose(), mx.as_ref()).as_ref());
    symmetric_matmul(asm.mass.as_ref(), x.as_ref(), mx.as_mut());
    let gram = seq(x.transpose(), mx.as_ref());
    let evd = gram
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| inconsistent("modal supports", format!("static shapes' Gram: {e:?}")))?;
    let top = (0..x.ncols()).map(|k| evd.S()[k]).fold(0.0, f64::max);
    let kept: Vec<usize> = (0..x.ncols())
        .filter(|&k| evd.S()[k] > DEPENDENT * top)
        .collect();
    let u = evd.U();
    let x = Mat::from_fn(n, kept.len(), |d, j| {
        let k = kept[j];
        (0..x.ncols()).map(|c| x[(d, c)] * u[(c, k)]).sum::<f64>() / evd.S()[k].sqrt()
    });
    let v = Mat::from_fn(n, phi.ncols() + x.ncols(), |d, j| {
        if j < phi.ncols() {
            phi[(d, j)]
        } else {
            x[(d, j - phi.ncols())]
        }
    });
    let mut kv = Mat::zeros(n, v.ncols());
    symmetric_matmul(asm.stiffness.as_ref(), v.as_ref(), kv.as_mut());
    let kr = seq(v.transpose(), kv.as_ref());
    let kr = Mat::from_fn(kr.nrows(), kr.ncols(), |a, b| {
        0.5 * (kr[(a, b)] + kr[(b, a)])
    });
    let evd = kr
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| inconsistent("modal supports", format!("Ritz eigensolver: {e:?}")))?;
    let lambda = (0..kr.nrows()).map(|k| evd.S()[k]).collect();
    Ok((lambda, seq(v.as_ref(), evd.U())))
}

/// The force patterns f_g of the support groups (module docs), n × groups: the static shapes
/// once solved with K0 − σM.
fn group_forces(n: usize, supports: &[GroundedSupport]) -> Mat<f64> {
    let mut groups: BTreeMap<usize, Vec<&GroundedSupport>> = BTreeMap::new();
    for s in supports {
        groups.entry(s.group).or_default().push(s);
    }
    let mut f = Mat::zeros(n, groups.len());
    for (j, members) in groups.values().enumerate() {
        let stiff = members.iter().any(|s| s.stiffness_n_m > 0.0);
        for s in members {
            let w = if stiff {
                s.stiffness_n_m
            } else {
                s.damping_n_s_m
            };
            for &(d, b) in s.probe.entries() {
                if d < n {
                    f[(d, j)] += w * b;
                }
            }
        }
    }
    f
}
