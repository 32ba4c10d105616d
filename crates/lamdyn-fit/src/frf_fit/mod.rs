//! The core's law fitted to the measured FRFs through a model whose stiffness holds the core
//! through one complex scale s(ω) = G*(ω)/G_a (the layered model, [`CoreFrfModel`]): the
//! model is fitted to the data, not to poles identified from it, so damped and overlapping
//! modes need no EMA.
//!
//! **Model of the data.** At each line ω_l of the band, sensor c and reference r,
//!
//!   D_lcr = g_r Q(ω_l) H_cr(ω_l; s(ω_l; u)) + e_lcr,
//!
//! with H the model's receptance, Q the factor to the measured quantity (1, iω, −ω²), g_r a
//! real calibration gain per reference (prior ln g_r ~ N(0, s_g²)) and e the noise, whose scale
//! σ_lcr is taken from the data ([`BandData`]: the curve's local level, a dynamic-range floor).
//!
//! **Fit.** Levenberg–Marquardt on the parameters x = (u, δ, ln g) minimises
//! Σ |(g_r Q H − D)/σ|² + Σ (δ_k/s_k)² + Σ (ln g_r/s_g)², δ_k = ln θ_k/θ_k,0 the changes of
//! the model's inputs fitted under their priors ([`InputPrior`]: the faces' modulus, the
//! thicknesses, densities, the supports' stiffness and damping), with the Jacobian analytic
//! through the same LU as the residuals: ∂H/∂u_k = ∂H/∂s · (∂G*/∂u_k)/G_a and ∂H/∂δ_k
//! ([`lamdyn_layered::frf::ObservedModel::receptance_with_inputs`]; ∂G*/∂u from
//! [`FrfLaw::gradient`]). The law's covariance is the law block of the whole inverse, so the
//! inputs' priors widen its band as far as the data do not pin them.
//! Starts: the law closest to a given curve (another route's answer), and the best few
//! constant moduli of a grid in (G', η) evaluated on a thinned set of lines, each taken
//! through [`FrfLaw::closest_to`]; the lowest minimum wins.
//!
//! **Bands.** C = A⁺ B A⁺ at the minimum, A = JᵀJ (Laplace approximation), with the middle
//! term B from the residuals themselves: the line scores g_l = J_lᵀ r_l (every channel of a
//! line together) in a Bartlett window over neighbouring lines [Newey & West 1987], plus the
//! priors' rows (`Problem::line_score_information`). It is the misfit's real noise, not the
//! assumed one: where the noise does not follow the weights (a sensor's constant floor
//! against weights relative to the curve's level), where the channels share an error at a
//! line (a law or model error seen by every sensor), and where the residual is correlated
//! along frequency (a structured residual leaves fewer independent lines than it counts).
//! With white noise of one scale s it is s² A⁺. A relative discretization error (the mesh
//! ladder's estimate) is added to the bands of ln G' and ln η in quadrature, and so is the
//! grid's own error: a generalized Maxwell law is fitted again on its relaxation times moved
//! by half a step, from the first law's curve, and the two laws' widest difference within
//! half a grid step counts as two draws of the grid's error
//! ([`FrfFit::grid_spread`]): a true law between what one grid follows ripples about each
//! placement in its own way, a bias of the law's form that no noise model sees, and its
//! amplitude, not its value where the two placements happen to cross, is what it can be. A
//! law parameter whose 95 % interval spans more than a decade either side, or that the data do
//! not see at all (a relaxation weight driven to zero), is reported as not determined. Where
//! inputs are fitted, the law's step with them held at the model's values is kept to first
//! order ([`FrfFit::inputs_held_step`]) for the caller's model-error term.

mod data;
mod law;

pub use data::{BandData, ENVELOPE_HALF_WIDTH};
pub use law::{FrfLaw, PRONY_TERMS_PER_DECADE};

use crate::error::{FitError, inconsistent};
use crate::lm::{LmOutcome, LmSettings, levenberg_marquardt_with_jacobian};
use crate::master::{describe_direction, pseudo_inverse};
use faer::Mat;
use lamdyn_frf::{FrfSet, Quantity};
use lamdyn_layered::frf::{LineReceptance, ObservedModel, input_change};
use lamdyn_layered::sensitivity::Input;
use num_complex::Complex64;
use rayon::prelude::*;
use std::sync::Mutex;

const CONTEXT: &str = "FRF fit";

/// A model whose core enters through one complex scale s(ω) = G*(ω)/G_a.
pub trait CoreFrfModel: Sync {
    /// Number of sensors (rows of H).
    fn n_sensors(&self) -> usize;
    /// Number of references (columns of H).
    fn n_references(&self) -> usize;
    /// Receptance H and ∂H/∂s at ω (rad/s) for the core scale s.
    ///
    /// # Errors
    /// Whatever the model's solve reports.
    fn receptance(&self, omega: f64, core_scale: Complex64) -> Result<LineReceptance, FitError>;
    /// The inputs whose changes [`Self::receptance_with_inputs`] takes (none by default).
    fn inputs(&self) -> Vec<Input> {
        Vec::new()
    }
    /// H, ∂H/∂s and ∂H/∂δ_k with the inputs changed by `deltas` (ln θ/θ₀, one per
    /// [`Self::inputs`]); a model without inputs takes none.
    ///
    /// # Errors
    /// Whatever the model's solve reports; changes the model does not take.
    fn receptance_with_inputs(
        &self,
        omega: f64,
        core_scale: Complex64,
        deltas: &[f64],
    ) -> Result<LineReceptance, FitError> {
        if deltas.is_empty() {
            return self.receptance(omega, core_scale);
        }
        Err(inconsistent(
            CONTEXT,
            format!("the model takes no input changes, {} given", deltas.len()),
        ))
    }
}

impl CoreFrfModel for ObservedModel {
    fn n_sensors(&self) -> usize {
        ObservedModel::n_sensors(self)
    }
    fn n_references(&self) -> usize {
        ObservedModel::n_references(self)
    }
    fn receptance(&self, omega: f64, core_scale: Complex64) -> Result<LineReceptance, FitError> {
        Ok(ObservedModel::receptance(self, omega, core_scale)?)
    }
    fn inputs(&self) -> Vec<Input> {
        ObservedModel::inputs(self)
    }
    fn receptance_with_inputs(
        &self,
        omega: f64,
        core_scale: Complex64,
        deltas: &[f64],
    ) -> Result<LineReceptance, FitError> {
        Ok(ObservedModel::receptance_with_inputs(
            self, omega, core_scale, deltas,
        )?)
    }
}

/// An input of the model fitted beside the law under a prior: ln θ/θ₀ ~ N(0, sd²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputPrior {
    /// The input (the model must hold its derivatives).
    pub input: Input,
    /// Prior standard deviation of ln θ/θ₀ (a 2 % tolerance: 0.02).
    pub sd: f64,
}

/// An input as the fit found it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedInput {
    /// The input.
    pub input: Input,
    /// θ/θ₀ − 1 (how far from the value the model was built with).
    pub change: f64,
    /// The change as the model takes it (δ of [`lamdyn_layered::frf::input_change`]).
    pub delta: f64,
    /// Standard deviation of ln θ/θ₀ after the fit (its prior's where the data say nothing).
    pub sd: f64,
    /// Its prior standard deviation.
    pub prior_sd: f64,
}

/// Settings of [`fit_core_to_frfs`].
#[derive(Debug, Clone, PartialEq)]
pub struct FrfFitSettings {
    /// The band fitted, Hz (inclusive).
    pub band_hz: [f64; 2],
    /// Dynamic range of the weights, dB ([`BandData`]).
    pub dynamic_range_db: f64,
    /// Prior standard deviation s_g of each reference's ln gain.
    pub gain_prior_sd: f64,
    /// Starts taken from the constant-modulus grid beside the start curve; 0 with a start
    /// curve: that curve alone (at least one grid start without a curve).
    pub starts: usize,
    /// Lines of the band the grid is evaluated on (evenly thinned).
    pub grid_lines: usize,
    /// The iteration's stopping rules.
    pub lm: LmSettings,
    /// Relative discretization error of (G', η) added to the bands (the ladder's estimate).
    pub discretization_rel: [f64; 2],
    /// The model's inputs fitted beside the law under their priors (none: held as built).
    pub inputs: Vec<InputPrior>,
    /// Fit the law again on its grid moved by half a step, from the first law's curve, and put
    /// the two laws' difference in the bands ([`FrfFit::sibling`]; a generalized Maxwell law
    /// only).
    pub grid_spread: bool,
}

impl FrfFitSettings {
    /// Defaults over `band_hz`: 40 dB dynamic range, a 10 % gain prior, two starts from 48 grid
    /// lines, at most 60 iterations to a relative cost change of 1e-8, no discretization error,
    /// the grid's spread in the bands.
    pub fn over(band_hz: [f64; 2]) -> Self {
        Self {
            band_hz,
            dynamic_range_db: 40.0,
            gain_prior_sd: 0.1,
            starts: 2,
            grid_lines: 48,
            lm: LmSettings {
                max_iterations: 60,
                cost_tolerance: 1e-8,
                gradient_tolerance: 1e-12,
            },
            discretization_rel: [0.0, 0.0],
            inputs: Vec::new(),
            grid_spread: true,
        }
    }
}

/// A fitted law parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfParameter {
    /// Name with unit.
    pub name: String,
    /// Value, SI.
    pub value: f64,
    /// 95 % interval, or `None` where the data do not determine it (module docs).
    pub ci95: Option<[f64; 2]>,
}

/// The law and its band at one frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfLawPoint {
    /// Frequency, Hz.
    pub f_hz: f64,
    /// G', Pa.
    pub storage_pa: f64,
    /// η.
    pub loss_factor: f64,
    /// 95 % band of G', Pa.
    pub storage_ci95: [f64; 2],
    /// 95 % band of η.
    pub loss_factor_ci95: [f64; 2],
}

/// The fit's answer (module docs).
#[derive(Debug, Clone)]
pub struct FrfFit {
    /// The law fitted.
    pub law: FrfLaw,
    /// Its unconstrained parameters.
    pub u: Vec<f64>,
    /// Its natural parameters with intervals.
    pub parameters: Vec<FrfParameter>,
    /// The references' calibration gains.
    pub gains: Vec<f64>,
    /// Covariance of u (the law's block of C).
    pub covariance: Mat<f64>,
    /// The residuals' scale s.
    pub noise_scale: f64,
    /// The variance inflation τ = 1 + 2 Σ_k ρ_k for residuals correlated along frequency (ρ_k
    /// their pooled lag-k autocorrelation, summed to its first non-positive value [Box & Jenkins
    /// 1976, §2.1.5]): the effective residual count N/τ of [`compare_laws`] (the bands take the
    /// correlation through their line scores, module docs).
    pub inflation: f64,
    /// The misfit S at the start and at the end.
    pub cost: [f64; 2],
    /// RMS of the weighted residual relative to the weighted data.
    pub relative_rms: f64,
    /// The data's misfit S_data = Σ |(g Q H − D)/σ|² at the answer, on the data's own weights
    /// (the priors' rows left out): what [`compare_laws`] weighs.
    pub data_misfit: f64,
    /// Real residuals N fitted (two per line, sensor and reference).
    pub residuals: usize,
    /// Iterations of the last pass.
    pub iterations: usize,
    /// Residual evaluations of the last pass.
    pub evaluations: usize,
    /// Iterations and evaluations (each one sweep of the lines, residuals and Jacobian
    /// together) over every start and pass: the fit's whole work (the start grid's
    /// constant-modulus sweeps on its thinned lines not counted).
    pub work: [usize; 2],
    /// Lines and residuals fitted.
    pub lines: usize,
    /// The band, Hz.
    pub band_hz: [f64; 2],
    /// G_a, Pa.
    pub assembled_modulus_pa: f64,
    /// The relative discretization error in the bands.
    pub discretization_rel: [f64; 2],
    /// The inputs fitted beside the law.
    pub inputs: Vec<FittedInput>,
    /// The same family on its relaxation grid moved by half a step, fitted to the same FRFs
    /// from this law's curve ([`FrfFitSettings::grid_spread`]): law and parameters. Where the
    /// true law lies between what a grid can follow, each placement ripples about it in its own
    /// way; the two laws' difference is an error of the law's form that the covariance does not
    /// see ([`FrfFit::at`]).
    pub sibling: Option<(FrfLaw, Vec<f64>)>,
    /// Why the sibling could not be fitted (the bands then lack the grid's part).
    pub sibling_failed: Option<String>,
    /// The step Δu of the law's unconstrained parameters with the inputs held at the values the
    /// model was built with (δ = 0) and the law and gains refitted, to first order from the
    /// answer (`Problem::law_step_with_inputs_held`); `None` without inputs fitted. Where the
    /// data pin the inputs far below their priors, a model error they take up moves them, and
    /// the law with them: the difference is what that take-up can be.
    pub inputs_held_step: Option<Vec<f64>>,
}

impl FrfFit {
    /// G*(f), Pa.
    pub fn modulus(&self, f_hz: f64) -> Complex64 {
        self.law.modulus(&self.u, 2.0 * std::f64::consts::PI * f_hz)
    }

    /// G*(f) with the inputs held, Pa, to first order: G* + ∇_u G* · Δu
    /// ([`Self::inputs_held_step`]; linear in G*, since a relaxation weight's ln g along a
    /// direction the data barely see may take a step no exponential survives); `None` without
    /// inputs.
    pub fn modulus_inputs_held(&self, f_hz: f64) -> Option<Complex64> {
        let step = self.inputs_held_step.as_ref()?;
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let grad = self.law.gradient(&self.u, w);
        let moved: Complex64 = grad.iter().zip(step).map(|(g, d)| g * d).sum();
        Some(self.law.modulus(&self.u, w) + moved)
    }

    /// The law and its 95 % band at `f_hz` (module docs).
    pub fn at(&self, f_hz: f64) -> FrfLawPoint {
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let g = self.law.modulus(&self.u, w);
        let grad = self.law.gradient(&self.u, w);
        let d_ln_storage: Vec<f64> = grad.iter().map(|d| d.re / g.re).collect();
        let d_ln_eta: Vec<f64> = grad.iter().map(|d| d.im / g.im - d.re / g.re).collect();
        let var = |d: &[f64]| {
            let mut v = 0.0;
            for a in 0..d.len() {
                for b in 0..d.len() {
                    v += d[a] * self.covariance[(a, b)] * d[b];
                }
            }
            v.max(0.0)
        };
        let [grid_storage, grid_eta] = self.grid_spread(w);
        let sd_storage =
            (var(&d_ln_storage) + self.discretization_rel[0].powi(2) + grid_storage.powi(2)).sqrt();
        let sd_eta =
            (var(&d_ln_eta) + self.discretization_rel[1].powi(2) + grid_eta.powi(2)).sqrt();
        let band = |x: f64, sd: f64| [x * (-1.96 * sd).exp(), x * (1.96 * sd).exp()];
        let eta = g.im / g.re;
        FrfLawPoint {
            f_hz,
            storage_pa: g.re,
            loss_factor: eta,
            storage_ci95: band(g.re, sd_storage),
            loss_factor_ci95: band(eta, sd_eta),
        }
    }

    /// The grid's part of the bands at ω: the sd of ln G' and ln η over the two grid placements,
    /// the widest |ln a − ln b|/√2 within half a grid step of ω (two draws of the grid's error,
    /// an oscillation with the grid's period whose amplitude counts, not its value at ω where
    /// the placements may cross; zeros without a [`FrfFit::sibling`]).
    pub fn grid_spread(&self, omega: f64) -> [f64; 2] {
        let Some((law, u)) = &self.sibling else {
            return [0.0, 0.0];
        };
        let half_step = 0.5 * self.law.grid_step_ln().unwrap_or(0.0);
        let n = GRID_SPREAD_POINTS as i32;
        let mut widest = [0.0f64; 2];
        for k in -n..=n {
            let w = omega * (half_step * f64::from(k) / f64::from(n)).exp();
            let (a, b) = (self.law.modulus(&self.u, w), law.modulus(u, w));
            widest[0] = widest[0].max((a.re / b.re).ln().abs());
            widest[1] = widest[1].max(((a.im / a.re) / (b.im / b.re)).ln().abs());
        }
        widest.map(|v| v / std::f64::consts::SQRT_2)
    }

    /// One line: how the fit went.
    pub fn describe(&self) -> String {
        let grid = match &self.sibling_failed {
            Some(e) => format!(
                "; the grid moved by half a step did not fit ({e}): the bands lack the grid's \
                 spread"
            ),
            None => String::new(),
        };
        format!(
            "{} fitted to {} lines in {:.1}–{:.1} Hz: misfit {:.3e} → {:.3e} (relative RMS {:.1} \
             %), {} iterations in the last pass, noise scale {:.3}, correlation inflation \
             {:.1}{grid}, {} iterations in all",
            self.law.name(),
            self.lines,
            self.band_hz[0],
            self.band_hz[1],
            self.cost[0],
            self.cost[1],
            100.0 * self.relative_rms,
            self.iterations,
            self.noise_scale,
            self.inflation,
            self.work[0]
        )
    }
}

/// A start of the fit: a curve G*(ω) (Pa, ω in rad/s) the law starts closest to.
pub type StartCurve<'a> = &'a (dyn Fn(f64) -> Complex64 + Sync);

/// Fits `law` to `set` through `model` (module docs). `set`'s responses and references are the
/// model's sensors and references in order; `assembled_modulus_pa` is G_a.
///
/// # Errors
/// [`FitError::Inconsistent`] for channel counts that differ from the model's, a band with
/// fewer lines than parameters, non-finite data, a model that cannot be solved at the start,
/// or a fit that does not settle within its iterations (how far it got and which parameters
/// move together).
pub fn fit_core_to_frfs(
    model: &dyn CoreFrfModel,
    set: &FrfSet,
    law: FrfLaw,
    assembled_modulus_pa: f64,
    start: Option<StartCurve<'_>>,
    settings: &FrfFitSettings,
) -> Result<FrfFit, FitError> {
    check_model_and_data(model, set, assembled_modulus_pa)?;
    let inputs = fitted_inputs(model, &settings.inputs)?;
    let n_params = law.n_params() + inputs.len() + set.references().len();
    let data = BandData::from_set(set, settings.band_hz, settings.dynamic_range_db, n_params)?;
    let problem = Problem {
        model,
        data,
        law,
        g_a: assembled_modulus_pa,
        quantity: set.quantity(),
        gain_prior_sd: settings.gain_prior_sd,
        inputs,
        n_model_inputs: model.inputs().len(),
        data_weight: 1.0,
    };
    let mut problem = problem;
    let starts = problem.starts(start, settings)?;
    let (first, mut work) = best_of_starts(&problem, starts, settings.lm)?;
    // The data's own noise scale, then the fit again with the data rows on that scale, so the
    // priors weigh against the data as they should: a fixed point (module docs). The first
    // pass, on an unknown scale, need not settle; the passes after it must.
    let (mut run, mut data_scale) = (first, 1.0);
    for _ in 0..MAX_SCALE_PASSES {
        let scale = problem.data_noise_scale(&run);
        let settled = (scale / data_scale - 1.0).abs() < 0.1;
        data_scale = scale;
        problem.data_weight = 1.0 / data_scale;
        let from = run.x.clone();
        run = problem.minimise(&run.x, settings.lm).ok_or_else(|| {
            inconsistent(
                CONTEXT,
                "the model could not be solved at the previous pass's answer".into(),
            )
        })?;
        work = [work[0] + run.iterations, work[1] + run.evaluations];
        if !run.converged && problem.law_change_in_band(&from, &run.x) > SETTLED_LAW_CHANGE {
            return Err(problem.did_not_settle(&run));
        }
        if settled {
            break;
        }
    }
    let mut fit = problem.conclude(run, data_scale, settings)?;
    fit.work = work;
    if settings.grid_spread
        && let Some(shifted) = fit.law.shifted_half_step()
    {
        let curve = |w: f64| fit.modulus(w / (2.0 * std::f64::consts::PI));
        // The sibling starts from a law that already follows the data but on another grid, so
        // its terms may need to move far: it gets SIBLING_ITERATIONS times the budget.
        let alone = FrfFitSettings {
            starts: 0,
            grid_spread: false,
            lm: LmSettings {
                max_iterations: SIBLING_ITERATIONS * settings.lm.max_iterations,
                ..settings.lm
            },
            ..settings.clone()
        };
        match fit_core_to_frfs(
            model,
            set,
            shifted,
            assembled_modulus_pa,
            Some(&curve),
            &alone,
        ) {
            Ok(sibling) => {
                fit.work = [fit.work[0] + sibling.work[0], fit.work[1] + sibling.work[1]];
                fit.sibling = Some((sibling.law, sibling.u));
            }
            Err(e) => fit.sibling_failed = Some(e.to_string()),
        }
    }
    Ok(fit)
}

/// Refuses data whose channel counts differ from the model's and a non-positive assembled
/// modulus ([`fit_core_to_frfs`]'s errors).
fn check_model_and_data(
    model: &dyn CoreFrfModel,
    set: &FrfSet,
    assembled_modulus_pa: f64,
) -> Result<(), FitError> {
    if set.responses().len() != model.n_sensors() || set.references().len() != model.n_references()
    {
        return Err(inconsistent(
            CONTEXT,
            format!(
                "the data have {} response(s) × {} reference(s), the model {} × {}",
                set.responses().len(),
                set.references().len(),
                model.n_sensors(),
                model.n_references()
            ),
        ));
    }
    if !(assembled_modulus_pa.is_finite() && assembled_modulus_pa > 0.0) {
        return Err(inconsistent(
            CONTEXT,
            format!("assembled core modulus {assembled_modulus_pa} Pa must be positive"),
        ));
    }
    Ok(())
}

/// The lowest-cost minimisation from `starts`, and the iterations and evaluations all of them
/// took.
fn best_of_starts(
    problem: &Problem<'_>,
    starts: Vec<Vec<f64>>,
    lm: LmSettings,
) -> Result<(LmOutcome, [usize; 2]), FitError> {
    let mut best: Option<LmOutcome> = None;
    let mut work = [0usize; 2];
    for x0 in starts {
        let run = problem.minimise(&x0, lm);
        if let Some(r) = &run {
            work = [work[0] + r.iterations, work[1] + r.evaluations];
        }
        if let Some(run) = run
            && best.as_ref().is_none_or(|b| run.cost < b.cost)
        {
            best = Some(run);
        }
    }
    let first = best.ok_or_else(|| {
        inconsistent(
            CONTEXT,
            "the model could not be solved at any start (a singular dynamic stiffness)".into(),
        )
    })?;
    Ok((first, work))
}

/// How laws fitted to the same FRFs compare ([`compare_laws`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LawComparison {
    /// Index of the law kept: the lowest criterion.
    pub chosen: usize,
    /// Each fit's corrected Akaike criterion (lower is better).
    pub akaike: Vec<f64>,
    /// The effective number of independent residuals N/τ the criteria were taken on.
    pub effective_residuals: f64,
}

/// Compares fits of different laws to the same FRFs by the corrected Akaike criterion
/// [Hurvich & Tsai 1989] of a Gaussian misfit with unknown scale,
///
///   AICc = n ln(S_data/N) + 2p + 2p(p + 1)/(n − p − 1),  n = N/τ,
///
/// p the law's parameters (the inputs and gains are common to all), N the residuals and τ the
/// largest of the fits' correlation inflations: residuals correlated along frequency count as
/// n independent ones, so a law's extra terms must buy a drop of the misfit that the
/// independent lines would show, not one the correlated residual counts many times over.
///
/// # Errors
/// No fits, or fits of different data (their residual counts differ).
pub fn compare_laws(fits: &[&FrfFit]) -> Result<LawComparison, FitError> {
    let Some(first) = fits.first() else {
        return Err(inconsistent(CONTEXT, "no fits to compare".into()));
    };
    if let Some(other) = fits.iter().find(|f| f.residuals != first.residuals) {
        return Err(inconsistent(
            CONTEXT,
            format!(
                "fits of different data cannot be compared: {} and {} residuals",
                first.residuals, other.residuals
            ),
        ));
    }
    let tau = fits.iter().map(|f| f.inflation).fold(1.0, f64::max);
    let n_total = first.residuals as f64;
    let n = n_total / tau;
    let akaike: Vec<f64> = fits
        .iter()
        .map(|f| {
            let p = f.law.n_params() as f64;
            if n <= p + 1.0 || f.data_misfit.is_nan() || f.data_misfit <= 0.0 {
                return f64::INFINITY;
            }
            n * (f.data_misfit / n_total).ln() + 2.0 * p + 2.0 * p * (p + 1.0) / (n - p - 1.0)
        })
        .collect();
    let chosen = (0..fits.len())
        .min_by(|&a, &b| akaike[a].total_cmp(&akaike[b]))
        .unwrap_or(0);
    Ok(LawComparison {
        chosen,
        akaike,
        effective_residuals: n,
    })
}

/// Each prior's input as (its index among the model's inputs, its prior sd).
///
/// # Errors
/// An input the model holds no derivatives for, one named twice, or a prior sd that is not
/// positive.
fn fitted_inputs(
    model: &dyn CoreFrfModel,
    priors: &[InputPrior],
) -> Result<Vec<(usize, InputPrior)>, FitError> {
    let held = model.inputs();
    let mut out: Vec<(usize, InputPrior)> = Vec::with_capacity(priors.len());
    for p in priors {
        let Some(k) = held.iter().position(|&i| i == p.input) else {
            return Err(inconsistent(
                CONTEXT,
                format!(
                    "input '{}' has a prior but the model holds no derivative for it",
                    p.input.name()
                ),
            ));
        };
        if out.iter().any(|(j, _)| *j == k) {
            return Err(inconsistent(
                CONTEXT,
                format!("input '{}' has two priors", p.input.name()),
            ));
        }
        if !(p.sd.is_finite() && p.sd > 0.0) {
            return Err(inconsistent(
                CONTEXT,
                format!(
                    "input '{}': prior sd {} must be positive",
                    p.input.name(),
                    p.sd
                ),
            ));
        }
        out.push((k, *p));
    }
    Ok(out)
}

/// The problem the iteration sees.
struct Problem<'a> {
    model: &'a dyn CoreFrfModel,
    data: BandData,
    law: FrfLaw,
    g_a: f64,
    quantity: Quantity,
    gain_prior_sd: f64,
    /// The inputs fitted: (index among the model's inputs, prior).
    inputs: Vec<(usize, InputPrior)>,
    /// How many inputs the model holds.
    n_model_inputs: usize,
    /// 1/s: the data rows divided by the noise scale s of the first pass (1 in it).
    data_weight: f64,
}

/// One line's residuals and its Jacobian rows (row-major, p per row).
type LineBlock = (Vec<f64>, Vec<f64>);

impl Problem<'_> {
    fn n_law(&self) -> usize {
        self.law.n_params()
    }

    fn n_inputs(&self) -> usize {
        self.inputs.len()
    }

    /// Index of the first gain in x = (u, δ, ln g).
    fn first_gain(&self) -> usize {
        self.n_law() + self.n_inputs()
    }

    fn n_params(&self) -> usize {
        self.first_gain() + self.data.n_references
    }

    /// The model's input changes for x: the fitted ones from x, the others 0 (none when no
    /// input is fitted).
    fn model_deltas(&self, x: &[f64]) -> Vec<f64> {
        if self.inputs.is_empty() {
            return Vec::new();
        }
        let mut d = vec![0.0; self.n_model_inputs];
        for (j, (k, _)) in self.inputs.iter().enumerate() {
            d[*k] = x[self.n_law() + j];
        }
        d
    }

    /// One Levenberg–Marquardt run over every line from `x0`. Each evaluation builds the
    /// Jacobian with the residuals (the LU per line gives both); the iteration asks for the
    /// Jacobian at the point it has just accepted, so the last one is kept and handed back
    /// rather than factorised again.
    fn minimise(&self, x0: &[f64], lm: LmSettings) -> Option<LmOutcome> {
        let last: Mutex<Option<(Vec<f64>, Mat<f64>)>> = Mutex::new(None);
        let residuals = |x: &[f64]| {
            let (r, j) = self.evaluate(x)?;
            *last.lock().unwrap_or_else(|e| e.into_inner()) = Some((x.to_vec(), j));
            Some(r)
        };
        let jacobian = |x: &[f64]| {
            let kept = last.lock().unwrap_or_else(|e| e.into_inner()).take();
            match kept {
                Some((at, j)) if at == x => Some(j),
                _ => self.evaluate(x).map(|e| e.1),
            }
        };
        levenberg_marquardt_with_jacobian(&residuals, &jacobian, x0, lm)
    }

    /// s = (S_data/(N − p))^½ of `run`'s data rows (the priors' rows left out), in the
    /// weights' units, at least 1e-6 (a relative noise of one part per million: below any
    /// measurement, and where the misfit's rounding begins).
    fn data_noise_scale(&self, run: &LmOutcome) -> f64 {
        let n = self.data.n_residuals();
        (self.data_misfit(run) / n.saturating_sub(self.n_params()).max(1) as f64)
            .sqrt()
            .max(1e-6)
    }

    /// S_data of `run`'s data rows on the data's own weights (the priors' rows left out).
    fn data_misfit(&self, run: &LmOutcome) -> f64 {
        let n = self.data.n_residuals();
        run.residuals[..n].iter().map(|v| v * v).sum::<f64>()
            / (self.data_weight * self.data_weight)
    }

    /// Residuals over every line plus the gains' prior rows, and their Jacobian.
    fn evaluate(&self, x: &[f64]) -> Option<(Vec<f64>, Mat<f64>)> {
        let blocks: Vec<LineBlock> = (0..self.data.n_lines())
            .into_par_iter()
            .map(|l| self.line(x, l))
            .collect::<Option<Vec<_>>>()?;
        let p = self.n_params();
        let n_law = self.n_law();
        let mut r: Vec<f64> = blocks.iter().flat_map(|b| b.0.iter().copied()).collect();
        let data_rows = r.len();
        // The priors' rows: one per input, one per gain (x's tail after the law).
        let prior_sd: Vec<f64> = self
            .inputs
            .iter()
            .map(|(_, p)| p.sd)
            .chain(std::iter::repeat_n(
                self.gain_prior_sd,
                self.data.n_references,
            ))
            .collect();
        r.extend(prior_sd.iter().enumerate().map(|(k, sd)| x[n_law + k] / sd));
        let mut j = Mat::<f64>::zeros(r.len(), p);
        for (row, v) in blocks.iter().flat_map(|b| b.1.chunks(p)).enumerate() {
            for (k, v) in v.iter().enumerate() {
                j[(row, k)] = *v;
            }
        }
        for (k, sd) in prior_sd.iter().enumerate() {
            j[(data_rows + k, n_law + k)] = 1.0 / sd;
        }
        Some((r, j))
    }

    /// Line `l`'s block (module docs).
    fn line(&self, x: &[f64], l: usize) -> Option<LineBlock> {
        let u = &x[..self.n_law()];
        let ln_gains = &x[self.first_gain()..];
        let w = self.data.omegas[l];
        let g = self.law.modulus(u, w);
        if !(g.re > 0.0 && g.im >= 0.0 && g.is_finite()) {
            return None;
        }
        let rec = self
            .model
            .receptance_with_inputs(w, g / self.g_a, &self.model_deltas(x))
            .ok()?;
        let q = self.quantity.from_receptance(w);
        let dg: Vec<Complex64> = self
            .law
            .gradient(u, w)
            .iter()
            .map(|d| d / self.g_a)
            .collect();
        let (n_c, n_r, p) = (self.data.n_sensors, self.data.n_references, self.n_params());
        let mut res = Vec::with_capacity(2 * n_c * n_r);
        let mut jac = vec![0.0; 2 * n_c * n_r * p];
        for r in 0..n_r {
            let gain = ln_gains[r].exp();
            for c in 0..n_c {
                let wt = self.data.weights[l][r][c] * self.data_weight;
                let (h, dh) = (rec.h[(c, r)], rec.dh_ds[(c, r)]);
                let modelled = gain * q * Complex64::new(h.re, h.im);
                let e = wt * (modelled - self.data.values[l][r][c]);
                res.push(e.re);
                res.push(e.im);
                // The two rows (real, imaginary part) of this residual.
                let at = 2 * p * (r * n_c + c);
                let (re_row, im_row) = jac[at..at + 2 * p].split_at_mut(p);
                let dm = wt * gain * q * Complex64::new(dh.re, dh.im);
                for (k, d) in dg.iter().enumerate() {
                    let v = dm * d;
                    re_row[k] = v.re;
                    im_row[k] = v.im;
                }
                for (j, (k, _)) in self.inputs.iter().enumerate() {
                    let d = rec.dh_dinputs[*k][(c, r)];
                    let v = wt * gain * q * Complex64::new(d.re, d.im);
                    re_row[self.n_law() + j] = v.re;
                    im_row[self.n_law() + j] = v.im;
                }
                let dgain = wt * modelled;
                re_row[self.first_gain() + r] = dgain.re;
                im_row[self.first_gain() + r] = dgain.im;
            }
        }
        Some((res, jac))
    }

    /// Starting points (module docs).
    fn starts(
        &self,
        start: Option<StartCurve<'_>>,
        settings: &FrfFitSettings,
    ) -> Result<Vec<Vec<f64>>, FitError> {
        let tail = self.n_inputs() + self.data.n_references;
        let with_gains = |u: Vec<f64>| {
            u.into_iter()
                .chain(std::iter::repeat_n(0.0, tail))
                .collect()
        };
        // A given curve (another route's answer) is the first start; the grid's follow it,
        // since another route's law may sit in another basin (a pole route misled by damped
        // modes).
        let given: Vec<Vec<f64>> = start
            .map(|curve| with_gains(self.law.closest_to(&self.data.omegas, curve)))
            .into_iter()
            .collect();
        if settings.starts == 0 && !given.is_empty() {
            return Ok(given);
        }
        let n_l = self.data.n_lines();
        let step = n_l.div_ceil(settings.grid_lines.max(1)).max(1);
        let lines: Vec<usize> = (0..n_l).step_by(step).collect();
        let mut scored: Vec<(f64, usize, usize)> = Vec::new();
        for (i, &ratio) in GRID_STORAGE_RATIOS.iter().enumerate() {
            for (j, &eta) in GRID_LOSS_FACTORS.iter().enumerate() {
                let g = Complex64::new(ratio * self.g_a, ratio * self.g_a * eta);
                let cost = self.constant_cost(g, &lines);
                if cost.is_finite() {
                    scored.push((cost, i, j));
                }
            }
        }
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut chosen: Vec<(usize, usize)> = Vec::new();
        for &(_, i, j) in &scored {
            // Starts at least two grid steps apart in G' or in η.
            if chosen
                .iter()
                .all(|&(a, b)| a.abs_diff(i) >= 2 || b.abs_diff(j) >= 2)
            {
                chosen.push((i, j));
            }
            if chosen.len() >= settings.starts.max(1) {
                break;
            }
        }
        if chosen.is_empty() {
            return Err(inconsistent(
                CONTEXT,
                "the model could not be solved for any constant core modulus of the start grid"
                    .into(),
            ));
        }
        Ok(given
            .into_iter()
            .chain(chosen.into_iter().map(|(i, j)| {
                let g = Complex64::new(
                    GRID_STORAGE_RATIOS[i] * self.g_a,
                    GRID_STORAGE_RATIOS[i] * self.g_a * GRID_LOSS_FACTORS[j],
                );
                with_gains(self.law.closest_to(&self.data.omegas, &|_| g))
            }))
            .collect())
    }

    /// The data misfit with a constant core modulus `g` and unit gains on `lines` (the lines
    /// in parallel, summed in order: the same bits on any thread count).
    fn constant_cost(&self, g: Complex64, lines: &[usize]) -> f64 {
        let per_line: Option<Vec<f64>> = lines
            .par_iter()
            .map(|&l| {
                let w = self.data.omegas[l];
                let rec = self.model.receptance(w, g / self.g_a).ok()?;
                let q = self.quantity.from_receptance(w);
                let mut s = 0.0;
                for r in 0..self.data.n_references {
                    for c in 0..self.data.n_sensors {
                        let h = rec.h[(c, r)];
                        let m = q * Complex64::new(h.re, h.im);
                        s += (self.data.weights[l][r][c] * (m - self.data.values[l][r][c]))
                            .norm_sqr();
                    }
                }
                Some(s)
            })
            .collect();
        per_line.map_or(f64::INFINITY, |v| v.iter().sum())
    }

    /// The answer from the winning run (module docs).
    fn conclude(
        &self,
        run: LmOutcome,
        data_scale: f64,
        settings: &FrfFitSettings,
    ) -> Result<FrfFit, FitError> {
        let names = self.names();
        let jtj = run.jacobian.transpose() * &run.jacobian;
        let (inv, _) = pseudo_inverse(&jtj, CONTEXT)?;
        // On the second pass's scale the data rows should give χ²/ν ≈ 1; more is scatter the
        // first pass did not see, less is not credited.
        let s2 = (self.data_noise_scale(&run) / data_scale).powi(2).max(1.0);
        let inflation = self.inflation(&run.residuals);
        let n_law = self.n_law();
        // C = A⁺ (Σ scores' products) A⁺ (module docs); τ is kept for the law comparison.
        let information = self.line_score_information(&run.residuals, &run.jacobian);
        let whole = &inv * &information * &inv;
        let covariance = Mat::from_fn(n_law, n_law, |a, b| whole[(a, b)]);
        let u = run.x[..n_law].to_vec();
        let natural = self.law.natural(&u);
        let most = (0..n_law).map(|k| jtj[(k, k)]).fold(0.0, f64::max);
        let parameters = natural
            .iter()
            .enumerate()
            .map(|(k, &value)| {
                let sd = covariance[(k, k)].max(0.0).sqrt();
                let determined = determined(sd, jtj[(k, k)], most);
                FrfParameter {
                    name: names[k].clone(),
                    value,
                    ci95: determined.then(|| natural_interval(&self.law, &u, k, sd)),
                }
            })
            .collect();
        let data_norm: f64 = self.weighted_data_norm();
        Ok(FrfFit {
            law: self.law.clone(),
            parameters,
            gains: run.x[self.first_gain()..].iter().map(|v| v.exp()).collect(),
            inputs: self
                .inputs
                .iter()
                .enumerate()
                .map(|(j, (_, prior))| {
                    let k = n_law + j;
                    FittedInput {
                        input: prior.input,
                        change: input_change(prior.input, run.x[k]).0,
                        delta: run.x[k],
                        sd: whole[(k, k)].max(0.0).sqrt(),
                        prior_sd: prior.sd,
                    }
                })
                .collect(),
            covariance,
            noise_scale: data_scale * s2.sqrt(),
            inflation,
            cost: [run.initial_cost, run.cost],
            relative_rms: self.data_noise_scale(&run)
                * (self.data.n_residuals() as f64 / data_norm).sqrt(),
            data_misfit: self.data_misfit(&run),
            residuals: self.data.n_residuals(),
            iterations: run.iterations,
            evaluations: run.evaluations,
            work: [0, 0],
            lines: self.data.n_lines(),
            band_hz: settings.band_hz,
            assembled_modulus_pa: self.g_a,
            discretization_rel: settings.discretization_rel,
            sibling: None,
            sibling_failed: None,
            inputs_held_step: self.law_step_with_inputs_held(&jtj, &run.x),
            u,
        })
    }

    /// The law's step Δu with the inputs held at δ = 0 and the law and gains (f) free, to first
    /// order from the answer x̂: r ≈ r̂ + J_f Δf − J_δ δ̂ is least at Δf = (J_fᵀJ_f)⁺ J_fᵀ J_δ δ̂,
    /// since J_fᵀ r̂ = 0 at the minimum; both products are blocks of the answer's `jtj` = JᵀJ
    /// (J_f vanishes on the inputs' prior rows). `None` without inputs or where the
    /// pseudo-inverse fails.
    fn law_step_with_inputs_held(&self, jtj: &Mat<f64>, x: &[f64]) -> Option<Vec<f64>> {
        if self.inputs.is_empty() {
            return None;
        }
        let (n_law, n_inputs) = (self.n_law(), self.n_inputs());
        let free: Vec<usize> = (0..n_law)
            .chain(self.first_gain()..self.n_params())
            .collect();
        let a = Mat::from_fn(free.len(), free.len(), |i, k| jtj[(free[i], free[k])]);
        let b = Mat::from_fn(free.len(), 1, |i, _| {
            (0..n_inputs)
                .map(|k| jtj[(free[i], n_law + k)] * x[n_law + k])
                .sum::<f64>()
        });
        let (inv, _) = pseudo_inverse(&a, CONTEXT).ok()?;
        let step = inv * b;
        Some((0..n_law).map(|k| step[(k, 0)]).collect())
    }

    /// The middle term of the covariance's sandwich: the line scores g_l = Σ_(rows of line l)
    /// J_row r_row (every sensor and reference of a line together, so what the channels share,
    /// a law or model error, counts once per line and not once per channel) in a Bartlett
    /// window over L lines [Newey & West 1987], L = ⌊4 (n/100)^(2/9)⌋ for n lines [Newey &
    /// West 1994], times n/(n − p), plus the priors' rows JᵀJ:
    ///
    ///   B = n/(n − p) Σ_(|k| ≤ L) (1 − |k|/(L + 1)) Σ_l g_l g_(l+k)ᵀ + J_priorᵀ J_prior.
    fn line_score_information(&self, residuals: &[f64], jacobian: &Mat<f64>) -> Mat<f64> {
        let d = &self.data;
        let per_line = 2 * d.n_references * d.n_sensors;
        let n_l = d.n_lines();
        let p = jacobian.ncols();
        let scores = Mat::from_fn(n_l, p, |l, k| {
            (l * per_line..(l + 1) * per_line)
                .map(|i| jacobian[(i, k)] * residuals[i])
                .sum::<f64>()
        });
        let lags = newey_west_lags(n_l).min(n_l.saturating_sub(1));
        let mut meat = scores.transpose() * &scores;
        for lag in 1..=lags {
            let w = 1.0 - lag as f64 / (lags + 1) as f64;
            let (early, late) = (scores.subrows(0, n_l - lag), scores.subrows(lag, n_l - lag));
            let c = early.transpose() * late;
            meat += Mat::from_fn(p, p, |a, b| w * (c[(a, b)] + c[(b, a)]));
        }
        let small_sample = n_l as f64 / n_l.saturating_sub(p).max(1) as f64;
        let n = d.n_residuals();
        let priors = jacobian.subrows(n, jacobian.nrows() - n);
        Mat::from_fn(p, p, |a, b| small_sample * meat[(a, b)]) + priors.transpose() * priors
    }

    fn weighted_data_norm(&self) -> f64 {
        let d = &self.data;
        (0..d.n_lines())
            .flat_map(|l| {
                (0..d.n_references).flat_map(move |r| {
                    (0..d.n_sensors)
                        .map(move |c| (d.weights[l][r][c] * d.values[l][r][c]).norm_sqr())
                })
            })
            .sum::<f64>()
            .max(f64::MIN_POSITIVE)
    }

    /// τ = 1 + 2 Σ ρ_k over the residual series along the lines (module docs).
    fn inflation(&self, residuals: &[f64]) -> f64 {
        let d = &self.data;
        let per_line = 2 * d.n_references * d.n_sensors;
        let n_l = d.n_lines();
        let at = |l: usize, s: usize| residuals[l * per_line + s];
        let c0: f64 = (0..n_l)
            .flat_map(|l| (0..per_line).map(move |s| (l, s)))
            .map(|(l, s)| at(l, s).powi(2))
            .sum();
        if c0.is_nan() || c0 <= 0.0 {
            return 1.0;
        }
        let mut tau = 1.0;
        for k in 1..(n_l / 4).max(1) {
            let ck: f64 = (0..n_l - k)
                .flat_map(|l| (0..per_line).map(move |s| (l, s)))
                .map(|(l, s)| at(l, s) * at(l + k, s))
                .sum();
            let rho = ck / c0;
            if rho <= 0.0 {
                break;
            }
            tau += 2.0 * rho;
        }
        tau
    }

    /// The parameters' names with units, the gains last.
    fn names(&self) -> Vec<String> {
        self.law
            .names()
            .into_iter()
            .chain(
                self.inputs
                    .iter()
                    .map(|(_, p)| format!("ln {}", p.input.name())),
            )
            .chain((0..self.data.n_references).map(|r| format!("gain of reference {}", r + 1)))
            .collect()
    }

    /// The largest relative change of G*(ω) over the band's lines between the laws of `a` and
    /// `b`: what a pass that ran out of iterations still moved where the data see the law.
    fn law_change_in_band(&self, a: &[f64], b: &[f64]) -> f64 {
        let n = self.n_law();
        self.data
            .omegas
            .iter()
            .map(|&w| {
                let (ga, gb) = (self.law.modulus(&a[..n], w), self.law.modulus(&b[..n], w));
                (gb / ga - 1.0).norm()
            })
            .fold(0.0, f64::max)
    }

    /// The error of a fit that ran out of iterations: how far it got and what moves together.
    fn did_not_settle(&self, run: &LmOutcome) -> FitError {
        let names = self.names();
        let jtj = run.jacobian.transpose() * &run.jacobian;
        let weakest = jtj.self_adjoint_eigen(faer::Side::Lower).ok().map(|e| {
            (0..jtj.nrows())
                .map(|a| e.U()[(a, 0)])
                .collect::<Vec<f64>>()
        });
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let together = weakest.map_or_else(
            || "unknown parameters".to_string(),
            |v| describe_direction(&names, &v),
        );
        inconsistent(
            CONTEXT,
            format!(
                "the fit did not settle in {} iterations ({}): the misfit fell from {:.4e} to \
                 {:.4e}; the parameters that move together are {together}. Narrow the band, give a \
                 start law, or choose a law with fewer terms",
                run.iterations, run.reason, run.initial_cost, run.cost
            ),
        )
    }
}

/// The largest change of G* over the band (relative) that a pass may still make when it runs
/// out of iterations and count as settled: what it then moves are terms the band does not see
/// (the equilibrium modulus of a Prony law whose optimum lies at zero, reached only in the
/// limit of ln g → −∞), not the law the data determine.
const SETTLED_LAW_CHANGE: f64 = 1e-3;

/// Passes of the noise scale's fixed point at most (each a Levenberg–Marquardt run from the
/// previous answer; noisy data settle in two).
const MAX_SCALE_PASSES: usize = 6;

/// The grid-moved sibling's iteration budget, in multiples of the fit's own.
const SIBLING_ITERATIONS: usize = 3;

/// Points either side of a frequency at which [`FrfFit::grid_spread`] looks for the two grid
/// placements' widest difference within half a grid step.
const GRID_SPREAD_POINTS: usize = 4;

/// Newey and West's automatic lag for a Bartlett window over `n` lines, ⌊4 (n/100)^(2/9)⌋
/// [Newey & West 1994] (3 for 66 lines, 5 for 300 or 400).
fn newey_west_lags(n: usize) -> usize {
    (4.0 * (n as f64 / 100.0).powf(2.0 / 9.0)).floor() as usize
}

/// G'/G_a of the start grid, 1/16 … 16 in steps of two.
const GRID_STORAGE_RATIOS: [f64; 9] = [0.0625, 0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0];
/// η of the start grid.
const GRID_LOSS_FACTORS: [f64; 6] = [0.05, 0.15, 0.3, 0.6, 1.0, 1.5];

/// Whether the data determine a law parameter: its 95 % interval within a decade either side
/// (1.96 sd ≤ ln 10), and its own information JᵀJ_kk above 1e-12 of the law's largest. A
/// parameter the data do not see (a relaxation weight driven to zero: its Jacobian column
/// vanishes) falls in the pseudo-inverse's null space, whose zero variance is no interval.
fn determined(sd: f64, information: f64, most_information: f64) -> bool {
    1.96 * sd <= 10f64.ln() && information > 1e-12 * most_information
}

/// The 95 % interval of natural parameter `k` from the sd of its unconstrained u_k.
fn natural_interval(law: &FrfLaw, u: &[f64], k: usize, sd: f64) -> [f64; 2] {
    let at = |delta: f64| {
        let mut v = u.to_vec();
        v[k] += delta;
        law.natural(&v)[k]
    };
    let (a, b) = (at(-1.96 * sd), at(1.96 * sd));
    [a.min(b), a.max(b)]
}

#[cfg(test)]
mod tests;
