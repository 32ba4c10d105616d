//! Levenberg–Marquardt for small nonlinear least-squares problems, on faer.
//!
//! Minimises S(x) = Σ r_i(x)² with steps (JᵀJ + λ diag JᵀJ) δ = −Jᵀr [Marquardt 1963], J by
//! central differences (2p evaluations, [`levenberg_marquardt`]) or given with the residuals
//! ([`levenberg_marquardt_with_jacobian`]), λ divided by 3 after an accepted step and multiplied by
//! 4 after a rejected one. Written here rather than taken from the `levenberg-marquardt` crate
//! because that crate works on nalgebra, a second linear-algebra library.

use faer::prelude::Solve;
use faer::{Mat, Side};

/// Stopping rules.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmSettings {
    /// Iterations allowed.
    pub max_iterations: usize,
    /// Stop when an accepted step lowers S by less than this fraction.
    pub cost_tolerance: f64,
    /// Stop when ‖Jᵀr‖∞ falls below this times S.
    pub gradient_tolerance: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            cost_tolerance: 1e-12,
            gradient_tolerance: 1e-14,
        }
    }
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct LmOutcome {
    /// The parameters at the end.
    pub x: Vec<f64>,
    /// Residuals there.
    pub residuals: Vec<f64>,
    /// Jacobian there (m × p).
    pub jacobian: Mat<f64>,
    /// S = Σ r² there.
    pub cost: f64,
    /// S at the start.
    pub initial_cost: f64,
    /// Iterations (Jacobians computed).
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Whether a tolerance was met (rather than the iteration limit or a stall).
    pub converged: bool,
    /// Why it stopped.
    pub reason: String,
}

/// Minimises Σ r(x)² from `x0`. `residuals` returns `None` for parameters where the model is
/// not defined (treated as an infinitely bad step).
pub fn levenberg_marquardt(
    residuals: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x0: &[f64],
    settings: LmSettings,
) -> Option<LmOutcome> {
    let eval = |x: &[f64]| residuals(x).filter(|r| r.iter().all(|v| v.is_finite()));
    let jac = |x: &[f64], r: &[f64]| {
        let mut count = 0;
        let mut counted = |x: &[f64]| {
            count += 1;
            eval(x)
        };
        jacobian(&mut counted, x, r).map(|j| (j, count))
    };
    minimise(&eval, &jac, x0, settings)
}

/// Minimises Σ r(x)² from `x0` with the Jacobian `jacobian(x)` (m × p) given by the caller
/// (analytic derivatives): `residuals` as in [`levenberg_marquardt`], `jacobian` evaluated at
/// accepted points only.
pub fn levenberg_marquardt_with_jacobian(
    residuals: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    jacobian: &(dyn Fn(&[f64]) -> Option<Mat<f64>> + Sync),
    x0: &[f64],
    settings: LmSettings,
) -> Option<LmOutcome> {
    let eval = |x: &[f64]| residuals(x).filter(|r| r.iter().all(|v| v.is_finite()));
    let jac = |x: &[f64], r: &[f64]| {
        jacobian(x)
            .filter(|j| j.nrows() == r.len() && j.ncols() == x.len())
            .filter(|j| (0..j.ncols()).all(|c| j.col(c).iter().all(|v| v.is_finite())))
            .map(|j| (j, 1))
    };
    minimise(&eval, &jac, x0, settings)
}

/// A Jacobian at (x, r(x)) and the residual evaluations it took.
type JacobianSource<'a> = dyn Fn(&[f64], &[f64]) -> Option<(Mat<f64>, usize)> + 'a;

/// The Marquardt iteration of both entry points; `jac` returns the Jacobian and the residual
/// evaluations it took.
fn minimise(
    eval_residuals: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    jac: &JacobianSource<'_>,
    x0: &[f64],
    settings: LmSettings,
) -> Option<LmOutcome> {
    let p = x0.len();
    let evaluations = std::cell::Cell::new(0);
    let eval = |x: &[f64]| {
        evaluations.set(evaluations.get() + 1);
        eval_residuals(x)
    };
    let jacobian = |x: &[f64], r: &[f64]| {
        jac(x, r).map(|(j, n)| {
            evaluations.set(evaluations.get() + n);
            j
        })
    };
    let mut x = x0.to_vec();
    let mut r = eval(&x)?;
    let cost_of = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut cost = cost_of(&r);
    let initial_cost = cost;
    let mut lambda = 1e-3;
    let mut reason = String::from("iteration limit");
    let mut converged = false;
    let mut iterations = 0;
    let mut jac = jacobian(&x, &r)?;
    while iterations < settings.max_iterations {
        iterations += 1;
        let m = r.len();
        let rm = Mat::from_fn(m, 1, |i, _| r[i]);
        let g = jac.transpose() * &rm;
        let a = jac.transpose() * &jac;
        let gmax = (0..p).map(|i| g[(i, 0)].abs()).fold(0.0, f64::max);
        if gmax <= settings.gradient_tolerance * cost.max(f64::MIN_POSITIVE) || cost == 0.0 {
            converged = true;
            reason = "gradient below tolerance".into();
            break;
        }
        let mut accepted = false;
        while lambda < 1e16 {
            let damped = Mat::from_fn(p, p, |i, j| {
                if i == j {
                    a[(i, i)] * (1.0 + lambda) + 1e-300
                } else {
                    a[(i, j)]
                }
            });
            let Ok(llt) = damped.llt(Side::Lower) else {
                lambda *= 4.0;
                continue;
            };
            let step = llt.solve(-&g);
            let x_new: Vec<f64> = (0..p).map(|i| x[i] + step[(i, 0)]).collect();
            match eval(&x_new) {
                Some(r_new) if cost_of(&r_new) < cost => {
                    let new_cost = cost_of(&r_new);
                    let drop = (cost - new_cost) / cost;
                    x = x_new;
                    r = r_new;
                    cost = new_cost;
                    lambda = (lambda / 3.0).max(1e-12);
                    accepted = true;
                    if drop < settings.cost_tolerance {
                        converged = true;
                        reason = "relative decrease of the cost below tolerance".into();
                    }
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        if !accepted {
            converged = true;
            reason = "no step lowers the cost (minimum to working precision)".into();
            break;
        }
        jac = jacobian(&x, &r)?;
        if converged {
            break;
        }
    }
    Some(LmOutcome {
        x,
        residuals: r,
        jacobian: jac,
        cost,
        initial_cost,
        iterations,
        evaluations: evaluations.get(),
        converged,
        reason,
    })
}

/// Central-difference Jacobian, steps 1e-6·max(1, |x_i|).
fn jacobian(
    eval: &mut dyn FnMut(&[f64]) -> Option<Vec<f64>>,
    x: &[f64],
    r: &[f64],
) -> Option<Mat<f64>> {
    let (m, p) = (r.len(), x.len());
    let mut j = Mat::zeros(m, p);
    for k in 0..p {
        let h = 1e-6 * x[k].abs().max(1.0);
        let mut xp = x.to_vec();
        xp[k] += h;
        let mut xm = x.to_vec();
        xm[k] -= h;
        let (rp, rm) = (eval(&xp)?, eval(&xm)?);
        for i in 0..m {
            j[(i, k)] = (rp[i] - rm[i]) / (2.0 * h);
        }
    }
    Some(j)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as residuals: (1 − x, 10(y − x²)), minimum at (1, 1).
    #[test]
    fn solves_rosenbrock() {
        let f = |x: &[f64]| Some(vec![1.0 - x[0], 10.0 * (x[1] - x[0] * x[0])]);
        let out = levenberg_marquardt(&f, &[-1.2, 1.0], LmSettings::default()).unwrap();
        assert!(out.converged, "{}", out.reason);
        assert!(
            (out.x[0] - 1.0).abs() < 1e-8 && (out.x[1] - 1.0).abs() < 1e-8,
            "{:?}",
            out.x
        );
    }

    /// An exponential fit with noise-free data recovers the parameters.
    #[test]
    fn fits_an_exponential() {
        let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
        let data: Vec<f64> = t.iter().map(|t| 2.5 * (-1.3 * t).exp()).collect();
        let f = |x: &[f64]| {
            Some(
                t.iter()
                    .zip(&data)
                    .map(|(t, d)| x[0] * (-x[1] * t).exp() - d)
                    .collect(),
            )
        };
        let out = levenberg_marquardt(&f, &[1.0, 0.5], LmSettings::default()).unwrap();
        assert!(
            (out.x[0] - 2.5).abs() < 1e-9 && (out.x[1] - 1.3).abs() < 1e-9,
            "{:?}",
            out.x
        );
    }
}
