//! How far a fitted pole may lie from the truth beyond what noise explains: what the fit's
//! residual holds of a second-order term at the pole.
//!
//! **Why.** The standard deviations of [`crate::lsfd::pole_deviations`] and of the rank-one
//! fit are the noise's part of the error. A mode the model lacks under a pole (a weak mode
//! beside a strong one, near a node of the reference, that no column of the diagram shows) or a
//! pole the estimator left off its optimum (the diagram's, put back) biases the pole by far
//! more, and the noise's part does not say so.
//!
//! **The term.** Near λ, a pole off by δ leaves ψ δ/(s − λ)² in each curve (ψ its residues);
//! a mode b the model lacks, at Δ = λ_b − λ, adds φ_b/(s − λ) + φ_b Δ/(s − λ)². Where the pole
//! is the fit's optimum it has absorbed the part of the second term parallel to ψ and moved by
//! δ = (ψᴴφ_b/|ψ|²)Δ; the residual keeps c = φ_b⊥Δ. With θ the angle between φ_b and ψ,
//! |δ| = cot θ · |c|/|ψ|. Where the pole is not the optimum, c holds ψ δ itself. Either way
//! |c|/|ψ| is the pole's spread: exact for a pole off its optimum, for a missing mode the
//! bias at θ = 45° (a shape as likely parallel to the pole's as not).
//!
//! **What it cannot see.** A missing mode of the same shape as the pole's (θ = 0) leaves no
//! second shape; one as strong as the pole's own (ψ holds φ_b, cot θ large) is spread more
//! than |c|/|ψ| says. One reference cannot tell the first from one mode; the second shows as a
//! second shape under the pole, which the mode's verdict and the split of the rank-one fit
//! answer ([`crate::second_shape`]).
//!
//! **The window.** The term's columns are kept on the lines within ±[`crate::local_residues::HALF_WIDTHS`] half-power
//! half-widths ζf of the pole (at least [`crate::local_residues::MIN_HALF_WINDOW_LINES`] lines), as the second-shape
//! test's window ([`crate::local_residues`]) and zero elsewhere: 1/(s − λ)² falls off only as
//! 1/ω² away from the pole, and a misfit far from it (a mode the model lacks elsewhere in the
//! band) would otherwise widen every pole.
//!
//! **The estimate.** The term's columns (one complex coefficient per curve, or per reference
//! of a response) projected off the model's basis are fitted to the residual by least squares,
//! response by response, each response's noise variance estimated from its residual in the
//! window less that fit. Under noise alone the coefficients' χ² over their covariance has one
//! degree of freedom per real coefficient; below its 99 % point the spread is zero. Above it
//! the coefficients' energy less what noise gives at that point (its expected share times the
//! point over the χ²'s mean), over the residues' energy Σ|ψ|², gives |c|²/|ψ|². Noise alone
//! passes the point at 1 % of the poles; measured from the mean instead, the spread there would
//! be up to √curves times the deviation's noise part (the term's coefficients are one per curve,
//! the pole one for all).
//!
//! **The bound.** The spread is at most the pole's half-power half-width ζ|λ| (rad/s): a mode
//! farther from the pole than that shows as a resonance of its own, and the first-order
//! expansion above no longer holds there. Without the bound a mode whose residues are near
//! zero (own energy → 0) would take a spread without limit.

use crate::context::chi_square_99;
use crate::local_residues::half_width_hz;
use crate::lscf::pole_freq_hz;
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Whether each of the lines `omega` (rad/s, increasing) lies in the window of `pole` (module
/// docs, "The window"); the smallest step between lines is their spacing.
pub(crate) fn window_of(pole: Complex64, omega: &[f64]) -> Vec<bool> {
    let spacing_hz = omega
        .windows(2)
        .map(|w| (w[1] - w[0]) / (2.0 * PI))
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let spacing_hz = if spacing_hz.is_finite() {
        spacing_hz
    } else {
        0.0
    };
    let (f, half_hz) = (pole_freq_hz(pole), half_width_hz(pole, spacing_hz));
    omega
        .iter()
        .map(|w| (w / (2.0 * PI) - f).abs() <= half_hz)
        .collect()
}

/// The second-order term's fit to a residual, response by response (module docs).
pub(crate) struct SecondOrderTerm<'a> {
    /// The term's columns projected off the model's basis, in the same coordinates as
    /// `residual` (rows × coefficients).
    pub columns: MatRef<'a, f64>,
    /// The fit's residual, one column per response.
    pub residual: MatRef<'a, f64>,
    /// Each response's residual sum of squares over the window's rows.
    pub window_energy: &'a [f64],
    /// The window's rows per response (real rows, over every reference).
    pub window_rows: usize,
}

impl SecondOrderTerm<'_> {
    /// The spread |c|/|ψ| (module docs) in the units of the pole, with `own` = Σ|ψ|² the
    /// residues' energy, at most `bound` (module docs, "The bound"). Each response's noise
    /// variance is its residual's in the window less the term's fit, per degree of freedom left
    /// (noise is often larger near a resonance than over the band). Zero below the 99 % point of
    /// the noise's χ², where `own` is not positive, or where a value is not finite.
    pub(crate) fn spread(&self, own: f64, bound: f64) -> f64 {
        let gram = self.columns.transpose() * self.columns;
        let projections = self.columns.transpose() * self.residual;
        let p = gram.nrows();
        if self.window_rows <= p {
            return 0.0;
        }
        let gram_inverse = gram.full_piv_lu().solve(Mat::<f64>::identity(p, p));
        let trace = (0..p).map(|a| gram_inverse[(a, a)]).sum::<f64>();
        let (mut statistic, mut energy, mut noise) = (0.0_f64, 0.0_f64, 0.0_f64);
        for (o, window_energy) in self.window_energy.iter().enumerate() {
            // The coefficients are G⁻¹b with b = Gᵀr, their covariance v G⁻¹, the energy they
            // take from the residual bᵀG⁻¹b.
            let b = projections.col(o).as_mat().to_owned();
            let coefficients = &gram_inverse * &b;
            let explained = (b.transpose() * &coefficients)[(0, 0)];
            let variance = (window_energy - explained) / (self.window_rows - p) as f64;
            if variance.is_nan() || variance <= 0.0 {
                continue;
            }
            statistic += explained / variance;
            energy += coefficients.squared_norm_l2();
            noise += variance * trace;
        }
        let dof = (p * self.window_energy.len()).max(1);
        let threshold = chi_square_99(dof);
        if !(statistic > threshold && own > 0.0) {
            return 0.0;
        }
        // The energy beyond what noise reaches at the same point (noise × the 99 % point over
        // the mean): a term barely past the point is most likely noise and widens little.
        let beyond_noise = energy - noise * threshold / dof as f64;
        let spread = (beyond_noise.max(0.0) / own).sqrt();
        if spread.is_finite() {
            spread.min(bound)
        } else {
            0.0
        }
    }
}
