//! Residues by least-squares frequency domain (LSFD), with lower and upper residual terms, and
//! the modal model they make.
//!
//! With the poles λ_r fixed, each FRF curve is linear in its unknowns [Heylen et al. 1997]:
//!
//!   H(ω) = (iω)^k { Σ_r [ A_r/(iω − λ_r) + A_r*/(iω − λ_r*) ] + LR/(iω)² + UR }
//!
//! (k = 0, 1, 2 for receptance, mobility, accelerance: the fit is made in the measured units, so
//! that the noise of the measurement weighs every line alike) with complex residues A_r, a real
//! lower residual LR (modes below the band, the rigid-body mass line) and a real upper residual
//! UR (modes above it). Real and imaginary parts of every line give a real least-squares
//! problem whose matrix is shared by all curves: one QR, all curves as right-hand sides.
//!
//! **Pole refinement** ([`refine`]): the poles from the stabilization diagram carry the bias of
//! the linearised LSCF (its damping errors reach several percent at 40 dB for close modes).
//! They are refined by Levenberg–Marquardt on Σ_o Σ_k |H_o − Ĥ_o|² over the poles alone, the
//! residues being the LSFD solution for each trial (variable projection [Golub & Pereyra
//! 1973]); with white noise this is the maximum-likelihood estimate *if* the model held. The
//! residual terms cannot hold damped modes outside the band, and a damped pole next to the
//! band's edge takes up the misfit; so, given the LSCF model's denominator the diagram was read
//! from, the refinement holds an outside model beside its poles as fixed partial fractions with
//! free residues: below the band, that model's roots there (in the Ω domain:
//! `LscfContext::roots_below`); above it, four pseudo-modes (`band::pseudo_modes_above`), which
//! follow the tail of a damped mode just above the band where the LSCF model's negative real
//! roots, gathered at the band's upper edge, did not and a free pole left its column to take it
//! (docs/ema.md, "Damped poles"). The roots below the band trade with a pole within their reach,
//! so such a pole is refined in a second fit without them (`LscfContext::holds_below_beside`),
//! each pole's estimate taken from its own fit. Identification then refits each pole that
//! stands alone on the lines around it with the rest of the band's model held (module
//! `local_refit`): the joint fit lets the far lines' noise bias it.
//!
//! **Shapes.** For one reference, the residues over the responses are the complex mode shape
//! (up to scale). With a driving point p (response = reference), mass-normalised complex modes
//! A_r = φ φᵀ/(2iω_d) give φ_p = √(2iω_d A_r,pp) and φ_o = 2iω_d A_r,op/φ_p ([`shape_of`]).
//! The residues of the whole band hold what its two residual terms miss (damped modes outside
//! the band); the identified modes take their shapes from residues fitted near each pole
//! ([`crate::local_residues`]).

use crate::denominator::LscfContext;
use crate::error::{EmaError, check_curves, invalid};
use crate::pole_fit::{levenberg_marquardt, pole_parameters, to_poles};
pub use crate::projection::LineBasis;
use crate::projection::{LineSamples, NormalEquations, solve_by_blocks};
use faer::Mat;
use faer::linalg::solvers::Solve;
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The identified modal model of a set of curves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModalFit {
    /// Poles λ_r, rad/s.
    pub poles: Vec<Complex64>,
    /// Residues A_r per curve: `residues[o][r]` (receptance units, m/N·rad/s).
    pub residues: Vec<Vec<Complex64>>,
    /// Lower residual per curve (receptance × rad²/s²).
    pub lower: Vec<f64>,
    /// Upper residual per curve (receptance).
    pub upper: Vec<f64>,
    /// The quantity of the curves.
    pub quantity: Quantity,
}

/// Fits residues and residuals of `curves` (values of `quantity` at `freqs_hz`) for `poles`,
/// over the lines in `band_hz` (lines at 0 Hz are skipped).
///
/// # Errors
/// [`EmaError::Invalid`] for no pole, fewer lines than unknowns, curves of the wrong length, or
/// non-finite values.
pub fn lsfd(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    band_hz: [f64; 2],
) -> Result<ModalFit, EmaError> {
    check_curves(freqs_hz, curves)?;
    lsfd_on(
        freqs_hz,
        curves,
        quantity,
        poles,
        &crate::band::positive_lines(freqs_hz, band_hz),
    )
}

/// [`lsfd`] over the given lines (indices into `freqs_hz`; the curves already checked).
fn lsfd_on(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    lines: &[usize],
) -> Result<ModalFit, EmaError> {
    if poles.is_empty() {
        return Err(invalid("poles", "no pole to fit residues for".into()));
    }
    let unknowns = 2 * poles.len() + 2;
    if 2 * lines.len() < unknowns + 1 {
        return Err(invalid(
            "band",
            format!("{} lines for {} unknowns per curve", lines.len(), unknowns),
        ));
    }
    let x = solve_by_blocks(freqs_hz, curves, quantity, lines, poles)?.ok_or_else(|| {
        invalid(
            "poles",
            "the residue problem is singular (two poles on one mode?)".into(),
        )
    })?;
    let nr = poles.len();
    let curves = 0..x.ncols();
    Ok(ModalFit {
        poles: poles.to_vec(),
        residues: curves
            .clone()
            .map(|o| {
                (0..nr)
                    .map(|r| Complex64::new(x[(2 * r, o)], x[(2 * r + 1, o)]))
                    .collect()
            })
            .collect(),
        lower: curves.clone().map(|o| x[(2 * nr, o)]).collect(),
        upper: curves.map(|o| x[(2 * nr + 1, o)]).collect(),
        quantity,
    })
}

impl ModalFit {
    /// The synthesized value of curve `o` at `freq_hz`, in the curves' quantity.
    pub fn synthesize(&self, o: usize, freq_hz: f64) -> Complex64 {
        self.synthesize_on(&self.line_basis(freq_hz), o)
    }

    /// The model of the curves times `factor`: residues and residual terms scaled, poles kept.
    pub fn scaled(mut self, factor: f64) -> Self {
        for r in &mut self.residues {
            r.iter_mut().for_each(|a| *a *= factor);
        }
        self.lower.iter_mut().for_each(|v| *v *= factor);
        self.upper.iter_mut().for_each(|v| *v *= factor);
        self
    }

    /// The poles' partial fractions at `freq_hz`, computed once for every curve's synthesis
    /// there ([`Self::synthesize_on`], [`Self::mode_term_on`]).
    pub fn line_basis(&self, freq_hz: f64) -> LineBasis {
        LineBasis::new(&self.poles, self.quantity, 2.0 * PI * freq_hz)
    }

    /// [`Self::line_basis`] written into `basis` (loops over lines reuse one).
    pub(crate) fn set_line_basis(&self, basis: &mut LineBasis, freq_hz: f64) {
        basis.set(&self.poles, self.quantity, 2.0 * PI * freq_hz);
    }

    /// [`Self::synthesize`] on a line's basis.
    pub fn synthesize_on(&self, basis: &LineBasis, o: usize) -> Complex64 {
        let modes: Complex64 = (0..self.poles.len())
            .map(|r| self.pair_on(basis, o, r))
            .sum();
        (modes + self.residuals_before_factor(basis, o)) * basis.factor
    }

    /// The residual terms of curve `o` on a line's basis, in the curves' quantity.
    pub fn residual_term_on(&self, basis: &LineBasis, o: usize) -> Complex64 {
        self.residuals_before_factor(basis, o) * basis.factor
    }

    /// The model's columns on a line's basis, written into `out` (2 modes + 2 values): per
    /// mode (iω)^k/(iω − λ_r) and (iω)^k/(iω − λ_r*), then (iω)^k·(−1/ω²) and (iω)^k. Curve
    /// `o`'s value there is their sum weighted by [`Self::coefficients`].
    pub(crate) fn columns_on(&self, basis: &LineBasis, out: &mut [Complex64]) {
        let f = basis.factor;
        for (r, &(t, tc)) in basis.fractions.iter().enumerate() {
            out[2 * r] = f * t;
            out[2 * r + 1] = f * tc;
        }
        let n = out.len();
        out[n - 2] = f * basis.lower;
        out[n - 1] = f;
    }

    /// Curve `o`'s weights of [`Self::columns_on`]: each mode's residue A_r and its conjugate,
    /// then the lower and upper residuals.
    pub(crate) fn coefficients(&self, o: usize) -> Vec<Complex64> {
        let mut c: Vec<Complex64> = self.residues[o]
            .iter()
            .flat_map(|a| [*a, a.conj()])
            .collect();
        c.extend([
            Complex64::new(self.lower[o], 0.0),
            Complex64::new(self.upper[o], 0.0),
        ]);
        c
    }

    /// The lower and upper residuals of curve `o` before the quantity's (iω)^k.
    fn residuals_before_factor(&self, basis: &LineBasis, o: usize) -> Complex64 {
        Complex64::new(basis.lower * self.lower[o] + self.upper[o], 0.0)
    }

    /// [`Self::mode_term`] on a line's basis.
    pub fn mode_term_on(&self, basis: &LineBasis, o: usize, r: usize) -> Complex64 {
        self.pair_on(basis, o, r) * basis.factor
    }

    /// A_r/(iω − λ_r) + A_r*/(iω − λ_r*) of curve `o` on a line's basis.
    fn pair_on(&self, basis: &LineBasis, o: usize, r: usize) -> Complex64 {
        let a = self.residues[o][r];
        let (t, tc) = basis.fractions[r];
        a * t + a.conj() * tc
    }

    /// Mode r's term in curve `o` at `freq_hz`, in the curves' quantity:
    /// (iω)^k [A_r/(iω − λ_r) + A_r*/(iω − λ_r*)].
    pub fn mode_term(&self, o: usize, r: usize, freq_hz: f64) -> Complex64 {
        self.mode_term_on(&self.line_basis(freq_hz), o, r)
    }

    /// Σ_o Σ_k |H_o − Ĥ_o|² over `lines`.
    pub fn cost(&self, freqs_hz: &[f64], curves: &[&[Complex64]], lines: &[usize]) -> f64 {
        curves
            .iter()
            .enumerate()
            .map(|(o, c)| {
                lines
                    .iter()
                    .map(|&k| (c[k] - self.synthesize(o, freqs_hz[k])).norm_sqr())
                    .sum::<f64>()
            })
            .sum()
    }

    /// Mode r's complex shape over the curves: the residues, or mass-normalised through the
    /// driving-point curve `driving` (module docs).
    pub fn shape(&self, r: usize, driving: Option<usize>) -> Vec<Complex64> {
        let a: Vec<Complex64> = self.residues.iter().map(|res| res[r]).collect();
        shape_of(a, self.poles[r], driving)
    }
}

/// The complex shape of a mode of pole `pole` from its residues over the curves: the residues,
/// or mass-normalised through the driving-point curve `driving` (module docs).
pub fn shape_of(
    residues: Vec<Complex64>,
    pole: Complex64,
    driving: Option<usize>,
) -> Vec<Complex64> {
    match driving {
        Some(p) if p < residues.len() => {
            let two_i_wd = Complex64::new(0.0, 2.0 * pole.im);
            let phi_p = (two_i_wd * residues[p]).sqrt();
            residues.iter().map(|v| two_i_wd * v / phi_p).collect()
        }
        _ => residues,
    }
}

/// Frequency response assurance criterion between a measured and a synthesized curve over the
/// lines `lines`: |Σ H_m H_s*|² / (Σ|H_m|² Σ|H_s|²), 1 for identical shapes.
pub fn frac(measured: &[Complex64], synthesized: &[Complex64], lines: &[usize]) -> f64 {
    let mut sums = FracSums::default();
    for &k in lines {
        sums.add(measured[k], synthesized[k]);
    }
    sums.frac()
}

/// The sums of [`frac`]: Σ H Ĥ*, Σ|H|², Σ|Ĥ|², added line by line.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FracSums {
    cross: Complex64,
    measured: f64,
    model: f64,
}

impl FracSums {
    /// The sums Σ H Ĥ*, Σ|H|² and Σ|Ĥ|² as computed elsewhere.
    pub(crate) fn of(cross: Complex64, measured: f64, model: f64) -> Self {
        Self {
            cross,
            measured,
            model,
        }
    }

    /// Adds one line's measured and model values.
    pub(crate) fn add(&mut self, measured: Complex64, model: Complex64) {
        self.cross += measured * model.conj();
        self.measured += measured.norm_sqr();
        self.model += model.norm_sqr();
    }

    /// The FRAC of the lines added.
    pub(crate) fn frac(&self) -> f64 {
        self.cross.norm_sqr() / (self.measured * self.model).max(f64::MIN_POSITIVE)
    }
}

/// Refines `poles` by Levenberg–Marquardt with the residues eliminated (module docs); returns
/// the refined fit. Poles stay stable (Re λ < 0) by the parametrization ln(−Re λ), Im λ.
///
/// # Errors
/// As [`lsfd`].
pub fn refine(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    band_hz: [f64; 2],
    iterations: usize,
) -> Result<ModalFit, EmaError> {
    refine_with(
        freqs_hz,
        curves,
        quantity,
        poles,
        band_hz,
        RefineLines::default(),
        iterations,
        &|_, _| {},
    )
}

/// Which lines the refinement's iterations fit (the final residues always use every line of
/// the band).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefineLines {
    /// Every line of the band.
    All,
    /// When the band holds more than this many lines: the lines around each pole (±(5 ζ f +
    /// 20 Δf): two and a half half-power bandwidths each side, where its frequency and damping
    /// are decided; thinned evenly to about 1000 where there are more, a damped pole on a fine
    /// spacing) and an even thinning of the band to about half this many (the residual terms and
    /// the poles' far field); every line otherwise.
    AtMost(usize),
}

impl Default for RefineLines {
    /// At most 4000 lines: below that, every line (the agreement with the refinement on every
    /// line and the time saved: docs/ema.md, step 4, and `tests/it.rs`).
    fn default() -> Self {
        Self::AtMost(4000)
    }
}

/// The most lines of one pole's window that the refinement fits: a wider window (a damped pole
/// on a fine line spacing) is thinned evenly to about this many.
const WINDOW_LINES: usize = 1000;

/// The reach of a pole's window each side of its frequency, Hz: 5 ζ f + 20 Δf for lines
/// `spacing_hz` apart ([`RefineLines`]).
pub(crate) fn window_reach_hz(pole: Complex64, spacing_hz: f64) -> f64 {
    let (fp, z) = (pole.norm() / (2.0 * PI), -pole.re / pole.norm());
    5.0 * z * fp + 20.0 * spacing_hz
}

/// The lines the refinement fits (see [`RefineLines`]).
pub(crate) fn refinement_lines(
    freqs_hz: &[f64],
    band: &[usize],
    poles: &[Complex64],
    choice: RefineLines,
) -> Vec<usize> {
    let RefineLines::AtMost(max) = choice else {
        return band.to_vec();
    };
    if band.len() <= max || band.len() < 2 {
        return band.to_vec();
    }
    let df = (freqs_hz[band[band.len() - 1]] - freqs_hz[band[0]]) / (band.len() - 1) as f64;
    let step = (2 * band.len()).div_ceil(max).max(1);
    // Each pole's window (frequency, reach, stride): every line, or every m-th where it holds
    // more than WINDOW_LINES.
    let windows: Vec<(f64, f64, usize)> = poles
        .iter()
        .map(|p| {
            let (fp, reach) = (p.norm() / (2.0 * PI), window_reach_hz(*p, df));
            let lines = (2.0 * reach / df) as usize + 1;
            (fp, reach, lines.div_ceil(WINDOW_LINES).max(1))
        })
        .collect();
    let near = |i: usize, f: f64| {
        windows
            .iter()
            .any(|&(fp, reach, stride)| (f - fp).abs() <= reach && i % stride == 0)
    };
    band.iter()
        .enumerate()
        .filter(|(i, k)| i % step == 0 || near(*i, freqs_hz[**k]))
        .map(|(_, k)| *k)
        .collect()
}

/// [`refine`], calling `on_iteration(k, max)` as iteration k of at most `max` starts (for
/// progress on long records).
///
/// # Errors
/// As [`lsfd`].
#[allow(clippy::too_many_arguments)]
pub fn refine_with(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    band_hz: [f64; 2],
    fit_lines: RefineLines,
    iterations: usize,
    on_iteration: &dyn Fn(usize, usize),
) -> Result<ModalFit, EmaError> {
    let refined = refined_poles(
        freqs_hz,
        curves,
        quantity,
        poles,
        band_hz,
        fit_lines,
        iterations,
        None,
        on_iteration,
    )?;
    lsfd(freqs_hz, curves, quantity, &refined, band_hz)
}

/// The poles of [`refine_with`] without their residues (`poles` themselves where the residue
/// problem fails at the start); with `outside`, the LSCF model the poles were read from, the
/// outside model held fixed beside them (module docs): the pseudo-modes above the band, and
/// that model's roots below it except for a pole within their reach, which comes from a second
/// fit without them (every pole free in each fit). `on_iteration(k, max)` counts the
/// iterations over all the fits, one after the other (k of at most `max` = fits ×
/// `iterations`).
///
/// # Errors
/// As [`lsfd`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn refined_poles(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    band_hz: [f64; 2],
    fit_lines: RefineLines,
    iterations: usize,
    outside: Option<&LscfContext>,
    on_iteration: &dyn Fn(usize, usize),
) -> Result<Vec<Complex64>, EmaError> {
    let lines = checked_refinement_lines(freqs_hz, curves, poles, band_hz, fit_lines)?;
    let mut samples = LineSamples::new(freqs_hz, curves, quantity, &lines)?;
    let refine = |samples: &LineSamples, on_iteration: &dyn Fn(usize, usize)| {
        levenberg_marquardt(samples, poles, iterations, on_iteration)
            .unwrap_or_else(|| poles.to_vec())
    };
    let Some(c) = outside else {
        return Ok(refine(&samples, on_iteration));
    };
    let below = c.roots_below(band_hz);
    let pseudo = samples.pole_columns(&crate::band::pseudo_modes_above(band_hz[1]));
    // Two fits at most: one holds the roots below the band, for the poles they do not reach;
    // the other does without them, for the poles they reach. Each gives its members' poles.
    let (beside, apart): (Vec<usize>, Vec<usize>) =
        (0..poles.len()).partition(|&r| c.holds_below_beside(&below, poles[r]));
    let fits: Vec<(&[Complex64], Vec<usize>)> = [(&below[..], beside), (&[][..], apart)]
        .into_iter()
        .filter(|(_, members)| !members.is_empty())
        .collect();
    let mut refined = poles.to_vec();
    let count = fits.len();
    for (j, (held, members)) in fits.into_iter().enumerate() {
        let roots = c.held_root_columns(freqs_hz, &lines, held);
        samples.set_fixed(faer::concat![[roots, pseudo]]);
        // The iterations counted over all the fits, one after the other.
        let fit = refine(&samples, &|k, max| on_iteration(j * max + k, count * max));
        for r in members {
            refined[r] = fit[r];
        }
    }
    Ok(refined)
}

/// The curves checked ([`check_curves`]), then the lines the refinement fits
/// ([`refinement_lines`]) in `band_hz`.
fn checked_refinement_lines(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    poles: &[Complex64],
    band_hz: [f64; 2],
    fit_lines: RefineLines,
) -> Result<Vec<usize>, EmaError> {
    check_curves(freqs_hz, curves)?;
    Ok(refinement_lines(
        freqs_hz,
        &crate::band::positive_lines(freqs_hz, band_hz),
        poles,
        fit_lines,
    ))
}

/// Standard deviations of a pole's frequency and damping ratio.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoleSd {
    /// Of the natural frequency |λ|/2π, Hz.
    pub freq_hz: f64,
    /// Of the damping ratio −Re λ/|λ|.
    pub damping_ratio: f64,
}

impl PoleSd {
    /// These deviations of `pole` widened by a spread δ (rad/s) of the pole in any direction:
    /// √(sd² + s²) with s = δ/2π in f (|∂f/∂λ| = 1/2π) and δ/|λ| in ζ (|∂ζ/∂λ| ≤ 1/|λ|).
    pub(crate) fn widened_by(self, pole: Complex64, delta: f64) -> Self {
        Self {
            freq_hz: self.freq_hz.hypot(delta / (2.0 * PI)),
            damping_ratio: self.damping_ratio.hypot(delta / pole.norm()),
        }
    }
}

/// The standard deviations of `poles` as estimates of the refinement ([`refine`]) on the lines
/// `fit_lines` chooses in `band_hz`: the covariance of the poles' parameters is the sandwich
/// (JᵀJ)⁻¹ (Jᵀ Σ J) (JᵀJ)⁻¹ with J the Jacobian of the projected residuals (the residues
/// eliminated [Golub & Pereyra 1973]) and Σ each curve's residual variance (its sum of
/// squares over its degrees of freedom: 2 × lines − its own unknowns − its share of the
/// poles'), carried to f and ζ by their derivatives. It is the noise's part of the error: the
/// estimator's bias (modes outside the band, the model's residual terms) is not in it. None
/// where the Jacobian is singular or a residue problem fails.
///
/// # Errors
/// As [`lsfd`].
pub fn pole_deviations(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    poles: &[Complex64],
    band_hz: [f64; 2],
    fit_lines: RefineLines,
) -> Result<Option<Vec<PoleSd>>, EmaError> {
    let lines = checked_refinement_lines(freqs_hz, curves, poles, band_hz, fit_lines)?;
    let samples = LineSamples::new(freqs_hz, curves, quantity, &lines)?;
    Ok(deviations(&samples, poles))
}

/// The standard deviations of `poles` as the least-squares estimate of the residue problem on
/// `samples` (the sandwich covariance of [`pole_deviations`]). None where the Jacobian is
/// singular or the residue problem fails.
fn deviations(samples: &LineSamples, poles: &[Complex64]) -> Option<Vec<PoleSd>> {
    let u = pole_parameters(poles);
    let at = samples.project(&to_poles(&u))?;
    let normal = at.normal_equations(samples);
    let rows = samples.rows();
    let own = samples.unknowns(poles.len()) as f64 + u.len() as f64 / samples.curves() as f64;
    let dof = (rows as f64 - own).max(1.0);
    let variance: Vec<f64> = (0..samples.curves())
        .map(|o| at.curve_cost(o) / dof)
        .collect();
    parameter_covariance(&normal, &variance).map(|cov| {
        poles
            .iter()
            .enumerate()
            .map(|(k, p)| {
                pole_sd(
                    *p,
                    [
                        cov[(2 * k, 2 * k)],
                        cov[(2 * k, 2 * k + 1)],
                        cov[(2 * k + 1, 2 * k + 1)],
                    ],
                )
            })
            .collect()
    })
}

/// The sandwich covariance (JᵀJ)⁻¹ (Jᵀ Σ J) (JᵀJ)⁻¹ of [`pole_deviations`] from the normal
/// equations `normal` (JᵀJ curve by curve) and each curve's variance; None when JᵀJ is
/// singular.
fn parameter_covariance(normal: &NormalEquations, variance: &[f64]) -> Option<Mat<f64>> {
    let jtj = normal.weighted(|_| 1.0);
    let meat = normal.weighted(|o| variance[o]);
    sandwich(&jtj, &meat)
}

/// The sandwich (JᵀJ)⁻¹ `meat` (JᵀJ)⁻¹ from `jtj` = JᵀJ; None when JᵀJ is singular (a variance
/// not finite or negative).
pub(crate) fn sandwich(jtj: &Mat<f64>, meat: &Mat<f64>) -> Option<Mat<f64>> {
    let p = jtj.nrows();
    let inverse = jtj.full_piv_lu().solve(Mat::<f64>::identity(p, p));
    let cov = &inverse * meat * &inverse;
    (0..p)
        .all(|a| cov[(a, a)].is_finite() && cov[(a, a)] >= 0.0)
        .then_some(cov)
}

/// f and ζ's standard deviations of pole `p` from the covariance [var a, cov ab, var b] of its
/// parameters a = ln σ, b = ω_d (σ = −Re λ): ∂f/∂a = σ²/(2π|λ|), ∂f/∂b = ω_d/(2π|λ|),
/// ∂ζ/∂a = σω_d²/|λ|³, ∂ζ/∂b = −σω_d/|λ|³.
pub(crate) fn pole_sd(p: Complex64, [vaa, vab, vbb]: [f64; 3]) -> PoleSd {
    let (sigma, wd) = (-p.re, p.im);
    let m = p.norm();
    let spread = |ga: f64, gb: f64| {
        (ga * ga * vaa + 2.0 * ga * gb * vab + gb * gb * vbb)
            .max(0.0)
            .sqrt()
    };
    PoleSd {
        freq_hz: spread(sigma * sigma / (2.0 * PI * m), wd / (2.0 * PI * m)),
        damping_ratio: spread(sigma * wd * wd / m.powi(3), -sigma * wd / m.powi(3)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The derivatives of f and ζ in `pole_sd` against central differences in a = ln σ and
    /// b = ω_d, for a light and a damped pole: one parameter's variance at a time gives |∂/∂u|.
    #[test]
    fn the_deviations_carry_each_parameter_by_its_own_derivative() {
        let f_z = |a: f64, b: f64| {
            let p = Complex64::new(-a.exp(), b);
            (p.norm() / (2.0 * PI), -p.re / p.norm())
        };
        for p in [Complex64::new(-0.16, 161.0), Complex64::new(-90.0, 1130.0)] {
            let (a, b) = ((-p.re).ln(), p.im);
            for (k, var) in [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]].into_iter().enumerate() {
                let h = if k == 0 { 1e-3 } else { 1e-4 * b };
                let (up, down) = if k == 0 {
                    (f_z(a + h, b), f_z(a - h, b))
                } else {
                    (f_z(a, b + h), f_z(a, b - h))
                };
                let sd = pole_sd(p, var);
                let df = ((up.0 - down.0) / (2.0 * h)).abs();
                let dz = ((up.1 - down.1) / (2.0 * h)).abs();
                assert!(
                    (sd.freq_hz - df).abs() <= 1e-5 * df,
                    "{p}, {k}: f {} {df}",
                    sd.freq_hz
                );
                let z = sd.damping_ratio;
                assert!((z - dz).abs() <= 1e-5 * dz, "{p}, {k}: ζ {z} {dz}");
            }
        }
    }

    /// On 0.02 Hz lines over 20–1000 Hz: a light pole's window (51.5 Hz, ζ 0.3 %: ±1.17 Hz,
    /// 117 lines) is fitted on every line, a damped one's (960 Hz, ζ 0.8 %: ±38.8 Hz, 3880
    /// lines) on about WINDOW_LINES of them, evenly; away from both, the band's even thinning.
    #[test]
    fn a_wide_window_is_thinned_evenly_and_a_narrow_one_kept_whole() {
        let freqs: Vec<f64> = (1..=50_000).map(|k| k as f64 * 0.02).collect();
        let band = crate::band::positive_lines(&freqs, [20.0, 1000.0]);
        let pole = |f: f64, z: f64| {
            let w = 2.0 * PI * f;
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        };
        let poles = [pole(51.5, 0.003), pole(960.0, 0.008)];
        let lines = refinement_lines(&freqs, &band, &poles, RefineLines::AtMost(4000));
        let within = |f0: f64, reach: f64| {
            let kept = lines.iter().filter(|&&k| (freqs[k] - f0).abs() <= reach);
            kept.count()
        };
        assert_eq!(within(51.5, 1.17), 117);
        let wide = within(960.0, 38.8);
        assert!((WINDOW_LINES * 9 / 10..=WINDOW_LINES * 11 / 10).contains(&wide));
        let far = within(600.0, 50.0);
        assert!((190..=210).contains(&far), "{far} lines in 550–650 Hz");
    }
}
