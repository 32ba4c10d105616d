//! Free (or supported) vibration modes: K φ = λ M φ, λ = ω² in rad²/s².
//!
//! [`solve_modes`] assembles nothing: it takes an [`Assembly`], factorizes K − σM once with a
//! shift σ below the spectrum (negative, so that LLᵀ applies even with six rigid-body modes),
//! runs the shift-invert [`lanczos::lanczos`] for the lowest modes, and proves the result:
//!
//! - mass normalisation Φᵀ M Φ = I (Lanczos keeps its basis M-orthonormal);
//! - residuals ‖K φ − λ M φ‖₂ / (‖K‖₁ ‖φ‖₂) per mode;
//! - a Sturm sequence count: the number of negative pivots of LDLᵀ(K − cM) at a cut-off c in
//!   the gap above the highest returned mode equals the number of modes returned, so none was
//!   missed. If it does not, the missing modes are searched for in the M-orthogonal complement
//!   of the found ones (up to three times) before [`FemError::SturmMismatch`] is returned.
//!
//! Rigid-body modes are flagged when λ ≤ 1e-6 times the largest returned eigenvalue.

pub mod factor;
pub mod lanczos;

use crate::assembly::Assembly;
use crate::error::FemError;
use factor::{FactorPlan, LltFactor};
use faer::sparse::SparseColMatRef;
use faer::{Mat, MatMut, MatRef, Par};
use lanczos::{LanczosParams, ShiftInvert, lanczos};
use serde::Serialize;
use std::time::Instant;

/// How the shift σ of K − σM is chosen.
///
/// A shift much closer to zero than the first elastic eigenvalue λ_e leaves K − σM nearly
/// singular along the rigid-body modes and costs digits (residuals grow from 1e-17 at σ ≈ −λ_e
/// to 1e-13 at σ = −1e-4 λ_e on the roof plate); a shift far below λ_e squeezes the θ spectrum
/// and slows convergence (none at −1e4 λ_e). [`Shift::Auto`] starts at −(2π·10 Hz)² and, when
/// the first elastic eigenvalue found lies outside [|σ|/10, 1000|σ|], factorizes again at
/// σ = −λ_e.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shift {
    /// Start at −(2π·10 Hz)², re-shift once to −λ_e if it is far off (see above).
    Auto,
    /// σ = −(2π f)² for the given frequency in Hz; choose f near the first elastic mode.
    BelowHz(f64),
    /// A shift in rad²/s² (must lie below the lowest eigenvalue).
    Value(f64),
}

/// Settings of [`solve_modes`].
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub struct ModalParams {
    /// Number of lowest modes wanted (rigid-body modes included).
    pub modes: usize,
    /// The shift.
    pub shift: Shift,
    /// Ritz residual tolerance (relative to θ).
    pub tolerance: f64,
    /// Lanczos basis size (default: wanted + 10 blocks: 96 columns for 20 modes, enough to
    /// converge without a restart on the plates of the benchmark; memory 16·n·size bytes).
    pub subspace: Option<usize>,
    /// Lanczos block size (columns per solve; default 8).
    pub block: usize,
    /// Restarts allowed per Lanczos run.
    pub max_restarts: usize,
    /// Run the Sturm sequence check (one more factorization).
    pub sturm_check: bool,
    /// Seed of the start vector.
    pub seed: u64,
    /// Parallelism of faer's dense products (default sequential: on this project's 2-core
    /// machines its thread pool slowed the Lanczos stage by a third; the sparse products and
    /// the split block solves run on rayon instead, see [`factor`]).
    pub par: Par,
}

impl ModalParams {
    /// The `modes` lowest modes with default settings.
    pub fn lowest(modes: usize) -> Self {
        Self {
            modes,
            shift: Shift::Auto,
            tolerance: 1e-10,
            subspace: None,
            block: 8,
            max_restarts: 100,
            sturm_check: true,
            seed: 2026,
            par: Par::Seq,
        }
    }

    /// The same with another shift.
    pub fn with_shift(mut self, shift: Shift) -> Self {
        self.shift = shift;
        self
    }

    /// The same with or without the Sturm check.
    pub fn with_sturm_check(mut self, on: bool) -> Self {
        self.sturm_check = on;
        self
    }

    /// The same with another parallelism.
    pub fn with_par(mut self, par: Par) -> Self {
        self.par = par;
        self
    }
}

/// One mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Mode {
    /// Eigenvalue λ = ω², rad²/s².
    pub eigenvalue: f64,
    /// Natural frequency f = √λ / 2π, Hz (0 for λ ≤ 0).
    pub freq_hz: f64,
    /// A rigid-body mode (λ ≈ 0).
    pub rigid: bool,
    /// ‖K φ − λ M φ‖₂ / (‖K‖₁ ‖φ‖₂).
    pub residual: f64,
}

/// The Sturm sequence check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SturmCheck {
    /// Cut-off c, rad²/s², in the gap above the highest returned mode.
    pub cutoff: f64,
    /// Negative pivots of LDLᵀ(K − cM): eigenvalues below c.
    pub count: usize,
    /// Modes returned (all below c).
    pub returned: usize,
}

/// Work done.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SolveInfo {
    /// Shift σ used, rad²/s².
    pub shift: f64,
    /// Dofs.
    pub n_dofs: usize,
    /// Entries of the Cholesky factor.
    pub factor_nnz: usize,
    /// Lanczos restarts (all runs).
    pub restarts: usize,
    /// Applications of (K − σM)⁻¹M.
    pub applications: usize,
    /// Seconds spent in the symbolic analysis, numeric factorization, Lanczos and Sturm check.
    pub seconds: [f64; 4],
}

/// Modes, mass-normalised shapes and the checks.
#[derive(Debug, Clone)]
pub struct ModalSolution {
    /// The modes, lowest first.
    pub modes: Vec<Mode>,
    /// Mass-normalised shapes, n_dofs × modes (Φᵀ M Φ = I).
    pub shapes: Mat<f64>,
    /// The Sturm check, if run.
    pub sturm: Option<SturmCheck>,
    /// Work done.
    pub info: SolveInfo,
}

/// Progress reports from a long solve.
pub trait Progress {
    /// A stage starts ("symbolic analysis", "factorization", "Lanczos", "Sturm check").
    fn stage(&self, _name: &str) {}
    /// Lanczos: `converged` of `wanted` modes converged.
    fn converged(&self, _converged: usize, _wanted: usize) {}
}

/// No progress output.
pub struct Silent;
impl Progress for Silent {}

struct Operator<'a> {
    mass: SparseColMatRef<'a, usize, f64>,
    factor: &'a LltFactor<'a>,
}

impl ShiftInvert for Operator<'_> {
    fn dim(&self) -> usize {
        self.mass.nrows()
    }
    fn mass(&self, x: MatRef<'_, f64>, y: MatMut<'_, f64>) {
        crate::sparse::symmetric_matmul(self.mass, x, y);
    }
    fn solve(&self, x: MatMut<'_, f64>) {
        self.factor.solve_in_place(x);
    }
}

/// The lowest `params.modes` modes of the assembled model (K0 plus supports, M).
///
/// # Errors
/// [`FemError::InvalidParameter`] for zero modes or more modes than dofs allow;
/// [`FemError::Factorization`] when K − σM is not positive definite (σ not below the spectrum,
/// or a mechanism); [`FemError::NoConvergence`]; [`FemError::SturmMismatch`].
pub fn solve_modes(
    assembly: &Assembly,
    params: &ModalParams,
    progress: &dyn Progress,
) -> Result<ModalSolution, FemError> {
    let n = assembly.n_dofs();
    let wanted = params.modes;
    if wanted == 0 || wanted + 2 >= n / 2 {
        return Err(FemError::InvalidParameter {
            context: "modal solver".into(),
            field: "modes".into(),
            value: wanted.to_string(),
            requirement: format!(
                "must lie in 1..{} for this mesh ({n} dofs)",
                (n / 2).saturating_sub(2)
            ),
        });
    }
    let mut sigma = match params.shift {
        Shift::Auto => -(2.0 * std::f64::consts::PI * 10.0).powi(2),
        Shift::BelowHz(f) => -(2.0 * std::f64::consts::PI * f).powi(2),
        Shift::Value(s) => s,
    };
    let mut seconds = [0.0; 4];
    let clock = Instant::now();
    progress.stage("symbolic analysis");
    let plan = FactorPlan::new(&assembly.pattern)?;
    seconds[0] = clock.elapsed().as_secs_f64();

    let k_vals = assembly.total_stiffness_values(1.0);
    let sym = assembly.stiffness.symbolic();
    let k_mat = SparseColMatRef::new(sym, &k_vals);
    let k_norm = one_norm(k_mat);
    // Two extra modes locate the gap above the last returned one.
    let extra = 2;
    let lanczos_params = |want: usize, seed: u64| LanczosParams {
        wanted: want,
        subspace: params.subspace.unwrap_or(want + 10 * params.block.max(1)),
        block: params.block,
        tolerance: params.tolerance,
        max_restarts: params.max_restarts,
        seed,
        par: params.par,
    };
    // Exact rigid-body modes of a free model are deflated analytically: locked in the Lanczos
    // basis, reported with their Rayleigh quotients.
    let (x_rigid, mx_rigid) = free_rigid_modes(assembly, k_mat, k_norm)
        .unwrap_or_else(|| (Mat::zeros(n, 0), Mat::zeros(n, 0)));
    let n_rigid = x_rigid.ncols();
    let elastic_wanted = wanted.saturating_sub(n_rigid);
    let (mut restarts, mut applications) = (0, 0);
    let mut reshifted = false;
    let (factor, out) = loop {
        let clock = Instant::now();
        progress.stage("factorization");
        let shifted = assembly.shifted_values(&k_vals, sigma);
        let factor = plan.llt(
            SparseColMatRef::new(sym, &shifted),
            sigma,
            params.block.max(1),
        )?;
        seconds[1] += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        progress.stage("Lanczos");
        let op = Operator {
            mass: assembly.mass.as_ref(),
            factor: &factor,
        };
        let out = lanczos(
            &op,
            lanczos_params(elastic_wanted + extra, params.seed),
            x_rigid.as_ref(),
            mx_rigid.as_ref(),
            &mut |c| progress.converged((c + n_rigid).min(wanted), wanted),
        );
        restarts += out.restarts;
        applications += out.applications;
        seconds[2] += clock.elapsed().as_secs_f64();
        if params.shift == Shift::Auto && !reshifted {
            if let Some(le) = first_elastic(&out, sigma) {
                let ratio = le / sigma.abs();
                if !(0.1..=1000.0).contains(&ratio) || out.converged < elastic_wanted + extra {
                    sigma = -le;
                    reshifted = true;
                    continue;
                }
            }
        }
        check_converged(&out, elastic_wanted + extra)?;
        break (factor, out);
    };
    let op = Operator {
        mass: assembly.mass.as_ref(),
        factor: &factor,
    };
    let mut found = Found::default();
    found.push_rigid(x_rigid.as_ref(), k_mat);
    found.push(&out, sigma);

    let clock = Instant::now();
    let mut sturm = None;
    let mut returned = found.returned_count(wanted);
    if params.sturm_check {
        progress.stage("Sturm check");
        for round in 0..4 {
            let cutoff = found.cutoff(returned);
            let a = assembly.shifted_values(&k_vals, cutoff);
            let count = plan.negative_pivots(SparseColMatRef::new(sym, &a), cutoff)?;
            sturm = Some(SturmCheck {
                cutoff,
                count,
                returned,
            });
            if count == returned {
                break;
            }
            if round == 3 || count < returned {
                return Err(FemError::SturmMismatch {
                    cutoff,
                    count,
                    returned,
                });
            }
            // Search the complement of what was found for the missed modes.
            let missing = count - returned;
            let (x, mx) = found.basis(&op);
            let more = lanczos(
                &op,
                lanczos_params(missing + extra, params.seed + 1 + round as u64),
                x.as_ref(),
                mx.as_ref(),
                &mut |_| {},
            );
            restarts += more.restarts;
            applications += more.applications;
            check_converged(&more, missing + extra)?;
            found.push(&more, sigma);
            returned = found.returned_count(wanted);
        }
    }
    seconds[3] = clock.elapsed().as_secs_f64();

    let (modes, shapes) = found.finish(returned, k_mat, k_norm, assembly);
    Ok(ModalSolution {
        modes,
        shapes,
        sturm,
        info: SolveInfo {
            shift: sigma,
            n_dofs: n,
            factor_nnz: plan.factor_nnz(),
            restarts,
            applications,
            seconds,
        },
    })
}

fn check_converged(out: &lanczos::LanczosOutput, wanted: usize) -> Result<(), FemError> {
    if out.converged < wanted {
        return Err(FemError::NoConvergence {
            converged: out.converged,
            wanted,
            restarts: out.restarts,
            max_residual: out.residuals.iter().cloned().fold(0.0, |a: f64, r| {
                if r.is_nan() { f64::NAN } else { a.max(r) }
            }),
        });
    }
    Ok(())
}

/// Eigenpairs found so far, kept sorted by eigenvalue.
#[derive(Default)]
struct Found {
    lambda: Vec<f64>,
    vectors: Vec<Vec<f64>>,
}

impl Found {
    fn push(&mut self, out: &lanczos::LanczosOutput, sigma: f64) {
        for (i, th) in out.theta.iter().enumerate() {
            self.lambda.push(sigma + 1.0 / th);
            self.vectors
                .push(out.vectors.col(i).iter().copied().collect());
        }
        self.sort();
    }

    /// Adds M-orthonormal rigid-body vectors with their Rayleigh quotients xᵀKx.
    fn push_rigid(&mut self, x: MatRef<'_, f64>, k: SparseColMatRef<'_, usize, f64>) {
        if x.ncols() == 0 {
            return;
        }
        let mut kx = Mat::zeros(x.nrows(), x.ncols());
        crate::sparse::symmetric_matmul(k, x, kx.as_mut());
        for j in 0..x.ncols() {
            let q: f64 = (0..x.nrows()).map(|i| x[(i, j)] * kx[(i, j)]).sum();
            self.lambda.push(q);
            self.vectors.push(x.col(j).iter().copied().collect());
        }
        self.sort();
    }

    fn sort(&mut self) {
        let mut idx: Vec<usize> = (0..self.lambda.len()).collect();
        idx.sort_by(|&a, &b| self.lambda[a].total_cmp(&self.lambda[b]));
        self.lambda = idx.iter().map(|&i| self.lambda[i]).collect();
        self.vectors = idx
            .iter()
            .map(|&i| std::mem::take(&mut self.vectors[i]))
            .collect();
    }

    /// How many to return: `wanted`, extended over any cluster that `wanted` would split
    /// (relative gap below 1e-6), so that the Sturm cut-off lies in a real gap.
    fn returned_count(&self, wanted: usize) -> usize {
        let mut r = wanted.min(self.lambda.len());
        while r < self.lambda.len() && r > 0 && gap(self.lambda[r - 1], self.lambda[r]) < 1e-6 {
            r += 1;
        }
        r
    }

    /// A cut-off halfway between the last returned eigenvalue and the next found one.
    fn cutoff(&self, returned: usize) -> f64 {
        let last = self.lambda[returned - 1];
        match self.lambda.get(returned) {
            Some(next) => 0.5 * (last + next),
            None => last + 1e-6 * last.abs().max(1.0),
        }
    }

    fn basis(&self, op: &Operator<'_>) -> (Mat<f64>, Mat<f64>) {
        let n = op.dim();
        let x = Mat::from_fn(n, self.vectors.len(), |i, j| self.vectors[j][i]);
        let mut mx = Mat::zeros(n, x.ncols());
        op.mass(x.as_ref(), mx.as_mut());
        (x, mx)
    }

    fn finish(
        self,
        returned: usize,
        k: SparseColMatRef<'_, usize, f64>,
        k_norm: f64,
        asm: &Assembly,
    ) -> (Vec<Mode>, Mat<f64>) {
        let n = k.nrows();
        let shapes = Mat::from_fn(n, returned, |i, j| self.vectors[j][i]);
        let mut kx = Mat::zeros(n, returned);
        crate::sparse::symmetric_matmul(k, shapes.as_ref(), kx.as_mut());
        let mut mx = Mat::zeros(n, returned);
        crate::sparse::symmetric_matmul(asm.mass.as_ref(), shapes.as_ref(), mx.as_mut());
        let top = self.lambda[..returned].iter().cloned().fold(0.0, f64::max);
        let modes = (0..returned)
            .map(|j| {
                let lam = self.lambda[j];
                let r = (0..n)
                    .map(|i| (kx[(i, j)] - lam * mx[(i, j)]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let xn = shapes.col(j).norm_l2();
                Mode {
                    eigenvalue: lam,
                    freq_hz: lam.max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                    rigid: lam.abs() <= 1e-6 * top,
                    residual: r / (k_norm * xn),
                }
            })
            .collect();
        (modes, shapes)
    }
}

/// The six rigid-body modes of a free model, M-orthonormal, with M times them; `None` when
/// supports hold the model or K does not annihilate them to 1e-9 (relative to ‖K‖₁).
///
/// Translations e_a at every node; rotations about axis e_a through the centroid c:
/// u = e_a × (x − c), θ = e_a.
fn free_rigid_modes(
    asm: &Assembly,
    k: SparseColMatRef<'_, usize, f64>,
    k_norm: f64,
) -> Option<(Mat<f64>, Mat<f64>)> {
    if !asm.springs.is_empty() {
        return None;
    }
    let nodes = &asm.nodes;
    let n = 6 * nodes.len();
    let mut c = [0.0; 3];
    for p in nodes {
        for a in 0..3 {
            c[a] += p[a] / nodes.len() as f64;
        }
    }
    let r = Mat::from_fn(n, 6, |row, col| {
        let (node, comp) = (row / 6, row % 6);
        let d = crate::vec3::sub(nodes[node], c);
        match (col, comp) {
            (a, cc) if a < 3 => {
                if cc == a {
                    1.0
                } else {
                    0.0
                }
            }
            (a, cc) if cc < 3 => {
                let mut axis = [0.0; 3];
                axis[a - 3] = 1.0;
                crate::vec3::cross(axis, d)[cc]
            }
            (a, cc) => {
                if cc - 3 == a - 3 {
                    1.0
                } else {
                    0.0
                }
            }
        }
    });
    let mut kr = Mat::zeros(n, 6);
    crate::sparse::symmetric_matmul(k, r.as_ref(), kr.as_mut());
    for j in 0..6 {
        if kr.col(j).norm_l2() > 1e-9 * k_norm * r.col(j).norm_l2() {
            return None;
        }
    }
    let mut mr = Mat::zeros(n, 6);
    crate::sparse::symmetric_matmul(asm.mass.as_ref(), r.as_ref(), mr.as_mut());
    let g = r.transpose() * &mr;
    let g = Mat::from_fn(6, 6, |i, j| 0.5 * (g[(i, j)] + g[(j, i)]));
    let l = g.llt(faer::Side::Lower).ok()?;
    // X = R L⁻ᵀ, M X = (M R) L⁻ᵀ.
    let mut linv_t = Mat::<f64>::identity(6, 6);
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(
        l.L().transpose(),
        linv_t.as_mut(),
        Par::Seq,
    );
    Some((&r * &linv_t, &mr * &linv_t))
}

/// The first elastic eigenvalue among the Ritz values (converged or not): the smallest above
/// 1e-6 times the largest.
fn first_elastic(out: &lanczos::LanczosOutput, sigma: f64) -> Option<f64> {
    let lambda: Vec<f64> = out
        .theta
        .iter()
        .filter(|t| **t > 0.0)
        .map(|t| sigma + 1.0 / t)
        .collect();
    let top = lambda.iter().cloned().fold(0.0, f64::max);
    lambda
        .into_iter()
        .filter(|l| *l > 1e-6 * top)
        .fold(None, |m: Option<f64>, l| Some(m.map_or(l, |m| m.min(l))))
}

fn gap(a: f64, b: f64) -> f64 {
    (b - a).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// ‖A‖₁: largest absolute column sum.
fn one_norm(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.val_of_col(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}
