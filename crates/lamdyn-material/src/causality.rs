//! Local Kramers–Kronig check of a complex modulus sampled at discrete frequencies.
//!
//! For a linear viscoelastic solid with a non-negative relaxation spectrum H(τ) (any causal,
//! passive material: a generalized Maxwell body with positive strengths, in the limit of many
//! elements) [Ferry 1980, ch. 3; Tschoegl 1989, ch. 4]
//!
//! G'(ω)            = G_e + ∫ H(τ) x²/(1+x²) d ln τ,        x = ωτ
//! dG'/d ln ω       =       ∫ H(τ) 2x²/(1+x²)² d ln τ
//! G''(ω)           =       ∫ H(τ) x/(1+x²)   d ln τ
//!
//! Both kernels are positive and their ratio is (1+x²)/(2x) ≥ 1, so for every ω
//!
//! (a) dG'/d ln ω ≥ 0              (the storage modulus never falls with frequency),
//! (b) G'' ≥ 0                      (passivity),
//! (c) G'' ≥ dG'/d ln ω.
//!
//! The local Kramers–Kronig approximation [Booij & Thoone 1982] states G'' ≈ (π/2) dG'/d ln ω;
//! this module reports the ratio r = G'' / ((π/2) dG'/d ln ω) per frequency. A smooth causal
//! spectrum gives r ≈ 1 (for G' ∝ ω^n, r = tan(nπ/2)/(nπ/2) ≥ 1); inequality (c) says r ≥ 2/π
//! for every causal material, so r < 2/π is data that no causal material could produce.
//!
//! The slope is a three-point, second-order finite difference in ln ω on the given
//! (non-uniform) grid. [`CausalityParams::tolerance`] absorbs its error and measurement noise:
//! a line is flagged only when an inequality fails by more than that fraction.

use crate::error::MaterialError;
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// Settings of [`kramers_kronig_check`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct CausalityParams {
    /// Relative margin before a line is flagged (default 0.05): covers the finite-difference
    /// error of the slope on grids of about ten points per decade and a few percent of noise.
    pub tolerance: f64,
}

impl Default for CausalityParams {
    fn default() -> Self {
        Self { tolerance: 0.05 }
    }
}

/// What the check concluded at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CausalityVerdict {
    /// All three inequalities hold within the tolerance.
    Consistent,
    /// The loss modulus is negative: the material would create energy.
    NegativeLoss,
    /// The storage modulus falls with frequency, which no causal passive material does.
    StorageFalls,
    /// The loss is smaller than the rise of the storage modulus allows (r < 2/π).
    TooLittleLoss,
}

impl CausalityVerdict {
    /// True for [`CausalityVerdict::Consistent`].
    pub fn is_consistent(self) -> bool {
        self == Self::Consistent
    }

    /// A short label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Self::Consistent => "causal",
            Self::NegativeLoss => "negative loss",
            Self::StorageFalls => "G' falls",
            Self::TooLittleLoss => "too little loss",
        }
    }
}

/// The check at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CausalityLine {
    /// Angular frequency, rad/s.
    pub omega_rad_s: f64,
    /// Loss modulus G'', Pa.
    pub loss_modulus_pa: f64,
    /// dG'/d ln ω, Pa.
    pub storage_slope_pa: f64,
    /// r = G'' / ((π/2) dG'/d ln ω); `None` where the slope is not positive.
    pub ratio: Option<f64>,
    /// The verdict.
    pub verdict: CausalityVerdict,
}

/// The check over all frequencies.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CausalityReport {
    /// One line per input frequency, in input order.
    pub lines: Vec<CausalityLine>,
}

impl CausalityReport {
    /// True when every line is consistent.
    pub fn is_causal(&self) -> bool {
        self.lines.iter().all(|l| l.verdict.is_consistent())
    }

    /// The lines that failed.
    pub fn violations(&self) -> impl Iterator<Item = &CausalityLine> {
        self.lines.iter().filter(|l| !l.verdict.is_consistent())
    }
}

/// Checks sampled complex moduli against the causality inequalities (a)–(c) of the module doc.
///
/// `omega_rad_s` must be strictly increasing and positive, with at least three points, and
/// `modulus_pa` of the same length with finite values.
///
/// # Errors
/// [`MaterialError::InvalidData`] naming the index of the first bad value.
///
/// # Complexity
/// O(n).
pub fn kramers_kronig_check(
    omega_rad_s: &[f64],
    modulus_pa: &[Complex64],
    params: CausalityParams,
) -> Result<CausalityReport, MaterialError> {
    validate(omega_rad_s, modulus_pa)?;
    let x: Vec<f64> = omega_rad_s.iter().map(|w| w.ln()).collect();
    let g: Vec<f64> = modulus_pa.iter().map(|m| m.re).collect();
    let lines = (0..x.len())
        .map(|i| {
            let slope = derivative(&x, &g, i);
            let loss = modulus_pa[i].im;
            CausalityLine {
                omega_rad_s: omega_rad_s[i],
                loss_modulus_pa: loss,
                storage_slope_pa: slope,
                ratio: (slope > 0.0).then(|| loss / (FRAC_PI_2 * slope)),
                verdict: verdict(loss, slope, params.tolerance),
            }
        })
        .collect();
    Ok(CausalityReport { lines })
}

fn verdict(loss: f64, slope: f64, tol: f64) -> CausalityVerdict {
    if loss < 0.0 {
        CausalityVerdict::NegativeLoss
    } else if slope < -tol * loss {
        CausalityVerdict::StorageFalls
    } else if slope > loss * (1.0 + tol) {
        CausalityVerdict::TooLittleLoss
    } else {
        CausalityVerdict::Consistent
    }
}

fn validate(omega: &[f64], modulus: &[Complex64]) -> Result<(), MaterialError> {
    let bad = |reason: String| MaterialError::InvalidData {
        context: "Kramers-Kronig check".into(),
        reason,
    };
    if omega.len() != modulus.len() {
        return Err(bad(format!(
            "{} frequencies but {} moduli",
            omega.len(),
            modulus.len()
        )));
    }
    if omega.len() < 3 {
        return Err(bad(format!(
            "needs at least 3 frequencies, got {}",
            omega.len()
        )));
    }
    for (i, (w, m)) in omega.iter().zip(modulus).enumerate() {
        if !(w.is_finite() && *w > 0.0) {
            return Err(bad(format!(
                "frequency [{i}] = {w} is not a positive number"
            )));
        }
        if !(m.re.is_finite() && m.im.is_finite()) {
            return Err(bad(format!("modulus [{i}] = {m} is not finite")));
        }
        if i > 0 && *w <= omega[i - 1] {
            return Err(bad(format!(
                "frequencies must increase: [{}] = {} then [{i}] = {w}",
                i - 1,
                omega[i - 1]
            )));
        }
    }
    Ok(())
}

/// Kramers–Kronig verdicts at the points (f in Hz, G* in Pa) that have a modulus; `None` at the
/// others, and everywhere when fewer than three points have one (the check needs a slope).
///
/// # Errors
/// As [`kramers_kronig_check`] on the points with a modulus (frequencies not increasing, a
/// non-finite value).
pub fn verdicts_where_known(
    points: &[(f64, Option<Complex64>)],
    params: CausalityParams,
) -> Result<Vec<Option<CausalityVerdict>>, MaterialError> {
    let known: Vec<(usize, f64, Complex64)> = points
        .iter()
        .enumerate()
        .filter_map(|(i, (f, g))| g.map(|g| (i, 2.0 * std::f64::consts::PI * f, g)))
        .collect();
    let mut verdicts = vec![None; points.len()];
    if known.len() < 3 {
        return Ok(verdicts);
    }
    let omega: Vec<f64> = known.iter().map(|k| k.1).collect();
    let modulus: Vec<Complex64> = known.iter().map(|k| k.2).collect();
    let report = kramers_kronig_check(&omega, &modulus, params)?;
    for (k, (i, _, _)) in known.iter().enumerate() {
        verdicts[*i] = Some(report.lines[k].verdict);
    }
    Ok(verdicts)
}

/// Second-order three-point derivative of `f` at `x[i]` on a non-uniform grid (central inside,
/// one-sided at both ends).
fn derivative(x: &[f64], f: &[f64], i: usize) -> f64 {
    let n = x.len();
    let (a, b, c) = match i {
        0 => (0, 1, 2),
        _ if i == n - 1 => (n - 3, n - 2, n - 1),
        _ => (i - 1, i, i + 1),
    };
    // Derivative at x[i] of the parabola through (x_a, f_a), (x_b, f_b), (x_c, f_c).
    let t = x[i];
    let la = ((t - x[b]) + (t - x[c])) / ((x[a] - x[b]) * (x[a] - x[c]));
    let lb = ((t - x[a]) + (t - x[c])) / ((x[b] - x[a]) * (x[b] - x[c]));
    let lc = ((t - x[a]) + (t - x[b])) / ((x[c] - x[a]) * (x[c] - x[b]));
    la * f[a] + lb * f[b] + lc * f[c]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_is_exact_for_parabolas() {
        let x = [0.0, 0.3, 1.1, 1.5, 2.6];
        let f: Vec<f64> = x.iter().map(|t| 2.0 - 3.0 * t + 0.5 * t * t).collect();
        for i in 0..x.len() {
            let exact = -3.0 + x[i];
            assert!((derivative(&x, &f, i) - exact).abs() < 1e-13, "i = {i}");
        }
    }
}
