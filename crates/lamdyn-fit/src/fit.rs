//! Identification of the effective modulus law E*(ω) (paper eqs. 7 and 10, Table 2).
//!
//! Levenberg–Marquardt ([`crate::lm`]) minimises the misfit ([`crate::misfit`]) over the law's
//! unconstrained parameters ([`crate::law`]) from the best few points of a grid screened by
//! misfit, built around the storage modulus measured at the peaks (`start.rs`). The
//! per-mode law starts from the eq. 7 fit evaluated at the measured peaks. The measured peaks
//! are matched to FE modes in order: the first to the FE mode among the first three whose
//! frequency ratio is closest to one, each later one to the FE mode nearest after scaling by
//! the previous peak's ratio.
//!
//! The starts run in parallel. A complex-FRF misfit starts from the optimum of the log-RMS one
//! (faster, same minimum for consistent data).
//!
//! **Uncertainty.** With J the Jacobian of the m residuals r over the p unconstrained
//! parameters u at the optimum, the covariance of u is either the classical
//! S/(m − p) (JᵀJ)⁻¹ (S = Σ r²) or, by default, the HC3 sandwich
//! (JᵀJ)⁻¹ Jᵀ diag(r_i²/(1 − h_i)²) J (JᵀJ)⁻¹ with leverages h_i = J_i (JᵀJ)⁻¹ J_iᵀ
//! [MacKinnon & White 1985], which stays valid when the noise differs from line to line. It is
//! mapped to the natural parameters by the delta method; 95 % intervals are ±1.96 standard
//! deviations (normal approximation).
//!
//! **Model error.** When the modal model carries its modes' estimated discretization errors
//! ([`ModalModel::with_frequency_errors`]), the parameter change they cause (a linearised refit
//! against the corrected eigenvalues) is added to the covariance as one systematic term, so
//! the intervals cover the answer of a converged mesh (`discretization_shift`).

use crate::error::{FitError, inconsistent};
use crate::law::LawChoice;
use crate::lm::{LmSettings, levenberg_marquardt};
use crate::misfit::{MisfitKind, MisfitSpec, Objective};
use crate::peaks::{Peak, find_peaks};
use crate::start;
use crate::synthesis::ModalModel;
use faer::prelude::Solve;
use faer::{Mat, Side};
use lamdyn_frf::FrfSet;
use num_complex::Complex64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::time::Instant;

/// The law family to fit (the per-mode anchors come from the measured peaks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawKind {
    /// Paper eq. 7.
    PaperEq7,
    /// Fractional-derivative Zener.
    FractionalZener,
    /// Free E' and η at each measured resonance.
    PerMode,
}

/// Settings of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The law.
    pub law: LawKind,
    /// The misfit.
    pub misfit: MisfitSpec,
    /// LM stopping rules.
    pub lm: LmSettings,
    /// Peak prominence for the starting values (ratio over the neighbouring valleys).
    pub prominence: f64,
    /// How the parameter covariance is estimated.
    pub covariance: Covariance,
    /// Identified poles (`lamdyn ema`) to use instead of the RMS FRF's peaks for the starts, the
    /// peak matching and the mode-wise estimate (`None`: peaks of the measured RMS FRF).
    pub poles: Option<Vec<Pole>>,
}

/// An identified pole: natural frequency and damping ratio (e.g. one row of `lamdyn ema`'s
/// modes.csv).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pole {
    /// Damped natural frequency, Hz.
    pub freq_hz: f64,
    /// Damping ratio ζ (η = 2ζ).
    pub damping_ratio: f64,
}

/// Estimator of the parameter covariance at the optimum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Covariance {
    /// S/(m − p) (JᵀJ)⁻¹: exact for independent residuals of equal variance.
    Classical,
    /// The HC3 sandwich [MacKinnon & White 1985; Long & Ervin 2000]: valid when the residuals'
    /// variance changes from line to line (the absolute RMS misfit, where the noise scales with
    /// the signal and the peaks dominate). The default: calibrated for all three misfits in the
    /// recovery study of docs/fit.md, where the classical estimate covers the truth in only
    /// 40 % of cases with the absolute RMS misfit.
    #[default]
    RobustHc3,
}

impl FitSettings {
    /// `law` with `misfit` and default LM settings.
    pub fn new(law: LawKind, misfit: MisfitSpec) -> Self {
        Self {
            law,
            misfit,
            lm: LmSettings::default(),
            prominence: 1.5,
            covariance: Covariance::default(),
            poles: None,
        }
    }
}

/// One identified parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameter {
    /// Name with unit (`E0_pa`).
    pub name: String,
    /// Value.
    pub value: f64,
    /// Standard deviation (delta method), if the Jacobian has full rank.
    pub std_dev: Option<f64>,
    /// 95 % interval.
    pub ci95: Option<[f64; 2]>,
}

/// One start of the multi-start LM.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StartReport {
    /// Natural parameters at the start.
    pub start: Vec<f64>,
    /// Final cost Σ r².
    pub cost: f64,
    /// LM iterations.
    pub iterations: usize,
    /// Whether LM met a tolerance.
    pub converged: bool,
}

/// The identified law and how it was found.
#[derive(Debug, Clone, Serialize)]
pub struct FitResult {
    /// The law, with its anchors for the per-mode law.
    pub law: LawChoice,
    /// Parameters with uncertainty.
    pub parameters: Vec<Parameter>,
    /// Σ r² at the optimum.
    pub cost: f64,
    /// √(Σ r² / m).
    pub residual_rms: f64,
    /// Number of residuals m.
    pub n_residuals: usize,
    /// Lines used.
    pub n_lines: usize,
    /// Misfit evaluations: grid screening, every LM start, and the preliminary fit a complex or
    /// per-mode fit starts from.
    pub evaluations: usize,
    /// Why the best run stopped.
    pub reason: String,
    /// Whether the best run met a tolerance.
    pub converged: bool,
    /// All starts.
    pub starts: Vec<StartReport>,
    /// Measured peaks used for the starts.
    pub peaks: Vec<Peak>,
    /// Wall time of the fit, s.
    pub seconds: f64,
    /// What the plausibility check noticed but did not refuse ([`fit`]).
    pub warnings: Vec<String>,
    /// Change of the natural parameters from the model's estimated discretization error
    /// (linearised refit against the corrected model; included in the intervals), if the
    /// model carries an estimate.
    pub discretization_shift: Option<Vec<f64>>,
    #[serde(skip)]
    cov_u: Option<Mat<f64>>,
    #[serde(skip)]
    u: Vec<f64>,
}

impl FitResult {
    /// The natural parameter values.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.value).collect()
    }

    /// E*(ω) of the identified law, Pa.
    pub fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        self.law.modulus(&self.values(), omega_rad_s)
    }

    /// Natural parameters drawn from the fit's sampling distribution: u + L z in the
    /// unconstrained parameters, with L L^T the covariance of u (Cholesky) and `z` standard
    /// normal deviates (one per parameter). `None` without a covariance or with a covariance
    /// that is not positive definite, or for a wrong number of deviates.
    pub fn draw_parameters(&self, z: &[f64]) -> Option<Vec<f64>> {
        let cov = self.cov_u.as_ref()?;
        let p = self.u.len();
        if z.len() != p {
            return None;
        }
        let l = cov.llt(Side::Lower).ok()?.L().to_owned();
        let u: Vec<f64> = (0..p)
            .map(|i| self.u[i] + (0..=i).map(|k| l[(i, k)] * z[k]).sum::<f64>())
            .collect();
        let n = self.law.natural(&u);
        n.iter().all(|v| v.is_finite()).then_some(n)
    }

    /// χ² quantile at 0.95 for 4 degrees of freedom (9.4877): the bound of the joint 95 %
    /// region of a 4-parameter law for [`FitResult::mahalanobis_squared`].
    pub const CHI2_95_4_PARAMETERS: f64 = 9.487_729;

    /// The squared Mahalanobis distance d² = (u − u*)ᵀ C⁻¹ (u − u*) of natural parameters
    /// `natural` (e.g. a known truth, mapped to unconstrained u*) from the estimate u, with C the
    /// covariance of u. A point lies inside the joint 95 % confidence region when
    /// d² ≤ χ²_p(0.95) (9.488 for p = 4). `None` without a positive definite covariance, for a
    /// wrong number of parameters, or for parameters outside the law's constraints.
    pub fn mahalanobis_squared(&self, natural: &[f64]) -> Option<f64> {
        let cov = self.cov_u.as_ref()?;
        if natural.len() != self.u.len() {
            return None;
        }
        let target = self.law.unconstrained(natural);
        let d = Mat::from_fn(self.u.len(), 1, |i, _| self.u[i] - target[i]);
        if !(0..d.nrows()).all(|i| d[(i, 0)].is_finite()) {
            return None;
        }
        let x = cov.llt(Side::Lower).ok()?.solve(&d);
        Some((0..d.nrows()).map(|i| d[(i, 0)] * x[(i, 0)]).sum())
    }

    /// Whether the fit has a parameter covariance (for [`FitResult::draw_parameters`]).
    pub fn has_covariance(&self) -> bool {
        self.cov_u.is_some()
    }

    /// E'(ω), η(ω) and their standard deviations (delta method through the parameter
    /// covariance), if available.
    pub fn modulus_uncertainty(&self, omega_rad_s: f64) -> (f64, f64, Option<(f64, f64)>) {
        let e = self.modulus(omega_rad_s);
        let eta = e.im / e.re;
        let Some(cov) = &self.cov_u else {
            return (e.re, eta, None);
        };
        let p = self.u.len();
        let grad = |k: usize| {
            let h = 1e-6 * self.u[k].abs().max(1.0);
            let mut up = self.u.clone();
            up[k] += h;
            let mut um = self.u.clone();
            um[k] -= h;
            let (ep, em) = (
                self.law.modulus(&self.law.natural(&up), omega_rad_s),
                self.law.modulus(&self.law.natural(&um), omega_rad_s),
            );
            (
                (ep.re - em.re) / (2.0 * h),
                (ep.im / ep.re - em.im / em.re) / (2.0 * h),
            )
        };
        let g: Vec<(f64, f64)> = (0..p).map(grad).collect();
        let (mut ve, mut vn) = (0.0, 0.0);
        for a in 0..p {
            for b in 0..p {
                ve += g[a].0 * cov[(a, b)] * g[b].0;
                vn += g[a].1 * cov[(a, b)] * g[b].1;
            }
        }
        (e.re, eta, Some((ve.max(0.0).sqrt(), vn.max(0.0).sqrt())))
    }
}

/// Elastic FE frequencies (Hz) at E_ref, increasing.
pub(crate) fn elastic_hz(model: &ModalModel) -> Vec<f64> {
    model.elastic_hz()
}

/// The stiffness scale E/E_ref suggested by the first measured peak: (f_exp/f_num)² against the
/// FE mode among the first three whose ratio is closest to one.
pub(crate) fn start_scale(peaks: &[Peak], fe_hz: &[f64]) -> f64 {
    let f1 = peaks[0].freq_hz;
    fe_hz
        .iter()
        .take(3)
        .map(|f| (f1 / f).powi(2))
        .min_by(|a, b| a.ln().abs().total_cmp(&b.ln().abs()))
        .unwrap_or(1.0)
}

/// The FE frequency (Hz, at E_ref) matching each peak: the first peak as in [`start_scale`],
/// each later one to the FE mode nearest its frequency after scaling by the previous peak's
/// ratio (the modulus varies smoothly with frequency, so the previous ratio is the best guess).
pub(crate) fn match_modes(peaks: &[Peak], fe_hz: &[f64]) -> Vec<f64> {
    let mut ratio = start_scale(peaks, fe_hz).sqrt();
    peaks
        .iter()
        .map(|p| {
            let f = fe_hz
                .iter()
                .cloned()
                .min_by(|a, b| {
                    (a * ratio - p.freq_hz)
                        .abs()
                        .total_cmp(&(b * ratio - p.freq_hz).abs())
                })
                .unwrap_or(p.freq_hz);
            ratio = p.freq_hz / f;
            f
        })
        .collect()
}

/// The effective modulus E* (Pa) each pole implies on the shell model alone, no FRF fit:
/// E* = E_ref (f/f_FE)² e^{2i asin ζ} against the FE mode `match_modes` pairs it with (as
/// the fit's start does). One modulus scales the whole stiffness, K = (E*/E_ref) K0, so the
/// pole of FE mode ω_FE is p = i ω_FE √(E*/E_ref): its natural frequency |p|/2π = f gives
/// |E*| = E_ref (f/f_FE)², and its damping ratio ζ = −Re p/|p| = sin(arg E*/2) gives the
/// phase (loss factor tan(2 asin ζ) ≈ 2ζ). Exact for poles of that model. `poles`:
/// (natural frequency in Hz, damping ratio), increasing in frequency. Empty when the model has
/// no elastic mode or there are no poles.
///
/// With supports (which do not scale with the modulus) the FE frequencies are the supported
/// part's and the modulus is the root of det(s Λ + K̃ + p C̃ + p² I) = 0 nearest that first
/// estimate ([`crate::supports`]), exact for poles of the supported model.
pub fn pole_moduli(model: &ModalModel, poles: &[(f64, f64)]) -> Vec<Complex64> {
    let fe = elastic_hz(model);
    if fe.is_empty() || poles.is_empty() {
        return Vec::new();
    }
    let peaks: Vec<Peak> = poles
        .iter()
        .map(|&(freq_hz, zeta)| Peak {
            freq_hz,
            amplitude: 0.0,
            damping_ratio: Some(zeta),
        })
        .collect();
    match_modes(&peaks, &fe)
        .iter()
        .zip(poles)
        .map(|(f_fe, &(f, zeta))| {
            let magnitude = model.e_ref_pa() * (f / f_fe).powi(2);
            let free = Complex64::from_polar(magnitude, 2.0 * zeta.clamp(0.0, 1.0).asin());
            supported_root(model, free, f, zeta).unwrap_or(free)
        })
        .collect()
}

/// The modulus (Pa) of a supported model's pole (f Hz, ζ) nearest `start` in |ln(E/start)|;
/// `None` for a free model or when no finite root exists.
fn supported_root(model: &ModalModel, start: Complex64, f: f64, zeta: f64) -> Option<Complex64> {
    let z = zeta.clamp(0.0, 1.0);
    let pole = 2.0 * PI * f * Complex64::new(-z, (1.0 - z * z).sqrt());
    let e_ref = model.e_ref_pa();
    model
        .supported_pole_scales(pole)?
        .into_iter()
        .map(|s| s * e_ref)
        .min_by(|a, b| (a / start).ln().norm().total_cmp(&(b / start).ln().norm()))
}

/// Fits the law of `settings` to `measured` through `model`, then checks the result against
/// what a laminate can be ([`check_plausible`]).
///
/// # Errors
/// [`FitError::Inconsistent`] for mismatched channels, an empty band, fewer residuals than
/// parameters, no resonance peak in the band, no start that evaluates, or an implausible
/// result (a modulus orders of magnitude from the model's, a loss factor above 1).
pub fn fit(
    model: &ModalModel,
    measured: &FrfSet,
    settings: &FitSettings,
) -> Result<FitResult, FitError> {
    let mut result = fit_unchecked(model, measured, settings)?;
    check_plausible(&mut result, model.e_ref_pa())?;
    Ok(result)
}

/// Largest factor between the fitted storage modulus at a peak and the model's reference
/// modulus: a laminate's effective modulus lies between its faces' bending alone (a few % of
/// E_ref for thin faces) and E_ref itself, so a factor of 50 either way means the data and the
/// model do not belong together (frequencies in kHz read as Hz, a wrong model or quantity).
pub const PLAUSIBLE_MODULUS_FACTOR: f64 = 50.0;

/// Refuses a fit whose modulus at any measured peak is more than
/// [`PLAUSIBLE_MODULUS_FACTOR`] from `e_ref_pa` or whose loss factor exceeds 1 there; warns
/// (in [`FitResult::warnings`]) when the loss factor is below 1e-7 at every peak (no damping
/// found: is the FRF's quantity right?) and for parameters at the edge of the floating-point
/// range (the optimum ran off to a bound).
///
/// # Errors
/// [`FitError::Inconsistent`] naming the peak and the figure.
pub fn check_plausible(result: &mut FitResult, e_ref_pa: f64) -> Result<(), FitError> {
    let mut max_eta: f64 = 0.0;
    for p in &result.peaks {
        let e = result.modulus(2.0 * PI * p.freq_hz);
        let ratio = e.re / e_ref_pa;
        let eta = e.im / e.re;
        if !(ratio.is_finite()
            && (1.0 / PLAUSIBLE_MODULUS_FACTOR..=PLAUSIBLE_MODULUS_FACTOR).contains(&ratio))
        {
            return Err(inconsistent(
                "fit",
                format!(
                    "implausible result: E' = {:.3e} Pa at the peak at {:.4} Hz is {ratio:.3e} \
                     times the model's E_ref = {e_ref_pa:.4e} Pa; the measured peaks do not belong \
                     to this model: check the FRF's frequency unit (Hz), its quantity line and the \
                     model's material and size",
                    e.re, p.freq_hz
                ),
            ));
        }
        if !(eta.is_finite() && eta <= 1.0) {
            return Err(inconsistent(
                "fit",
                format!(
                    "implausible result: loss factor {eta:.3e} at the peak at {:.4} Hz (above 1: \
                     no laminate damps that much); check the FRF's quantity line and the band",
                    p.freq_hz
                ),
            ));
        }
        max_eta = max_eta.max(eta.abs());
    }
    if !result.peaks.is_empty() && max_eta < 1e-7 {
        result.warnings.push(format!(
            "loss factor below 1e-7 at every peak (largest {max_eta:.2e}): the fit found no \
             damping; is the FRF's '# quantity' line right?"
        ));
    }
    for p in &result.parameters {
        let v = p.value.abs();
        if !(v == 0.0 || (1e-150..=1e150).contains(&v)) {
            result.warnings.push(format!(
                "parameter {} = {:.3e} is at the edge of the number range: the optimum ran off to \
                 a bound and the law is not identified there",
                p.name, p.value
            ));
        } else if v == 0.0 {
            result.warnings.push(format!(
                "parameter {} = 0 is at its bound: the data do not determine it",
                p.name
            ));
        }
    }
    Ok(())
}

/// The poles inside the misfit's band as peaks (the measured RMS FRF at the nearest line as
/// the amplitude, the pole's damping ratio), lowest first.
///
/// # Errors
/// [`FitError::Inconsistent`] for a pole with a frequency that is not positive and finite or a
/// damping ratio outside [0, 1), and when no pole lies in the band.
fn poles_as_peaks(
    poles: &[Pole],
    freqs_hz: &[f64],
    objective: &Objective<'_>,
) -> Result<Vec<Peak>, FitError> {
    for (k, p) in poles.iter().enumerate() {
        if !(p.freq_hz.is_finite() && p.freq_hz > 0.0) {
            return Err(inconsistent(
                "poles",
                format!(
                    "pole {}: frequency {} Hz must be positive",
                    k + 1,
                    p.freq_hz
                ),
            ));
        }
        if !(p.damping_ratio.is_finite() && (0.0..1.0).contains(&p.damping_ratio)) {
            return Err(inconsistent(
                "poles",
                format!(
                    "pole {} at {} Hz: damping ratio {} must lie in [0, 1)",
                    k + 1,
                    p.freq_hz,
                    p.damping_ratio
                ),
            ));
        }
    }
    let lines = objective.lines();
    let (lo, hi) = match (lines.first(), lines.last()) {
        (Some(&a), Some(&b)) => (freqs_hz[a], freqs_hz[b]),
        _ => return Ok(vec![]),
    };
    let rms = objective.measured_rms();
    let mut peaks: Vec<Peak> = poles
        .iter()
        .filter(|p| (lo..=hi).contains(&p.freq_hz))
        .map(|p| {
            let nearest = lines
                .iter()
                .copied()
                .min_by(|&a, &b| {
                    (freqs_hz[a] - p.freq_hz)
                        .abs()
                        .total_cmp(&(freqs_hz[b] - p.freq_hz).abs())
                })
                .unwrap_or(0);
            Peak {
                freq_hz: p.freq_hz,
                amplitude: rms[nearest],
                damping_ratio: Some(p.damping_ratio),
            }
        })
        .collect();
    if peaks.is_empty() {
        return Err(inconsistent(
            "poles",
            format!(
                "none of the {} poles lies in the fit band {lo}-{hi} Hz",
                poles.len()
            ),
        ));
    }
    peaks.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    Ok(peaks)
}

/// [`fit`] without the plausibility check.
fn fit_unchecked(
    model: &ModalModel,
    measured: &FrfSet,
    settings: &FitSettings,
) -> Result<FitResult, FitError> {
    let clock = Instant::now();
    // The complex misfit starts from the log-RMS optimum.
    if settings.misfit.kind == MisfitKind::Complex {
        let mut coarse = settings.clone();
        coarse.misfit.kind = MisfitKind::LogRms;
        let first = fit(model, measured, &coarse)?;
        let objective = Objective::new(model, measured, settings.misfit.clone())?;
        let mut result = run_starts(&objective, &first.law, vec![first.values()], settings)?;
        result.peaks = first.peaks;
        result.evaluations += first.evaluations;
        result.seconds = clock.elapsed().as_secs_f64();
        return Ok(result);
    }
    let objective = Objective::new(model, measured, settings.misfit.clone())?;
    enough_residuals(&objective, settings.law)?;
    let peaks = match &settings.poles {
        Some(poles) => poles_as_peaks(poles, measured.freqs_hz(), &objective)?,
        None => find_peaks(
            measured.freqs_hz(),
            objective.measured_rms(),
            objective.lines(),
            settings.prominence,
        ),
    };
    if peaks.is_empty() {
        return Err(inconsistent(
            "fit",
            "no resonance peak in the band: no starting value for the modulus can be derived"
                .into(),
        ));
    }
    let fe = elastic_hz(model);
    if fe.is_empty() {
        return Err(inconsistent(
            "fit",
            "the modal model has no elastic mode".into(),
        ));
    }
    let matched = match_modes(&peaks, &fe);
    let storage: Vec<(f64, f64)> = peaks
        .iter()
        .zip(&matched)
        .map(|(p, f)| {
            (
                2.0 * PI * p.freq_hz,
                model.e_ref_pa() * (p.freq_hz / f).powi(2),
            )
        })
        .collect();
    let (law, screening, starts) = match settings.law {
        LawKind::PaperEq7 => {
            let grid = start::paper_eq7_grid(&storage);
            (
                LawChoice::PaperEq7,
                grid.len(),
                screened(&objective, LawChoice::PaperEq7, grid),
            )
        }
        LawKind::FractionalZener => {
            let grid = start::fractional_zener_grid(&storage);
            (
                LawChoice::FractionalZener,
                grid.len(),
                screened(&objective, LawChoice::FractionalZener, grid),
            )
        }
        LawKind::PerMode => {
            // Start from the eq. 7 fit evaluated at the peaks: a smooth first guess that keeps
            // every anchor on its own mode.
            let mut smooth = settings.clone();
            smooth.law = LawKind::PaperEq7;
            let first = fit(model, measured, &smooth)?;
            let anchors: Vec<f64> = peaks.iter().map(|p| p.freq_hz).collect();
            let start: Vec<f64> = anchors
                .iter()
                .flat_map(|f| {
                    let e = first.modulus(2.0 * PI * f);
                    [e.re, (e.im / e.re).clamp(1e-6, 1.0)]
                })
                .collect();
            (
                LawChoice::PerMode {
                    anchors_hz: anchors,
                },
                first.evaluations,
                vec![start],
            )
        }
    };
    let mut result = run_starts(&objective, &law, starts, settings)?;
    result.evaluations += screening;
    result.peaks = peaks;
    result.seconds = clock.elapsed().as_secs_f64();
    Ok(result)
}

/// More residuals than parameters (the per-mode law has two per peak, at least two).
fn enough_residuals(objective: &Objective<'_>, law: LawKind) -> Result<(), FitError> {
    let p = match law {
        LawKind::PaperEq7 | LawKind::FractionalZener => 4,
        LawKind::PerMode => 2,
    };
    let m = objective.n_residuals();
    if m <= p {
        return Err(inconsistent(
            "fit",
            format!("{m} residuals for {p} parameters: widen the band or use more lines"),
        ));
    }
    Ok(())
}

/// The best few points of `grid` by misfit ([`start::screen`]).
fn screened(objective: &Objective<'_>, law: LawChoice, grid: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let cost = |n: &[f64]| {
        let prepared = law.prepare(n);
        let r = objective.residuals(&|w| prepared.modulus(w));
        Some(r.iter().map(|v| v * v).sum::<f64>())
    };
    start::screen(&law, grid, &cost, STARTS)
}

/// Levenberg–Marquardt runs per fit (the best screened grid points).
const STARTS: usize = 4;

fn run_starts(
    objective: &Objective<'_>,
    law: &LawChoice,
    starts: Vec<Vec<f64>>,
    settings: &FitSettings,
) -> Result<FitResult, FitError> {
    let p = law.n_params();
    let m = objective.n_residuals();
    if m <= p {
        return Err(inconsistent(
            "fit",
            format!("{m} residuals for {p} parameters: widen the band or use more lines"),
        ));
    }
    let residuals = law_residuals(objective, law);
    // Starts run in parallel; the best final cost wins.
    let outcomes: Vec<(Vec<f64>, Option<crate::lm::LmOutcome>)> = starts
        .into_par_iter()
        .map(|start| {
            let u0 = law.unconstrained(&start);
            let out = levenberg_marquardt(&residuals, &u0, settings.lm);
            (start, out)
        })
        .collect();
    let mut reports = Vec::new();
    let mut best: Option<crate::lm::LmOutcome> = None;
    let mut evaluations = 0;
    for (start, out) in outcomes {
        let Some(out) = out else { continue };
        evaluations += out.evaluations;
        reports.push(StartReport {
            start,
            cost: out.cost,
            iterations: out.iterations,
            converged: out.converged,
        });
        if best.as_ref().is_none_or(|b| out.cost < b.cost) {
            best = Some(out);
        }
    }
    let best =
        best.ok_or_else(|| inconsistent("fit", "no starting point gives a finite misfit".into()))?;
    let nat = law.natural(&best.x);
    let cov_noise = match settings.covariance {
        Covariance::Classical => covariance(&best.jacobian, best.cost, m, p),
        Covariance::RobustHc3 => sandwich_covariance(&best.jacobian, &best.residuals, p),
    };
    let shift_u = discretization_shift(objective, law, &best, settings);
    let cov_u = match (cov_noise, &shift_u) {
        (Some(c), Some(du)) => Some(Mat::from_fn(p, p, |a, b| {
            c[(a, b)] + du[a] * du[b] / (1.96 * 1.96)
        })),
        (c, _) => c,
    };
    let discretization_shift = shift_u.as_ref().map(|du| {
        let moved: Vec<f64> = best.x.iter().zip(du).map(|(u, d)| u + d).collect();
        law.natural(&moved)
            .iter()
            .zip(&nat)
            .map(|(a, b)| a - b)
            .collect()
    });
    let stds = cov_u.as_ref().map(|c| natural_std(law, &best.x, c));
    let parameters = law
        .names()
        .into_iter()
        .enumerate()
        .map(|(k, name)| {
            let sd = stds.as_ref().map(|s| s[k]);
            Parameter {
                name,
                value: nat[k],
                std_dev: sd,
                ci95: sd.map(|s| [nat[k] - 1.96 * s, nat[k] + 1.96 * s]),
            }
        })
        .collect();
    Ok(FitResult {
        law: law.clone(),
        parameters,
        cost: best.cost,
        residual_rms: (best.cost / m as f64).sqrt(),
        n_residuals: m,
        n_lines: objective.lines().len(),
        evaluations,
        reason: best.reason.clone(),
        converged: best.converged,
        starts: reports,
        peaks: vec![],
        warnings: Vec::new(),
        seconds: 0.0,
        discretization_shift,
        cov_u,
        u: best.x,
    })
}

/// What the model's discretization error does to the parameters: Δu = u_c − u, where u_c is
/// the optimum against the corrected model ([`ModalModel::corrected`]), found by LM from u. A
/// refit, not a linearised step: a frequency error of a few per cent moves a peak by several
/// half-power bandwidths, far outside the range where the misfit is linear in it. The errors of
/// one mesh share their sign (a mesh too stiff is too stiff in every mode), so they are one
/// systematic effect, not independent scatter: Δu enters the covariance as the rank-one term
/// Δu Δuᵀ / 1.96², so that the 95 % interval reaches the corrected optimum. `None` when the
/// model carries no estimate or the refit fails.
fn discretization_shift(
    objective: &Objective<'_>,
    law: &LawChoice,
    best: &crate::lm::LmOutcome,
    settings: &FitSettings,
) -> Option<Vec<f64>> {
    let corrected = objective.model().corrected()?;
    let moved = objective.with_model(&corrected);
    let residuals = law_residuals(&moved, law);
    let refit = levenberg_marquardt(&residuals, &best.x, settings.lm)?;
    let out: Vec<f64> = refit.x.iter().zip(&best.x).map(|(c, u)| c - u).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The misfit's residuals as a function of the law's unconstrained parameters u (`None` where
/// the natural parameters are not finite): what LM minimises.
fn law_residuals<'o>(
    objective: &'o Objective<'_>,
    law: &'o LawChoice,
) -> impl Fn(&[f64]) -> Option<Vec<f64>> + Sync + 'o {
    move |u: &[f64]| {
        let n = law.natural(u);
        if !n.iter().all(|v| v.is_finite()) {
            return None;
        }
        let prepared = law.prepare(&n);
        Some(objective.residuals(&|w: f64| prepared.modulus(w)))
    }
}

/// The HC3 sandwich (JᵀJ)⁻¹ Jᵀ diag(r_i²/(1 − h_i)²) J (JᵀJ)⁻¹ with leverages
/// h_i = J_i (JᵀJ)⁻¹ J_iᵀ, or `None` if JᵀJ is singular.
fn sandwich_covariance(j: &Mat<f64>, r: &[f64], p: usize) -> Option<Mat<f64>> {
    let m = j.nrows();
    let jtj = j.transpose() * j;
    let inv = jtj.llt(Side::Lower).ok()?.solve(Mat::<f64>::identity(p, p));
    let leverage = |i: usize| -> f64 {
        (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| j[(i, a)] * inv[(a, b)] * j[(i, b)])
                    .sum::<f64>()
            })
            .sum()
    };
    // A leverage of one (a residual that alone fixes a parameter) is capped: its weight stays
    // finite.
    let jr = Mat::from_fn(m, p, |i, k| {
        j[(i, k)] * r[i] / (1.0 - leverage(i).min(0.99))
    });
    let meat = jr.transpose() * &jr;
    Some(&inv * &meat * &inv)
}

/// S/(m − p) (JᵀJ)⁻¹, or `None` if JᵀJ is singular.
fn covariance(j: &Mat<f64>, cost: f64, m: usize, p: usize) -> Option<Mat<f64>> {
    let jtj = j.transpose() * j;
    let llt = jtj.llt(Side::Lower).ok()?;
    let inv = llt.solve(Mat::<f64>::identity(p, p));
    let s2 = cost / (m - p) as f64;
    Some(Mat::from_fn(p, p, |a, b| s2 * inv[(a, b)]))
}

/// Standard deviations of the natural parameters by the delta method.
fn natural_std(law: &LawChoice, u: &[f64], cov: &Mat<f64>) -> Vec<f64> {
    let p = u.len();
    let mut t = Mat::zeros(p, p);
    for k in 0..p {
        let h = 1e-7 * u[k].abs().max(1.0);
        let mut up = u.to_vec();
        up[k] += h;
        let mut um = u.to_vec();
        um[k] -= h;
        let (np, nm) = (law.natural(&up), law.natural(&um));
        for i in 0..p {
            t[(i, k)] = (np[i] - nm[i]) / (2.0 * h);
        }
    }
    let c = &t * cov * t.transpose();
    (0..p).map(|i| c[(i, i)].max(0.0).sqrt()).collect()
}
