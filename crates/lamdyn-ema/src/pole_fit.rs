//! Levenberg–Marquardt on the poles of the residue problem ([`crate::projection`]), the
//! residues eliminated: the step the refinement ([`crate::lsfd::refined_poles`]) and the local
//! refits ([`crate::local_refit`]) share.

use crate::projection::LineSamples;
use faer::Mat;
use faer::linalg::solvers::Solve;
use num_complex::Complex64;

/// The relative reduction of the sum of squares that the Levenberg–Marquardt steps stop below:
/// rounding's share of it (a few thousand squared residuals summed in f64).
const CONVERGED: f64 = 1e-12;

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
    for k in 0..iterations {
        on_iteration(k + 1, iterations);
        let normal = at.normal_equations(samples);
        let (jtj, jtr) = (normal.weighted(|_| 1.0), normal.gradient);
        let mut improved = false;
        for _ in 0..8 {
            let step = marquardt_step(&jtj, |a| jtr[(a, 0)], lambda);
            // The Gauss–Newton model's reduction −δᵀJᵀr (within a factor 2 of its exact
            // value); it only shrinks as λ grows. Below rounding's share of the cost the poles
            // have converged, and every trial would be refused by rounding alone.
            let promised: f64 = (0..p).map(|a| -jtr[(a, 0)] * step[(a, 0)]).sum();
            if promised.is_finite() && promised <= CONVERGED * cost {
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
