//! The layered stage's FRF fit: the core's law fitted to the measured FRFs through the layered
//! model on the ladder's finest level ([`lamdyn_fit::frf_fit`]), the inputs under the job's
//! priors, on the converged scale: the level's model takes the law corrected by the ladder's
//! mesh correction ([`crate::frf_route::DiscretizationCorrection`]), and then, fitted again,
//! what that correction leaves of each ladder mode's own error taken out of the model
//! ([`crate::frf_route::ModeByMode`]). A pole the pole route matched to another branch of the
//! model's modes (its converged G' far off the law fitted) is converged again on the ladder
//! from that law before the correction is drawn for good ([`converge_out_of_reach`]).
//!
//! The model is that level of the ladder read at every response channel and driven at
//! every reference by the surface's shape functions ([`ObservedModel::build`]), on a basis of
//! `inverse.layered_modes` modes at two core moduli that bracket the start law over the band
//! (at least G_ref/2 … 2 G_ref: [`FrfBasis::default`]), two orders of core sensitivities and
//! the references' residual vectors. It starts from the pole route's law where there is one,
//! else from the best constant moduli of a grid.

use super::LadderAgain;
use super::setup::{LayeredSetup, basis_modulus, input_rel_sd};
#[cfg(doc)]
use super::tuning::FrfFitTuning;
use crate::Reporter;
use crate::chain::CorePoint;
use crate::error::{Context, Result};
use crate::frf_route::{
    DiscretizationCorrection, FrfCurve, FrfRoute, LawsCompared, ModeByMode, WhyFrfFit,
};
use crate::job::CoreLawChoice;
use crate::text;
use lamdyn_fit::FitError;
use lamdyn_fit::frf_fit::{
    CoreFrfModel, FrfFit, FrfFitSettings, FrfLaw, InputPrior, compare_laws, fit_core_to_frfs,
};
use lamdyn_fit::joint::CoreLawFit;
use lamdyn_frf::{Channel, FrfSet};
use lamdyn_layered::frf::{FrfBasis, LineReceptance, MeasuredPoint, ObservedModel};
use lamdyn_layered::inverse::BASIS_COVER;
use lamdyn_layered::reduced::ModeError;
use lamdyn_layered::sensitivity::Input;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;

/// Channels whose measured and model FRFs the report shows.
const SHOWN_CURVES: usize = 3;

/// What the FRF fit reads.
pub struct FrfFitInput<'a> {
    /// The measured FRFs.
    pub set: &'a FrfSet,
    /// The band fitted, Hz.
    pub band_hz: [f64; 2],
    /// The pole route's law, the start where there is one.
    pub start: Option<&'a CoreLawFit>,
    /// The pole route's modal points (the ladder's corrections; the starts without a law).
    pub modal: &'a [CorePoint],
    /// The ladder's levels (elements, dofs), coarsest first: the fit takes the finest (the
    /// coarsest when empty).
    pub levels: &'a [([usize; 2], usize)],
    /// The identified modes' half-power half-widths ζf (Hz): the lines are thinned to
    /// [`FrfFitTuning::lines_per_half_width`] per the narrowest ([`line_step`]).
    pub half_widths_hz: Vec<f64>,
    /// The ladder again, for poles the pole route matched to another branch of the model's
    /// modes ([`converge_out_of_reach`]); None: their errors stay out of the correction.
    pub ladder_again: Option<LadderAgain<'a>>,
}

/// Every how many lines the fit keeps: the narrowest half-width over `per_half_width` line
/// spacings, at least 1 (no modes: 1).
pub fn line_step(half_widths_hz: &[f64], spacing_hz: f64, per_half_width: f64) -> usize {
    let narrowest = half_widths_hz
        .iter()
        .copied()
        .filter(|w| w.is_finite() && *w > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !(narrowest.is_finite() && spacing_hz > 0.0) {
        return 1;
    }
    ((narrowest / (per_half_width * spacing_hz)).floor() as usize).max(1)
}

/// `set` with every `step`-th line (all for 1).
fn thinned(set: &FrfSet, step: usize) -> Result<FrfSet> {
    if step <= 1 {
        return Ok(set.clone());
    }
    let keep: Vec<usize> = (0..set.n_lines()).step_by(step).collect();
    let mut data = Vec::with_capacity(keep.len() * set.responses().len() * set.references().len());
    for c in 0..set.responses().len() {
        for r in 0..set.references().len() {
            let curve = set.curve(c, r);
            data.extend(keep.iter().map(|&l| curve[l]));
        }
    }
    Ok(FrfSet::new(
        keep.iter().map(|&l| set.freqs_hz()[l]).collect(),
        set.responses().to_vec(),
        set.references().to_vec(),
        set.quantity(),
        data,
    )?)
}

/// Fits the core's law to the FRFs through `setup`'s layered model (module docs); `why` says
/// why it is the answer (empty: it is beside the pole route).
///
/// The basis brackets the start law; where the fitted law leaves what the basis holds (a start
/// law far off: a pole route misled by supports or damping), the basis is built again about
/// the fitted law and the fit run again from it, at most [`FrfFitTuning::max_recentres`] times.
///
/// # Errors
/// A reference or channel not on the part, a basis that cannot be built, or the fit's own
/// errors (too few lines, a fit that does not settle).
pub fn fit_to_frfs(
    setup: &LayeredSetup,
    input: &FrfFitInput,
    why: Vec<WhyFrfFit>,
    spinner: &dyn Reporter,
) -> Result<FrfRoute> {
    let level = fit_level(setup, input.levels)?;
    let level_index = input.levels.iter().position(|l| l.0 == level).unwrap_or(0);
    let correction = DiscretizationCorrection::from_ladder(input.modal, level_index);
    let (mut g_ref, mut ratios) = basis_moduli(setup, input);
    let f = input.set.freqs_hz();
    let spacing = if f.len() > 1 { f[1] - f[0] } else { 0.0 };
    let tuning = setup.tuning.frf_fit;
    let step = line_step(&input.half_widths_hz, spacing, tuning.lines_per_half_width);
    let full = input.set;
    let set = thinned(full, step)?;
    let input = &FrfFitInput {
        set: &set,
        start: input.start,
        modal: input.modal,
        levels: input.levels,
        band_hz: input.band_hz,
        half_widths_hz: Vec::new(),
        ladder_again: input.ladder_again,
    };
    let pole_law = input
        .start
        .map(|law| move |w: f64| law.modulus(w / (2.0 * PI)).unwrap_or_default());
    let mut start: Option<Box<dyn Fn(f64) -> Complex64 + Sync + '_>> =
        pole_law.map(|f| Box::new(f) as Box<dyn Fn(f64) -> Complex64 + Sync>);
    let mut times = [0.0; 2];
    let mut round = 0;
    loop {
        let once = fit_once(
            setup,
            input,
            (level, &correction),
            (g_ref, &ratios),
            start.as_deref(),
            spinner,
        )?;
        times = [times[0] + once.times_s[0], times[1] + once.times_s[1]];
        let [lo, hi] = storage_range(&once.fit, &correction);
        let held = lo >= 0.8 * ratios[0] * g_ref && hi <= 1.25 * ratios[1] * g_ref;
        if held || round == tuning.max_recentres {
            let (fit, laws, other_s) = other_law(setup.core_law, &once, input.set, spinner);
            times[1] += other_s;
            let once = FitOnce { fit, ..once };
            let before = once.times_s;
            let Corrected {
                once,
                mode_by_mode,
                converged_again_hz,
            } = correct_further(setup, input, level_index, g_ref, once, spinner)?;
            for (t, (now, then)) in times.iter_mut().zip(once.times_s.iter().zip(before)) {
                *t += now - then;
            }
            let curves = shown_curves(&once.model, &once.fit, full)?;
            let inputs: Vec<&str> = once.model.model.inputs().iter().map(|i| i.name()).collect();
            let line = text::FrfModelLine {
                level: &setup.plate.plan.level_label(level),
                basis_size: once.model.model.basis_size(),
                g_ref,
                ratios: [ratios[0], ratios[1]],
                recentred: round,
                outside: (!held).then_some([lo, hi]),
                step,
                per_half_width: tuning.lines_per_half_width,
                inputs: &inputs,
            };
            return Ok(FrfRoute {
                model_line: text::frf_model_line(&line),
                correction: once.model.correction,
                mode_by_mode,
                converged_again_hz,
                fit: once.fit,
                why,
                curves,
                times_s: times,
                laws,
            });
        }
        round += 1;
        spinner.stage(&text::frf_basis_again(lo, hi));
        g_ref = (lo * hi).sqrt();
        ratios = bracket(lo, hi, g_ref);
        let fitted = once.fit;
        start = Some(Box::new(move |w: f64| fitted.modulus(w / (2.0 * PI))));
    }
}

/// The level the fit's model is built on: the finest of the ladder's `levels` (each within
/// `inverse.layered_max_dofs`, which the ladder obeys); without levels (no ladder was built),
/// the coarsest, if it is within `inverse.layered_max_dofs`. Its cost per line does not grow
/// with the level (one LU of the reduced basis), its build does (the basis's eigen solves and
/// the inputs' assemblies, on a mesh the ladder has already factorized); the finest level
/// leaves least for the ladder's correction to carry, whose second-order terms and the modes
/// it cannot take move the law (docs/fit.md, "The finest level").
///
/// # Errors
/// The coarsest level above `inverse.layered_max_dofs` (the ladder refused it too), or a plan
/// that cannot be meshed.
fn fit_level(setup: &LayeredSetup, levels: &[([usize; 2], usize)]) -> Result<[usize; 2]> {
    if let Some(level) = levels
        .iter()
        .filter(|l| l.1 <= setup.ladder.max_dofs)
        .map(|l| l.0)
        .next_back()
    {
        return Ok(level);
    }
    let dofs = setup
        .plate
        .dofs(setup.start)
        .context("cannot mesh the FRF fit's layered model")?;
    if dofs > setup.ladder.max_dofs {
        return Err(crate::err!(
            "the layered model's coarsest mesh ({}) has {dofs} dofs, above \
             inverse.layered_max_dofs = {}: raise it to run the FRF fit",
            setup.plate.plan.level_label(setup.start),
            setup.ladder.max_dofs
        ));
    }
    Ok(setup.start)
}

/// The level's model on the converged scale ([`DiscretizationCorrection`]): the law's G*(f)
/// enters the level's stiffness as G*(f)/c(f), so the law fitted is the converged model's and
/// the inputs fitted beside it see no mesh error to take up.
struct OnConvergedScale {
    model: ObservedModel,
    correction: DiscretizationCorrection,
}

impl CoreFrfModel for OnConvergedScale {
    fn n_sensors(&self) -> usize {
        self.model.n_sensors()
    }
    fn n_references(&self) -> usize {
        self.model.n_references()
    }
    fn receptance(&self, omega: f64, core_scale: Complex64) -> Result<LineReceptance, FitError> {
        self.receptance_with_inputs(omega, core_scale, &[])
    }
    fn inputs(&self) -> Vec<Input> {
        self.model.inputs()
    }
    /// H at the level's scale s/c and ∂H/∂s = ∂H/∂(s/c) / c.
    fn receptance_with_inputs(
        &self,
        omega: f64,
        core_scale: Complex64,
        deltas: &[f64],
    ) -> Result<LineReceptance, FitError> {
        let to_level = 1.0 / self.correction.factor(omega / (2.0 * PI));
        let s = core_scale * to_level;
        let mut rec = if deltas.is_empty() {
            CoreFrfModel::receptance(&self.model, omega, s)?
        } else {
            CoreFrfModel::receptance_with_inputs(&self.model, omega, s, deltas)?
        };
        for j in 0..rec.dh_ds.ncols() {
            for i in 0..rec.dh_ds.nrows() {
                rec.dh_ds[(i, j)] *= to_level;
            }
        }
        Ok(rec)
    }
}

/// One basis and one fit.
struct FitOnce {
    model: OnConvergedScale,
    fit: FrfFit,
    /// The fit's settings (its band, the inputs' priors).
    settings: FrfFitSettings,
    /// The laws tried so far: one, or the first's failure where the fallback was fitted.
    laws: LawsCompared,
    /// Seconds of the build and of the fit.
    times_s: [f64; 2],
}

/// The law the fit starts with: the fractional Zener law where the job asks for it, else the
/// generalized Maxwell law over the band (it follows any smooth law; `per_mode` and `none`,
/// which name no law, take it too).
fn first_law(choice: CoreLawChoice, band_hz: [f64; 2]) -> FrfLaw {
    match choice {
        CoreLawChoice::FractionalZener => FrfLaw::FractionalZener,
        _ => FrfLaw::generalized_maxwell_over(band_hz[0], band_hz[1]),
    }
}

/// Whether the job leaves the FRF fit's law open: `auto`, and `per_mode` and `none`, which
/// name no law.
fn law_is_open(choice: CoreLawChoice) -> bool {
    !matches!(
        choice,
        CoreLawChoice::FractionalZener | CoreLawChoice::GeneralizedMaxwell
    )
}

/// Where the job leaves the law open (`auto`, and `per_mode` or `none`, which name none): the
/// fractional Zener law fitted on the same model and lines from the first fit's curve alone,
/// and the law with the lower corrected Akaike criterion kept
/// ([`lamdyn_fit::frf_fit::compare_laws`]). Returns the fit kept, the comparison, and the
/// seconds the second fit took. A second fit that fails leaves the first, and says why.
fn other_law(
    choice: CoreLawChoice,
    once: &FitOnce,
    set: &FrfSet,
    spinner: &dyn Reporter,
) -> (FrfFit, LawsCompared, f64) {
    if once.laws != LawsCompared::One || !law_is_open(choice) {
        return (once.fit.clone(), once.laws.clone(), 0.0);
    }
    let law = FrfLaw::FractionalZener;
    spinner.stage(&text::frf_other_law(law.name(), once.fit.law.name()));
    let t = Instant::now();
    let first = &once.fit;
    let name = law.name();
    let other = fit_from_curve(&once.model, set, law, first, &once.settings);
    let seconds = t.elapsed().as_secs_f64();
    let other = match other {
        Ok(f) => f,
        Err(e) => {
            let error = e.to_string();
            return (
                first.clone(),
                LawsCompared::OtherFailed { name, error },
                seconds,
            );
        }
    };
    match compare_laws(&[first, &other]) {
        Ok(comparison) => {
            let names = vec![first.law.name(), other.law.name()];
            let kept = if comparison.chosen == 0 {
                first.clone()
            } else {
                other
            };
            let compared = LawsCompared::Compared {
                names,
                comparison,
                seconds,
            };
            (kept, compared, seconds)
        }
        Err(e) => (
            first.clone(),
            LawsCompared::OtherFailed {
                name,
                error: e.to_string(),
            },
            seconds,
        ),
    }
}

/// The fit again with what the line leaves of each ladder mode's own mesh error taken out of
/// `once`'s model ([`ObservedModel::take_out_mode_errors`]; [`mode_errors`]), from `once`'s
/// law, on the line `once`'s model is on (level `level`, 0: the coarsest). The line through
/// the modes' errors is fragile (one mode matched to another branch
/// bends it, docs/fit.md), but it corrects every mode; the correction mode by mode holds only
/// near each mode's G* and only where the faces' and the core's scales can take it, so the
/// model keeps the line and each mode it can correct is corrected to its own error. It starts
/// from the line's law, which the fit reached from any start: a start far off (a pole route
/// misled by poles of another branch) may settle elsewhere (docs/fit.md, "A correction mode
/// by mode"). Returns the fit and which modes it took out; None where none could be.
fn fit_mode_by_mode(
    input: &FrfFitInput,
    level: usize,
    g_ref: f64,
    once: &FitOnce,
    spinner: &dyn Reporter,
) -> Result<Option<(FitOnce, ModeByMode)>> {
    let line = &once.model.correction;
    let law = |f_hz: f64| once.fit.modulus(f_hz);
    let found = mode_errors(input.modal, (level, line), &law, g_ref);
    if found.is_empty() {
        return Ok(None);
    }
    let t = Instant::now();
    let mut model = once.model.model.clone();
    let errors: Vec<ModeError> = found.iter().map(|m| m.error).collect();
    let scales = model.take_out_mode_errors(&errors);
    let (mut taken_hz, mut left_hz) = (Vec::new(), Vec::new());
    for (m, scale) in found.iter().zip(&scales) {
        match scale {
            Some(_) => taken_hz.push(m.freq_hz),
            None => left_hz.push(m.freq_hz),
        }
    }
    spinner.stage(&text::frf_mode_by_mode(&taken_hz, &left_hz));
    if taken_hz.is_empty() {
        return Ok(None);
    }
    let model = OnConvergedScale {
        model,
        correction: line.clone(),
    };
    let fitted = refit(once, model, input.set, t.elapsed().as_secs_f64())?;
    let kept = ModeByMode {
        taken_hz,
        left_hz,
        line_law: once.fit.clone(),
    };
    Ok(Some((fitted, kept)))
}

/// `law` fitted on `model` from the curve of `first` alone (no grid of starts), with `first`'s
/// settings otherwise.
fn fit_from_curve(
    model: &OnConvergedScale,
    set: &FrfSet,
    law: FrfLaw,
    first: &FrfFit,
    settings: &FrfFitSettings,
) -> std::result::Result<FrfFit, FitError> {
    let curve = |w: f64| first.modulus(w / (2.0 * PI));
    let alone = FrfFitSettings {
        starts: 0,
        ..settings.clone()
    };
    fit_core_to_frfs(
        model,
        set,
        law,
        first.assembled_modulus_pa,
        Some(&curve),
        &alone,
    )
}

/// The law fitted with the mesh correction's line, corrected further: with its poles out of
/// the law's reach converged again and the law fitted again with the line drawn again
/// ([`converge_out_of_reach`]), then mode by mode ([`fit_mode_by_mode`]).
struct Corrected {
    /// The fit the route answers with (its model on the line it was fitted with).
    once: FitOnce,
    /// The correction mode by mode, where there was one.
    mode_by_mode: Option<ModeByMode>,
    /// The poles converged again (Hz).
    converged_again_hz: Vec<f64>,
}

/// [`Corrected`] from `once`, the law fitted with the line of the ladder's level `level`
/// (0: the coarsest) on a basis at `g_ref`.
fn correct_further(
    setup: &LayeredSetup,
    input: &FrfFitInput,
    level: usize,
    g_ref: f64,
    mut once: FitOnce,
    spinner: &dyn Reporter,
) -> Result<Corrected> {
    let mut modal = None;
    let mut converged_again_hz = Vec::new();
    if let Some((found, hz)) = converge_out_of_reach(setup, input, (level, &once), spinner) {
        let model = OnConvergedScale {
            model: once.model.model.clone(),
            correction: DiscretizationCorrection::from_ladder(&found, level),
        };
        match refit(&once, model, input.set, 0.0) {
            Ok(fitted) => {
                (once, modal, converged_again_hz) = (fitted, Some(found), hz);
            }
            Err(e) => spinner.stage(&text::frf_converge_again_failed(&e.to_string())),
        }
    }
    let input = &FrfFitInput {
        modal: modal.as_deref().unwrap_or(input.modal),
        half_widths_hz: Vec::new(),
        ..*input
    };
    let (once, mode_by_mode) = match fit_mode_by_mode(input, level, g_ref, &once, spinner)? {
        Some((by_mode, kept)) => (by_mode, Some(kept)),
        None => (once, None),
    };
    Ok(Corrected {
        once,
        mode_by_mode,
        converged_again_hz,
    })
}

/// The poles the pole route matched to another branch of the model's modes, converged again
/// on the ladder from the law `once` fitted with the line (level `level`), where they then
/// land within [`MODE_BY_MODE_REACH`] of it: the modal points with those modes in place of the
/// pole route's, and the poles' frequencies (None: no such pole, no ladder to run, or none
/// landed; a ladder that fails is said and left, as is a refit with the new line that fails).
///
/// A pole on another branch carries that branch's level error, with that branch's |S|², and
/// can draw the line to itself; left out, the line loses the mode (docs/fit.md, "Poles on
/// another branch, converged again"). Its own mode's error is the ladder's at the law.
fn converge_out_of_reach(
    setup: &LayeredSetup,
    input: &FrfFitInput,
    (level, once): (usize, &FitOnce),
    spinner: &dyn Reporter,
) -> Option<(Vec<CorePoint>, Vec<f64>)> {
    let again = input.ladder_again?;
    let law = |f_hz: f64| once.fit.modulus(f_hz);
    let points: Vec<usize> = (input.modal.iter().enumerate())
        .filter(|(_, p)| {
            let c = p
                .layered_convergence
                .as_ref()
                .or(p.ladder_estimate.as_ref());
            c.is_some_and(|c| !within_reach(c.core_shear_pa, law(p.freq_hz)))
        })
        .map(|(k, _)| k)
        .collect();
    if points.is_empty() {
        return None;
    }
    let hz: Vec<f64> = points.iter().map(|&k| input.modal[k].freq_hz).collect();
    spinner.stage(&text::frf_converge_again(&hz));
    let starts: Vec<Complex64> = hz.iter().map(|&f| law(f)).collect();
    let found = super::converge_again(setup, again, input.modal, (&points, &starts), spinner);
    let found = match found {
        Ok(found) => found,
        Err(e) => {
            let why = crate::error::chain_text(&e);
            spinner.stage(&text::frf_converge_again_failed(&why));
            return None;
        }
    };
    let mut modal = input.modal.to_vec();
    let mut landed = Vec::new();
    for (&k, m) in points.iter().zip(found) {
        let p = &mut modal[k];
        let Some(m) = m.filter(|m| {
            within_reach(m.core_shear_pa, law(p.freq_hz)) && m.level_corrections.len() > level
        }) else {
            continue;
        };
        (p.layered_convergence, p.ladder_estimate) = (Some(m), None);
        landed.push(p.freq_hz);
    }
    (!landed.is_empty()).then_some((modal, landed))
}

/// `once`'s law fitted again from its curve on `model` (built in `build_s` seconds, counted
/// with the build), with `once`'s settings.
fn refit(
    once: &FitOnce,
    model: OnConvergedScale,
    set: &FrfSet,
    build_s: f64,
) -> std::result::Result<FitOnce, FitError> {
    let t = Instant::now();
    let fit = fit_from_curve(&model, set, once.fit.law.clone(), &once.fit, &once.settings)?;
    Ok(FitOnce {
        model,
        fit,
        settings: once.settings.clone(),
        laws: once.laws.clone(),
        times_s: [
            once.times_s[0] + build_s,
            once.times_s[1] + t.elapsed().as_secs_f64(),
        ],
    })
}

/// Whether the converged `g` (G*, Pa) lies within [`MODE_BY_MODE_REACH`] of the `law`'s G' (a
/// G' of zero or none is not).
fn within_reach(g: Complex64, law: Complex64) -> bool {
    let off = (g.re / law.re).ln().abs();
    off <= MODE_BY_MODE_REACH.ln()
}

/// Modes are corrected one by one where the law passes within this factor of their converged
/// G' (the range over which the correction was checked against a finer mesh:
/// `lamdyn_layered::reduced::mode_errors`' tests, a thirtieth of the error left at 1.5 × and
/// ÷ 1.5 of the mode's G*). A mode further off is a pole matched to another branch of the
/// model's modes, its error one of another mode at another G*.
const MODE_BY_MODE_REACH: f64 = 1.5;

/// What the `line` leaves of each of `modal`'s ladder modes' error on the ladder's level
/// `level` (0: the coarsest), for a model whose core scale is G*/(`g_ref` c(f)), c on the line
/// ([`ModeError`]): with the mode's own correction c_k (its converged G* over the level's,
/// [`lamdyn_layered::convergence::ConvergedMode::level_corrections`]) and S = ∂ln λ/∂ln G*,
/// ε = S (ln c_k − ln c(f_k)) at the scale G*_k/(g_ref c(f_k)) where the model meets the mode.
/// Left out: a mode whose converged G' the `law` (G*(f), Pa) misses by more than
/// [`MODE_BY_MODE_REACH`], and two poles matched to one model mode (which one is right is not
/// known).
fn mode_errors(
    modal: &[CorePoint],
    (level, line): (usize, &DiscretizationCorrection),
    law: &dyn Fn(f64) -> Complex64,
    g_ref: f64,
) -> Vec<LadderModeError> {
    let found: Vec<LadderModeError> = modal
        .iter()
        .filter_map(|p| {
            let c = p
                .layered_convergence
                .as_ref()
                .or(p.ladder_estimate.as_ref())?;
            if !within_reach(c.core_shear_pa, law(p.freq_hz)) {
                return None;
            }
            let on_line = line.factor(p.freq_hz);
            let ln_error = c.sensitivity * (*c.level_corrections.get(level)? - on_line.ln());
            let w = 2.0 * PI * p.freq_hz;
            let error = ModeError {
                core_scale: c.core_shear_pa / (g_ref * on_line),
                rank: c.rank,
                target: w * w,
                ln_error,
            };
            let freq_hz = p.freq_hz;
            ln_error
                .is_finite()
                .then_some(LadderModeError { freq_hz, error })
        })
        .collect();
    let shared = |rank: usize| found.iter().filter(|m| m.error.rank == rank).count() > 1;
    found
        .iter()
        .filter(|m| !shared(m.error.rank))
        .copied()
        .collect()
}

/// A ladder mode's error for [`ObservedModel::take_out_mode_errors`], with its pole's
/// frequency.
#[derive(Debug, Clone, Copy)]
struct LadderModeError {
    /// The pole's frequency, Hz.
    freq_hz: f64,
    /// The error.
    error: ModeError,
}

/// Builds the model on `level` with its basis at `g_ref` × `ratios` (with more modes where the
/// band needs them) and fits the law from `start` (and the grid).
fn fit_once(
    setup: &LayeredSetup,
    input: &FrfFitInput,
    (level, correction): ([usize; 2], &DiscretizationCorrection),
    (g_ref, ratios): (f64, &[f64]),
    start: Option<&(dyn Fn(f64) -> Complex64 + Sync)>,
    spinner: &dyn Reporter,
) -> Result<FitOnce> {
    let set = input.set;
    let basis = FrfBasis {
        modes: setup.modes,
        ratios: ratios.to_vec(),
        ..FrfBasis::default()
    };
    let priors = input_priors(setup);
    let inputs: Vec<Input> = priors.iter().map(|p| p.input).collect();
    let t = Instant::now();
    let (model, held_hz) = observed_model(setup, input, level, g_ref, (&basis, &inputs), spinner)?;
    let model = OnConvergedScale {
        model,
        correction: correction.clone(),
    };
    let build_s = t.elapsed().as_secs_f64();
    let band_hz = [input.band_hz[0], input.band_hz[1].min(held_hz)];
    if band_hz[1] <= band_hz[0] {
        return Err(crate::err!(
            "the FRF fit's basis holds the model only up to {held_hz:.1} Hz, below the band \
             {:.1}-{:.1} Hz: raise inverse.layered_modes",
            input.band_hz[0],
            input.band_hz[1]
        ));
    }
    let law = first_law(setup.core_law, band_hz);
    let mut settings = FrfFitSettings::over(band_hz);
    settings.inputs = priors;
    spinner.stage(&text::frf_fitting(
        law.name(),
        model.model.basis_size(),
        band_hz,
    ));
    let t = Instant::now();
    let first_name = law.name();
    let (fit, laws) = match fit_core_to_frfs(&model, set, law, g_ref, start, &settings) {
        Ok(fit) => (fit, LawsCompared::One),
        Err(e) if law_is_open(setup.core_law) => {
            // The Prony series's slowest and fastest terms can drift where the band does not
            // see them; the four-parameter law is the fallback, from the same starts.
            let failed = LawsCompared::OtherFailed {
                name: first_name,
                error: e.to_string(),
            };
            spinner.stage(&text::frf_law_fallback(first_name));
            let fit = fit_core_to_frfs(
                &model,
                set,
                FrfLaw::FractionalZener,
                g_ref,
                start,
                &settings,
            )
            .map_err(|fz| crate::err!("{e}; the fractional Zener law neither: {fz}"))?;
            (fit, failed)
        }
        Err(e) => return Err(e.into()),
    };
    Ok(FitOnce {
        model,
        fit,
        settings,
        laws,
        times_s: [build_s, t.elapsed().as_secs_f64()],
    })
}

/// The layered model on `level` read at the set's channels, its basis at `g_ref` ×
/// `basis.ratios`, and the frequency (Hz) up to which the basis holds its modes; built again
/// with more modes (up to [`FrfFitTuning::max_modes`]) when that falls below the band.
fn observed_model(
    setup: &LayeredSetup,
    input: &FrfFitInput,
    level: [usize; 2],
    g_ref: f64,
    (basis, inputs): (&FrfBasis, &[Input]),
    spinner: &dyn Reporter,
) -> Result<(ObservedModel, f64)> {
    let set = input.set;
    let (sensors, references) = (points(set.responses()), points(set.references()));
    spinner.stage(&text::frf_model_read(
        &setup.plate.plan.level_label(level),
        sensors.len(),
        references.len(),
    ));
    let build = |basis: &FrfBasis| {
        let model = ObservedModel::build(
            &setup.plate,
            level,
            g_ref,
            basis,
            (&sensors, &references),
            inputs,
        )
        .context("cannot build the FRF fit's layered model")?;
        // The basis holds the modes below BASIS_COVER of its highest one (at its softest core).
        let held_hz = BASIS_COVER * model.model().top_eigenvalue.max(0.0).sqrt() / (2.0 * PI);
        Ok::<_, crate::PipelineError>((model, held_hz))
    };
    let (mut model, mut held_hz) = build(basis)?;
    // A band beyond the basis: once more with the modes the band needs (a plate's modes are
    // about evenly spaced in frequency), up to the tuning's max_modes.
    let max_modes = setup.tuning.frf_fit.max_modes;
    if held_hz < input.band_hz[1] && basis.modes < max_modes {
        let wanted = (basis.modes as f64 * 1.15 * input.band_hz[1] / held_hz.max(1.0)).ceil();
        let more = FrfBasis {
            modes: (wanted as usize).clamp(basis.modes + 1, max_modes),
            ..basis.clone()
        };
        spinner.stage(&text::frf_more_modes(held_hz, input.band_hz[1], more.modes));
        (model, held_hz) = build(&more)?;
    }
    Ok((model, held_hz))
}

/// The lowest and highest G' the level's model takes from the fitted law (G*/c, c the mesh
/// correction) over its band's ends and 20 points between (Pa).
fn storage_range(fit: &FrfFit, correction: &DiscretizationCorrection) -> [f64; 2] {
    let [a, b] = fit.band_hz;
    (0..=20)
        .map(|k| a * (b / a).powf(k as f64 / 20.0))
        .map(|f| (fit.modulus(f) / correction.factor(f)).re)
        .fold([f64::INFINITY, 0.0f64], |r, g| [r[0].min(g), r[1].max(g)])
}

/// The basis's ratios to `g_ref` that bracket G' from `lo` to `hi`: a factor 1.25 beyond them,
/// at least G_ref/2 … 2 G_ref.
fn bracket(lo: f64, hi: f64, g_ref: f64) -> Vec<f64> {
    vec![(0.8 * lo / g_ref).min(0.5), (1.25 * hi / g_ref).max(2.0)]
}

/// The channels as points the model is read or driven at.
fn points(channels: &[Channel]) -> Vec<MeasuredPoint<'_>> {
    channels
        .iter()
        .map(|c| MeasuredPoint {
            name: &c.name,
            point_m: c.point_m,
            direction: c.direction,
        })
        .collect()
}

/// G_ref and the basis's ratios: the start law's G' at the band's ends bracketed (a factor
/// 1.25 beyond them, at least G_ref/2 … 2 G_ref), G_ref their geometric mean; without a law,
/// the modes' starts' median and G_ref/2 … 2 G_ref.
fn basis_moduli(setup: &LayeredSetup, input: &FrfFitInput) -> (f64, Vec<f64>) {
    let ends = input.start.and_then(|law| {
        let lo = law.modulus(input.band_hz[0])?.re;
        let hi = law.modulus(input.band_hz[1])?.re;
        (lo > 0.0 && hi > 0.0 && lo.is_finite() && hi.is_finite()).then(|| (lo.min(hi), lo.max(hi)))
    });
    match ends {
        Some((lo, hi)) => {
            let g_ref = (lo * hi).sqrt();
            (
                g_ref,
                vec![(0.8 * lo / g_ref).min(0.5), (1.25 * hi / g_ref).max(2.0)],
            )
        }
        None => {
            let default = FrfBasis::default();
            (basis_modulus(&setup.starts(input.modal)), default.ratios)
        }
    }
}

/// The inputs fitted beside the law: those with a prior above zero and below the law's wide
/// prior, the supports' only where there are supports. An input known more loosely (the
/// supports' 20–30 % by default) is held at the job's value: fitted beside the law it kept the
/// iteration from settling on the supported roof of `examples/supported-close-pair.toml`
/// (docs/fit.md).
fn input_priors(setup: &LayeredSetup) -> Vec<InputPrior> {
    let wide = setup.tuning.law.wide_prior;
    Input::ALL
        .into_iter()
        .filter(|i| !i.of_supports() || !setup.plate.supports.is_empty())
        .filter_map(|input| {
            let sd = input_rel_sd(input, &setup.plate, &setup.priors);
            (sd > 0.0 && sd < wide).then_some(InputPrior { input, sd })
        })
        .collect()
}

/// The measured and model FRFs over the band at the [`SHOWN_CURVES`] responses of largest RMS
/// in the band, each at its strongest reference.
fn shown_curves(model: &OnConvergedScale, fit: &FrfFit, set: &FrfSet) -> Result<Vec<FrfCurve>> {
    let freqs = set.freqs_hz();
    let lines: Vec<usize> = (0..freqs.len())
        .filter(|&l| freqs[l] >= fit.band_hz[0] && freqs[l] <= fit.band_hz[1])
        .collect();
    let n_r = set.references().len();
    let mut strength: Vec<(f64, usize, usize)> = Vec::new();
    for c in 0..set.responses().len() {
        for r in 0..n_r {
            let curve = set.curve(c, r);
            let power: f64 = lines.iter().map(|&l| curve[l].norm_sqr()).sum();
            strength.push((power, c, r));
        }
    }
    strength.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut shown: Vec<(usize, usize)> = Vec::new();
    for &(_, c, r) in &strength {
        if shown.iter().all(|s| s.0 != c) {
            shown.push((c, r));
        }
        if shown.len() == SHOWN_CURVES {
            break;
        }
    }
    let held = model.inputs();
    let mut deltas = vec![0.0; held.len()];
    for i in &fit.inputs {
        if let Some(k) = held.iter().position(|&h| h == i.input) {
            deltas[k] = i.delta;
        }
    }
    let mut model_values = vec![Vec::with_capacity(lines.len()); shown.len()];
    for &l in &lines {
        let w = 2.0 * PI * freqs[l];
        let s = fit.modulus(freqs[l]) / fit.assembled_modulus_pa;
        let rec = model
            .receptance_with_inputs(w, s, &deltas)
            .map_err(crate::PipelineError::from)
            .context("the FRF fit's model at its answer")?;
        let q = set.quantity().from_receptance(w);
        for (k, &(c, r)) in shown.iter().enumerate() {
            let h = rec.h[(c, r)];
            model_values[k].push(fit.gains[r] * q * Complex64::new(h.re, h.im));
        }
    }
    Ok(shown
        .iter()
        .zip(model_values)
        .map(|(&(c, r), model)| FrfCurve {
            channel: set.responses()[c].name.clone(),
            reference: set.references()[r].name.clone(),
            freqs_hz: lines.iter().map(|&l| freqs[l]).collect(),
            measured: lines.iter().map(|&l| set.curve(c, r)[l]).collect(),
            model,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use lamdyn_frf::Quantity;
    use lamdyn_layered::convergence::ConvergedMode;

    /// Each mode's error is what the line leaves of its own, at the scale where the model on
    /// the line meets the mode, ε = S (ln c_k − ln c(f_k)); a mode on the line has none left;
    /// two poles matched to one model mode give none, nor do modes the law misses by more than
    /// a factor 1.5.
    #[test]
    fn mode_errors_are_what_the_line_leaves() {
        let g = Complex64::new(2e6, 1e6);
        let point = |freq_hz: f64, c: f64, rank: usize| {
            let mut mode = ConvergedMode::exact(g * c, g, rank);
            mode.sensitivity = Complex64::new(0.5, 0.01);
            CorePoint {
                layered_convergence: Some(mode),
                ..crate::frf_route::tests::at(freq_hz)
            }
        };
        let modal = [
            point(10.0, 1.04, 0),
            point(20.0, 1.03, 1),
            point(40.0, 1.01, 2),
            point(41.0, 1.02, 2),
        ];
        let line = DiscretizationCorrection::from_ladder(&modal[..3], 0);
        let law = |_: f64| g;
        let errors = mode_errors(&modal, (0, &line), &law, 1e6);
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert_eq!((errors[0].freq_hz, errors[1].freq_hz), (10.0, 20.0));
        let errors: Vec<ModeError> = errors.iter().map(|m| m.error).collect();
        for (e, p) in errors.iter().zip(&modal) {
            let on_line = line.factor(p.freq_hz);
            let own = p.layered_convergence.as_ref().unwrap();
            let wanted = own.sensitivity * (own.level_corrections[0] - on_line.ln());
            assert!((e.ln_error - wanted).norm() < 1e-12, "{e:?}");
            assert!((e.core_scale - own.core_shear_pa / (1e6 * on_line)).norm() < 1e-12);
            let w = 2.0 * PI * p.freq_hz;
            assert_eq!((e.rank, e.target), (own.rank, w * w));
        }
        // The Theil–Sen line runs through the 10 and 40 Hz modes (the median slope is theirs):
        // nothing is left of the first, and of the 20 Hz mode S (ln 1.03 − ln c(20 Hz)).
        assert!(errors[0].ln_error.norm() < 1e-9, "{:?}", errors[0]);
        assert!(errors[1].ln_error.norm() > 1e-3, "{:?}", errors[1]);
        // Rank 2 is shared by the 40 and 41 Hz poles: both left out.
        assert!(errors.iter().all(|e| e.rank != 2));
        // A law 1.6 times the modes' G' leaves every mode out; 1.45 times keeps them.
        let far = |_: f64| g * 1.6;
        assert!(mode_errors(&modal, (0, &line), &far, 1e6).is_empty());
        let near = |_: f64| g * 1.45;
        assert_eq!(mode_errors(&modal, (0, &line), &near, 1e6).len(), 2);
    }

    /// Four lines per half-width of the narrowest mode, at least one; no modes (or no spacing):
    /// every line.
    #[test]
    fn lines_are_thinned_to_four_per_half_width() {
        assert_eq!(line_step(&[30.0, 45.0], 1.0, 4.0), 7);
        assert_eq!(line_step(&[1.5, 30.0], 0.5, 4.0), 1);
        assert_eq!(line_step(&[], 1.0, 4.0), 1);
        assert_eq!(line_step(&[f64::NAN, 0.0], 1.0, 4.0), 1);
        assert_eq!(line_step(&[30.0], 0.0, 4.0), 1);
    }

    /// A thinned set keeps every step-th line of every curve.
    #[test]
    fn a_thinned_set_keeps_every_step_th_line() {
        let ch = |name: &str| Channel::new(name.to_string(), [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
        let freqs: Vec<f64> = (0..7).map(f64::from).collect();
        let data: Vec<Complex64> = (0..14).map(|k| Complex64::new(f64::from(k), 0.0)).collect();
        let set = FrfSet::new(
            freqs,
            vec![ch("a"), ch("b")],
            vec![ch("h")],
            Quantity::Accelerance,
            data,
        )
        .unwrap();
        let t = thinned(&set, 3).unwrap();
        assert_eq!(t.freqs_hz(), &[0.0, 3.0, 6.0]);
        let re = |c: usize| t.curve(c, 0).iter().map(|v| v.re).collect::<Vec<_>>();
        assert_eq!((re(0), re(1)), (vec![0.0, 3.0, 6.0], vec![7.0, 10.0, 13.0]));
    }
}
