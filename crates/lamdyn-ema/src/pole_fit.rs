//! Levenberg–Marquardt on the poles of the residue problem ([`crate::projection`]), the
//! residues eliminated: the step the refinement ([`crate::lsfd::refined_poles`]) and the local
//! refits ([`crate::local_refit`]) share.

use crate::projection::LineSamples;
use faer::Mat;
use faer::linalg::solvers::Solve;
use num_complex::Complex64;

/// The relative reduction of the sum of squares that the Levenberg–Marquardt steps stop below
/// where the residual is not noise-like: rounding's share of it (a few thousand squared
/// residuals summed in f64).
const ROUNDING: f64 = 1e-12;

/// How far a step may still move the parameters when the steps stop, in their noise standard
/// deviations ([`converged_share`]).
const STEP_IN_SD: f64 = 0.01;

/// The share of the sum of squares that a step's promised reduction must exceed for the
/// Levenberg–Marquardt steps to go on, on a problem of `dof` degrees of freedom (real residuals
/// less unknowns): rounding's share ([`ROUNDING`]) or, where larger, the reduction of a step of
/// [`STEP_IN_SD`] noise standard deviations. A Gauss–Newton step δ promises δᵀJᵀJδ, and with the
/// residual variance σ² = cost/dof the parameters' covariance is σ²(JᵀJ)⁻¹, so the promise is
/// σ² times the step's squared length in standard deviations: below STEP_IN_SD² cost/dof what
/// is left to move is a hundredth of the noise's part of the error. On noise-free curves the
/// cost, and with it the bound, goes to zero and the steps go to rounding.
pub(crate) fn converged_share(dof: usize) -> f64 {
    ROUNDING.max(STEP_IN_SD * STEP_IN_SD / dof.max(1) as f64)
}

/// Levenberg–Marquardt on the poles' parameters ([`pole_parameters`]) from `poles`, minimising
/// the residual sum of squares of the residue problem on `samples` with the residues eliminated
/// (its exact normal equations: [`crate::projection::Projection::normal_equations`]), at most
/// `iterations` steps (`on_iteration(k, max)` as step k starts); the refined poles, or None
/// where the residue problem fails at the start.
pub(crate) fn levenberg_marquardt(
    samples: &LineSamples,
    poles: &[Complex64],
    iterations: usize,
    on_iteration: &dyn Fn(usize, usize),
) -> Option<Vec<Complex64>> {
    let mut u = pole_parameters(poles);
    let mut at = samples.project(&to_poles(&u))?;
    let mut cost = at.cost();
    let mut lambda = 1e-3;
    let p = u.len();
    let n = poles.len();
    let dof =
        (samples.curves() * samples.rows().saturating_sub(samples.unknowns(n))).saturating_sub(p);
    let converged = converged_share(dof);
    for k in 0..iterations {
        on_iteration(k + 1, iterations);
        let normal = at.normal_equations(samples);
        let (jtj, jtr) = (normal.weighted(|_| 1.0), normal.gradient);
        let mut improved = false;
        for _ in 0..8 {
            let step = marquardt_step(&jtj, |a| jtr[(a, 0)], lambda);
            // The Gauss–Newton model's reduction −δᵀJᵀr (within a factor 2 of its exact
            // value); it only shrinks as λ grows. Below `converged` the poles have converged.
            let promised: f64 = (0..p).map(|a| -jtr[(a, 0)] * step[(a, 0)]).sum();
            if promised.is_finite() && promised <= converged * cost {
                return Some(to_poles(&u));
            }
            let trial: Vec<f64> = (0..p).map(|a| u[a] + step[(a, 0)]).collect();
            if let Some(next) = samples.project(&to_poles(&trial)) {
                let ct = next.cost();
                if ct < cost {
                    let rel = (cost - ct) / cost;
                    (u, at, cost) = (trial, next, ct);
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = rel > 1e-10;
                    break;
                }
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    Some(to_poles(&u))
}

/// The Levenberg–Marquardt step δ of (JᵀJ + λ diag JᵀJ) δ = −Jᵀr, Jᵀr's entries given by
/// `gradient` (one column, JᵀJ's size).
pub(crate) fn marquardt_step(
    jtj: &Mat<f64>,
    gradient: impl Fn(usize) -> f64,
    lambda: f64,
) -> Mat<f64> {
    let p = jtj.nrows();
    let m = Mat::from_fn(p, p, |a, b| {
        jtj[(a, b)]
            + if a == b {
                lambda * jtj[(a, a)].max(1e-300)
            } else {
                0.0
            }
    });
    let rhs = Mat::from_fn(p, 1, |a, _| -gradient(a));
    m.full_piv_lu().solve(&rhs)
}

/// The refinement's parameters of each pole: ln(−Re λ), Im λ.
pub(crate) fn pole_parameters(poles: &[Complex64]) -> Vec<f64> {
    poles
        .iter()
        .flat_map(|p| [(-p.re).max(1e-12).ln(), p.im])
        .collect()
}

/// The poles of the refinement's parameters ([`pole_parameters`]).
pub(crate) fn to_poles(u: &[f64]) -> Vec<Complex64> {
    u.chunks(2)
        .map(|c| Complex64::new(-c[0].exp(), c[1]))
        .collect()
}
