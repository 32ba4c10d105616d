//! The chain of `lamdyn run` and `lamdyn demo`, one stage after the other ([`run_job`]; the
//! table of stages is in the [crate docs](crate)): job (the configuration), measurement, EMA,
//! model, fit, inverse, layered inverse, uncertainty, truth.
//!
//! The slow results (model, EMA, layered model) are cached keyed by their inputs
//! ([`crate::cache`]). Every stage's error is a [`PipelineError::Stage`] naming it.

use crate::cache::{Cache, Key};
use crate::chain::{CorePoint, NoSandwichInverse, StageTime, Truth, nearest_within};
use crate::config::{
    EmaConfig, LayeredConfig, ModelConfig, PaperFitConfig, RunConfig, SandwichConfig,
};
use crate::error::{Context, Result};
use crate::frf_route::{self, FrfOutcome, WhyFrfFit};
use crate::job::{FrfFitChoice, Job, ModelFile, relative};
use crate::measurement::{Measured, read_measurement_section};
use crate::result::ChainResult;
use crate::{AsProgress, PipelineError, Reporter};
use crate::{bail, err};
use crate::{layered, text, uncertainty};
use lamdyn_ema::identify::{EmaResult, identify_with};
use lamdyn_fem::assembly::{Assembly, NodeSpring};
use lamdyn_fem::eigen::{ModalParams, solve_modes};
use lamdyn_fem::mesh::Mesh;
use lamdyn_fem::model::MeshSpec;
use lamdyn_fit::FitError;
use lamdyn_fit::fit::{FitResult, FitSettings, fit};
use lamdyn_fit::misfit::Objective;
use lamdyn_fit::modes::{PeakComparison, compare_peaks};
use lamdyn_fit::probe::{placement_line, probes_with};
use lamdyn_fit::supports::GroundedSupport;
use lamdyn_fit::synthesis::{ModalModel, ResidualTerm};
use lamdyn_frf::{Channel, FrfSet};
use lamdyn_layered::supports::PointSupport;
use lamdyn_material::MaterialError;
use lamdyn_material::causality::{CausalityParams, CausalityVerdict};
use lamdyn_material::laminate::paper_inverse;
use lamdyn_material::laminate::{PaperInverseOptions, SandwichStack};
use lamdyn_material::sandwich::exact_inverse;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of a run beside the job file.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Cache folder (absent: no cache).
    pub cache_dir: Option<PathBuf>,
}

/// Sets faer's global parallelism (used by its operators and decompositions that take no
/// explicit `Par`) to sequential. faer's parallel kernels split their sums by the thread
/// count, so results changed with `RAYON_NUM_THREADS` (the layered inverse's G* at 3e-6,
/// the EMA's damping at 1e-11); lamdyn's own parallelism (elements, right-hand-side blocks,
/// Monte Carlo samples) is split independently of the thread count. Process-wide: the CLI and
/// the Python module call it at start, and [`run_job`] does.
pub fn same_bits_on_any_thread_count() {
    faer::set_global_parallelism(faer::Par::Seq);
}

/// Runs the chain on `job`, read from the file at `path` (paths in it are relative to its
/// folder) with [`Job::read`] and the options' overrides applied
/// ([`Job::with_overrides`]).
///
/// The results are the same bits on any number of rayon threads: the chain parallelizes
/// across independent solves only, and it sets faer's global parallelism to sequential
/// ([`same_bits_on_any_thread_count`]).
///
/// # Errors
/// The first stage that fails (stage named).
pub fn run_job(
    job: Job,
    path: &Path,
    options: &RunOptions,
    spinner: &dyn Reporter,
) -> Result<ChainResult> {
    same_bits_on_any_thread_count();
    let cache = Cache::new(options.cache_dir.clone());
    let mut t = Timed {
        spinner,
        timings: Vec::new(),
    };
    let mut warnings = Vec::new();
    let config = t.stage("job", || Ok((RunConfig::resolve(&job, path)?, false)))?;
    let measured = t.stage("measurement", || {
        let m = &config.measurement;
        let measured = read_measurement_section(&m.section, m.band_hz, &m.base, &m.job_path)?;
        Ok((measured, false))
    })?;
    warnings.extend(crate::io::encoding_notes([path]));
    warnings.extend(measured.warnings.iter().cloned());
    let ema = t.stage("ema", || {
        run_ema(&config.ema, &measured.set, &cache, spinner)
    })?;
    let pole_checks = pole_checks(&mut t, &config, &measured, &cache)?;
    // The model stage stays fatal: it is where the measurement's channels are checked against
    // the part (a sensor off the plate, a wrong unit).
    let (model, model_line) = t.stage("model", || {
        build_model(&config.model, &measured.set, &cache, spinner)
    })?;
    let paper = paper_route(&mut t, &config, &ema, &model, &measured.set)?;
    warnings.extend(paper.warnings());
    let fit_result = paper.fit.as_ref();
    let SandwichRoute {
        mut modal,
        curve,
        causality,
        freqs_hz,
    } = sandwich_route(&mut t, &config, (fit_result, &ema), &model, &measured.set)?;
    let data = layered::Observations {
        frfs: &measured.set,
        ema: &ema,
        checks: &pole_checks,
    };
    let route = layered_route(&mut t, &config.layered, data, &mut modal, &cache)?;
    layered::to_real_frequency(&mut modal, route.law.as_ref());
    let frf = frf_fit_stage(&mut t, (&config, &route), data, &modal, &cache);
    let mc = uncertainty_stage(&mut t, &config, fit_result, freqs_hz)?;
    let truth = truth_stage(&mut t, config.truth.as_deref())?;
    warnings.extend(cache.notes());
    crate::warnings::collect_warnings(
        &config,
        &measured,
        &ema,
        fit_result,
        &modal,
        &causality,
        &mut warnings,
    );
    let PaperRoute { fit, curves, error } = paper;
    let SandwichConfig {
        stack,
        kinematics,
        paper: paper_options,
    } = config.sandwich;
    Ok(ChainResult {
        job,
        job_path: path.to_path_buf(),
        measured,
        ema,
        model_line,
        layered_line: route.line,
        core_law: route.law,
        frf,
        fit,
        paper_route_error: error,
        fit_lines: curves.lines,
        measured_rms: curves.measured_rms,
        fitted_rms: curves.fitted_rms,
        table3: curves.table3,
        stack,
        kinematics,
        paper_options,
        modal,
        curve,
        causality,
        uncertainty: mc,
        truth,
        warnings,
        timings: t.timings,
    })
}

/// The paper's and the exact inverse as run: at the modal frequencies and on the curve.
struct SandwichRoute {
    /// The modal points, each with its start for the layered route.
    modal: Vec<CorePoint>,
    /// The curve's points.
    curve: Vec<CorePoint>,
    /// The Kramers–Kronig verdicts of both inverses on the curve.
    causality: [Vec<Option<CausalityVerdict>>; 2],
    /// The modal frequencies, then the curve's, Hz (the Monte Carlo's lines).
    freqs_hz: Vec<f64>,
}

/// Stage "inverse" ([`inverses`]) at the modal frequencies of the paper's fit and the EMA and
/// on the curve; where the paper's fit failed, each modal point's start from its pole
/// ([`starts_from_the_poles`]).
fn sandwich_route(
    t: &mut Timed,
    config: &RunConfig,
    (fit, ema): (Option<&FitResult>, &EmaResult),
    model: &ModalModel,
    set: &FrfSet,
) -> Result<SandwichRoute> {
    let modal_hz = modal_frequencies(fit, ema);
    let curve_hz = fit.map_or_else(Vec::new, |f| curve_grid(&config.paper_fit, f, set));
    let hz = [modal_hz.as_slice(), curve_hz.as_slice()];
    let (mut modal, curve, causality) = t.stage("inverse", || {
        Ok((inverses(&config.sandwich, fit, hz)?, false))
    })?;
    if fit.is_none() {
        starts_from_the_poles(model, ema, &mut modal);
    }
    Ok(SandwichRoute {
        modal,
        curve,
        causality,
        freqs_hz: hz.concat(),
    })
}

/// Stage "truth": the truth of a virtual test, when the job names one.
fn truth_stage(t: &mut Timed<'_>, path: Option<&Path>) -> Result<Option<Truth>> {
    match path {
        Some(path) => Ok(Some(t.stage("truth", || Ok((read_truth(path)?, false)))?)),
        None => Ok(None),
    }
}

/// Stage "uncertainty": the Monte Carlo over the stack and the paper's fit at `freqs_hz`,
/// when the job asks for samples and the paper's route and a three-layer sandwich are there.
fn uncertainty_stage(
    t: &mut Timed<'_>,
    config: &RunConfig,
    fit: Option<&FitResult>,
    freqs_hz: Vec<f64>,
) -> Result<Option<uncertainty::McResult>> {
    let (Some(fit), Some(_)) = (fit, &config.sandwich.stack) else {
        return Ok(None);
    };
    if config.uncertainty.options.samples == 0 {
        return Ok(None);
    }
    let spinner = t.spinner;
    let paper = config.sandwich.paper;
    let mc = t.stage("uncertainty", || {
        let mc = monte_carlo(&config.uncertainty, fit, paper, freqs_hz, spinner)?;
        Ok((mc, false))
    })?;
    Ok(Some(mc))
}

/// The paper's and the exact inverse at the modal frequencies and on the curve, and the
/// Kramers–Kronig verdicts of both on the curve.
type Inverses = (
    Vec<CorePoint>,
    Vec<CorePoint>,
    [Vec<Option<CausalityVerdict>>; 2],
);

/// Stage "inverse": [`Inverses`] of the fitted law at `modal_hz` and `curve_hz`.
fn inverses(
    sandwich: &SandwichConfig,
    fit: Option<&FitResult>,
    [modal_hz, curve_hz]: [&[f64]; 2],
) -> Result<Inverses> {
    let at = |f: &[f64]| {
        f.iter()
            .map(|&f| core_point(sandwich.stack.as_ref(), &sandwich.paper, fit, f))
            .collect::<Vec<_>>()
    };
    let (modal, curve) = (at(modal_hz), at(curve_hz));
    let kk = [
        causality(&curve, CorePoint::paper_g)?,
        causality(&curve, CorePoint::exact_g)?,
    ];
    Ok((modal, curve, kk))
}

/// Stage "uncertainty": the paper's route's Monte Carlo over the stack's priors and the fit's
/// covariance at `freqs_hz`.
fn monte_carlo(
    config: &crate::config::UncertaintyConfig,
    fit: &FitResult,
    paper: PaperInverseOptions,
    freqs_hz: Vec<f64>,
    spinner: &dyn Reporter,
) -> Result<uncertainty::McResult> {
    let input = uncertainty::McInput {
        stack: &config.stack,
        fit,
        options: &config.options,
        kinematics: config.kinematics,
        paper,
        freqs_hz,
    };
    uncertainty::monte_carlo(&input, spinner)
}

/// The stages' progress and timings as they run.
struct Timed<'a> {
    spinner: &'a dyn Reporter,
    timings: Vec<StageTime>,
}

impl Timed<'_> {
    /// Runs `f` as stage `name`: progress, timing (with whether `f` took its result from the
    /// cache), and "stage 'NAME' failed" on error.
    fn stage<T>(&mut self, name: &'static str, f: impl FnOnce() -> Result<(T, bool)>) -> Result<T> {
        self.spinner.stage(&format!("stage '{name}'"));
        let t = Instant::now();
        let (value, cached) = f().map_err(|e| PipelineError::Stage {
            stage: name,
            source: Box::new(e),
        })?;
        self.timings.push(StageTime {
            name,
            seconds: t.elapsed().as_secs_f64(),
            cached,
        });
        Ok(value)
    }
}

/// The identifications beside the whole that the layered route reads each pole's scatter
/// from (none without the layered route): by response group, at other model orders, and
/// without each hammer hit (FRF or UFF data, or too few hits: no stage at all).
fn pole_checks(
    t: &mut Timed,
    config: &RunConfig,
    measured: &Measured,
    cache: &Cache,
) -> Result<layered::PoleChecks> {
    if config.layered.setup.is_none() {
        return Ok(layered::PoleChecks::default());
    }
    let spinner = t.spinner;
    let set = &measured.set;
    let ema = &config.ema;
    Ok(layered::PoleChecks {
        groups: t.stage("ema by response group", || {
            response_group_emas(ema, set, cache, spinner)
        })?,
        orders: t.stage("ema at other model orders", || {
            other_order_emas(ema, set, cache, spinner)
        })?,
        hits: if measured.has_hits_to_leave_out() {
            t.stage("ema without each hit", || {
                let m = (&config.measurement.section, config.measurement.band_hz);
                let sets = crate::measurement::without_each_hit(m, measured);
                without_each_hit_emas(ema, &sets.unwrap_or_default(), cache, spinner)
            })?
        } else {
            Vec::new()
        },
    })
}

/// The paper's route as run: the effective modulus fitted to the FRFs on the shell model, or
/// why it has no result.
struct PaperRoute {
    /// The fit; `None` when it failed and the layered route went on alone.
    fit: Option<FitResult>,
    /// Its misfit's lines and RMS curves.
    curves: FitCurves,
    /// Why it has no result.
    error: Option<String>,
}

impl PaperRoute {
    /// The warnings it leaves for the report.
    fn warnings(&self) -> Vec<String> {
        match (&self.fit, &self.error) {
            (Some(f), _) => f.warnings.iter().map(|w| format!("fit: {w}")).collect(),
            (None, Some(why)) => vec![text::paper_route_failed(why)],
            (None, None) => Vec::new(),
        }
    }
}

/// Stage "fit" ([`run_fit`]) and whether the chain goes on without it
/// ([`without_the_paper_route`]).
fn paper_route(
    t: &mut Timed,
    config: &RunConfig,
    ema: &EmaResult,
    model: &ModalModel,
    set: &FrfSet,
) -> Result<PaperRoute> {
    let fitted = t.stage("fit", || {
        Ok((run_fit(&config.paper_fit, model, set)?, false))
    });
    Ok(
        match without_the_paper_route(&config.layered, ema, fitted)? {
            Ok((fit, curves)) => PaperRoute {
                fit: Some(fit),
                curves,
                error: None,
            },
            Err(e) => PaperRoute {
                fit: None,
                curves: FitCurves::default(),
                error: Some(crate::error::chain_text(&e)),
            },
        },
    )
}

/// The law fitted to the layered modes, or why it failed; `None` when not asked for.
type LawResult = Option<std::result::Result<lamdyn_fit::joint::CoreLawFit, FitError>>;

/// What the layered route leaves for the stages after it.
struct LayeredRoute {
    /// Its line (None: not run).
    line: Option<String>,
    /// The law over all modes.
    law: LawResult,
    /// The ladder's levels (elements, dofs) of its last run.
    levels: Vec<([usize; 2], usize)>,
}

/// The layered route (when `inverse.layered`): stage "layered inverse" on the
/// configuration's [`layered::LayeredSetup`], then "core law"; where the law finds the
/// supports far from the job's, the ladder and the law again at those.
fn layered_route(
    t: &mut Timed,
    config: &LayeredConfig,
    data: layered::Observations,
    modal: &mut [CorePoint],
    cache: &Cache,
) -> Result<LayeredRoute> {
    let spinner = t.spinner;
    let (mut line, mut coarsest, mut levels) = (None, None, Vec::new());
    let setup = config.setup.as_ref();
    if let Some(s) = setup {
        let outcome = t.stage("layered inverse", || {
            let outcome = layered::run(s, data, modal, cache, spinner)?;
            let cached = outcome.all_cached;
            Ok((outcome, cached))
        })?;
        (line, coarsest) = (Some(outcome.line), outcome.coarsest);
        levels = outcome.levels;
    }
    let law = t.stage("core law", || {
        let tuning = setup.map(|s| s.tuning.law.clone()).unwrap_or_default();
        let law = layered::fit_law(config.core_law, &tuning, modal, coarsest.as_ref());
        Ok((law, false))
    })?;
    let Some((setup, at)) =
        setup.and_then(|s| Some((s, layered::supports_found(s, law.as_ref())?)))
    else {
        return Ok(LayeredRoute { line, law, levels });
    };
    let moved = setup.at_supports(at);
    let again = t.stage("layered inverse at the supports found", || {
        let outcome = layered::run(&moved, data, modal, cache, spinner)?;
        let cached = outcome.all_cached;
        Ok((outcome, cached))
    })?;
    line = Some(text::rerun_at_supports(&again.line, at));
    let law = t.stage("core law at the supports found", || {
        let tuning = &moved.tuning.law;
        let law = layered::fit_law(moved.core_law, tuning, modal, again.coarsest.as_ref());
        Ok((law, false))
    })?;
    Ok(LayeredRoute {
        line,
        law,
        levels: again.levels,
    })
}

/// Stage "FRF fit" where `inverse.frf_fit` and the rule call for it ([`crate::frf_route`]): the
/// core's law fitted to the FRFs through the layered model of `setup` on one of the ladder's
/// `levels`. A failure is kept in
/// the outcome (the pole route stays the answer), not raised.
fn frf_fit_stage(
    t: &mut Timed,
    (config, route): (&RunConfig, &LayeredRoute),
    data: layered::Observations,
    modal: &[CorePoint],
    cache: &Cache,
) -> FrfOutcome {
    let (law, levels) = (route.law.as_ref(), route.levels.as_slice());
    // The setup as the job gives it, supports included: the FRF fit fits the supports itself
    // under their priors, and does not take the ones the pole route's law found.
    let Some(setup) = &config.layered.setup else {
        return FrfOutcome::NotRun("the layered route is off (inverse.layered = false)");
    };
    let ema_band_hz = config.ema.band_hz;
    let config = &config.layered;
    let rule = setup.tuning.frf_fit.rule;
    let mut why = frf_route::reasons(&data.ema.modes, &data.ema.set_aside, modal, rule);
    match config.frf_fit {
        FrfFitChoice::Never => return FrfOutcome::NotRun("inverse.frf_fit = \"never\""),
        FrfFitChoice::Always => why.insert(0, WhyFrfFit::Asked),
        FrfFitChoice::Auto if why.is_empty() => {
            return FrfOutcome::NotRun(text::POLE_ROUTE_HOLDS);
        }
        FrfFitChoice::Auto => {}
    }
    let input = layered::FrfFitInput {
        set: data.frfs,
        band_hz: frf_band(ema_band_hz, data.ema),
        start: law.and_then(|l| l.as_ref().ok()),
        modal,
        levels,
        // The poles set aside as smears over clusters still mark resonances in the FRFs the
        // fit must resolve: their half-widths thin the lines too.
        half_widths_hz: data
            .ema
            .modes
            .iter()
            .chain(&data.ema.set_aside)
            .map(|m| m.damping_ratio * m.freq_hz)
            .collect(),
        ladder_again: Some(layered::LadderAgain {
            cache,
            ema: data.ema,
        }),
    };
    let spinner = t.spinner;
    let outcome = t.stage("FRF fit", || {
        Ok((
            layered::fit_to_frfs(setup, &input, why.clone(), spinner),
            false,
        ))
    });
    match outcome {
        Ok(Ok(route)) => FrfOutcome::Fitted(Box::new(route)),
        Ok(Err(error)) | Err(error) => FrfOutcome::Failed { why, error },
    }
}

/// The FRF fit's band: the EMA's (`ema_band_hz`, else the data's), from half the lowest
/// identified pole (smears set aside included) at least (a free part's rigid-body modes make
/// the model singular at 0 Hz).
fn frf_band(ema_band_hz: Option<[f64; 2]>, ema: &EmaResult) -> [f64; 2] {
    let [lo, hi] = ema_band_hz.unwrap_or(ema.band_hz);
    let lowest = ema
        .modes
        .iter()
        .chain(&ema.set_aside)
        .map(|m| m.freq_hz)
        .fold(f64::INFINITY, f64::min);
    let floor = if lowest.is_finite() {
        0.5 * lowest
    } else {
        1.0
    };
    [lo.max(floor).max(1e-3), hi]
}

fn channels_key(key: Key, channels: &[Channel]) -> Key {
    channels.iter().fold(key, |k, c| {
        let k = k.bytes(c.name.as_bytes());
        c.point_m
            .iter()
            .chain(&c.direction)
            .fold(k, |k, v| k.f64(*v))
    })
}

/// The modal identification again on each of `config.response_groups` groups of the
/// responses (the measurement points dealt round-robin in the order they first appear, every
/// direction of a point in one group; none when there are fewer than two points per group),
/// each cached like the whole. A pole the whole set pins by its stabilization diagram can
/// still move with the responses it is read from (noise at a weakly excited mode, a close mode
/// seen by some points; [`crate::config::RESPONSE_GROUPS`]). The spread of the groups' poles
/// is that uncertainty ([`crate::layered`]'s pole scatter). A group whose identification fails
/// is left out.
fn response_group_emas(
    config: &EmaConfig,
    set: &FrfSet,
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(Vec<EmaResult>, bool)> {
    let groups = config.response_groups;
    let mut points: Vec<[f64; 3]> = Vec::new();
    let group_of: Vec<usize> = set
        .responses()
        .iter()
        .map(|c| {
            let k = points
                .iter()
                .position(|p| *p == c.point_m)
                .unwrap_or_else(|| {
                    points.push(c.point_m);
                    points.len() - 1
                });
            k % groups
        })
        .collect();
    if points.len() < 2 * groups {
        return Ok((Vec::new(), true));
    }
    let mut subsets = Vec::new();
    for g in 0..groups {
        let keep: Vec<usize> = (0..group_of.len()).filter(|&i| group_of[i] == g).collect();
        subsets.push((keep.len(), set.with_responses(&keep)?));
    }
    Ok(successful(subsets.iter().enumerate().map(
        |(g, (n, subset))| {
            spinner.stage(&text::ema_group(g, groups, *n));
            run_ema(config, subset, cache, &crate::Silent)
        },
    )))
}

/// The identifications of `runs` that succeed (one that fails is left out) and whether each of
/// those came from the cache.
fn successful(runs: impl Iterator<Item = Result<(EmaResult, bool)>>) -> (Vec<EmaResult>, bool) {
    let mut out = Vec::new();
    let mut all_cached = true;
    for (r, cached) in runs.flatten() {
        all_cached &= cached;
        out.push(r);
    }
    (out, all_cached)
}

/// The modal identification again with the highest model order of the stabilization diagram
/// at each of [`EmaConfig::other_max_orders`], each cached like the whole. The poles are
/// refined on every FRF, but from the diagram's selection, and a mode the selection misses at
/// one order is fitted by the others ([`crate::config::OTHER_ORDERS`]). The spread across
/// orders is that uncertainty ([`crate::layered`]'s pole scatter). An order whose
/// identification fails is left out.
fn other_order_emas(
    config: &EmaConfig,
    set: &FrfSet,
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(Vec<EmaResult>, bool)> {
    Ok(successful(config.other_max_orders().into_iter().map(
        |order| {
            spinner.stage(&text::ema_order(order));
            run_ema_to_order(config, set, cache, &crate::Silent, order)
        },
    )))
}

/// The modal identification again on the FRFs without each hammer hit in turn
/// ([`crate::measurement::without_each_hit`]; none unless the measurement is time data of at
/// least three hits), each cached like the whole. An identification that fails is left out;
/// sets that cannot be read (the whole was) leave the jackknife out.
fn without_each_hit_emas(
    config: &EmaConfig,
    sets: &[FrfSet],
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(Vec<EmaResult>, bool)> {
    let (out, all_cached) = successful(sets.iter().enumerate().map(|(k, set)| {
        spinner.stage(&text::ema_without_hit(k, sets.len()));
        run_ema(config, set, cache, &crate::Silent)
    }));
    // Nothing to run (FRF data, fewer than three hits) is not a cache hit.
    Ok((out, all_cached && !sets.is_empty()))
}

/// Modal identification, from the cache when the FRFs and settings are unchanged.
fn run_ema(
    config: &EmaConfig,
    set: &FrfSet,
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(EmaResult, bool)> {
    run_ema_to_order(config, set, cache, spinner, config.max_order)
}

/// [`run_ema`] with the stabilization diagram's highest model order `max_order`.
fn run_ema_to_order(
    config: &EmaConfig,
    set: &FrfSet,
    cache: &Cache,
    spinner: &dyn Reporter,
    max_order: usize,
) -> Result<(EmaResult, bool)> {
    let settings = config.settings(max_order);
    let mut key = Key::new(concat!(
        "ema ",
        env!("CARGO_PKG_VERSION"),
        " ",
        env!("LAMDYN_SOURCE_HASH")
    ))
    .bytes(format!("{settings:?}").as_bytes());
    key = channels_key(key, set.responses());
    key = channels_key(key, set.references());
    for f in set.freqs_hz() {
        key = key.f64(*f);
    }
    for h in set.data() {
        key = key.f64(h.re).f64(h.im);
    }
    let keep_smears = config.keep_smears;
    let set_aside = |mut r: EmaResult| {
        if !keep_smears {
            r.set_aside_smears();
        }
        r
    };
    if let Some(bytes) = cache.get("ema", key) {
        if let Ok(r) = serde_json::from_slice::<EmaResult>(&bytes) {
            return Ok((set_aside(r), true));
        }
    }
    let r = identify_with(set, &settings, &|step| {
        spinner.stage(&format!("stage 'ema': {step}"))
    })
    .context("modal identification")?;
    cache.put("ema", key, &serde_json::to_vec(&r)?)?;
    Ok((set_aside(r), false))
}

/// The modal model of the FE model on the measured channels, cached.
fn build_model(
    config: &ModelConfig,
    set: &FrfSet,
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<((ModalModel, String), bool)> {
    let ModelFile {
        spec,
        dir: spec_dir,
        label,
    } = &config.file;
    let modes = config.modes.unwrap_or(spec.solver.modes);
    if modes < 7 {
        bail!("model.modes: {modes}: keep at least the 6 rigid-body modes and one elastic mode");
    }
    let tol = config.tolerance_m;
    let mut key = Key::new(concat!(
        "model with its line ",
        env!("CARGO_PKG_VERSION"),
        " ",
        env!("LAMDYN_SOURCE_HASH")
    ))
    .bytes(format!("{spec:?}").as_bytes())
    .bytes(&(modes as u64).to_le_bytes())
    .bytes(&[u8::from(config.residual)])
    .f64(tol)
    .bytes(format!("{:?}", config.sensor_mapping).as_bytes());
    if let MeshSpec::Gmsh { file, .. } = &spec.mesh {
        let p = relative(spec_dir, Path::new(file));
        key = key
            .bytes(&std::fs::read(&p).with_context(|| format!("cannot read '{}'", p.display()))?);
    }
    key = channels_key(key, set.responses());
    key = channels_key(key, set.references());
    if !config.supports.is_empty() {
        key = key.bytes(format!("{:?}", config.supports).as_bytes());
    }
    let line = |n_nodes: String, n_el: String| {
        format!(
            "{label}: {n_nodes} nodes, {n_el} elements, {modes} modes{}, E_ref = {:.4e} Pa, h = \
             {:.4} mm, rho = {:.1} kg/m^3",
            if config.residual {
                " + residual term"
            } else {
                ""
            },
            spec.material.young_pa,
            spec.material.thickness_m * 1e3,
            spec.material.density_kg_m3
        )
    };
    if let Some(bytes) = cache.get("model", key) {
        if let Some((text, model)) = unpack_model(&bytes) {
            if let Ok(m) = ModalModel::from_cache_bytes(model) {
                return Ok(((m, format!("{text} (cached)")), true));
            }
        }
    }
    let (mesh, node_springs) = spec
        .build(spec_dir)
        .with_context(|| format!("invalid model {label}"))?;
    let supports = shell_supports(&mesh, &node_springs, &config.supports)
        .with_context(|| format!("the part's supports on model {label}"))?;
    let asm = Assembly::new(&mesh, &spec.material, &[])
        .with_context(|| format!("invalid model {label}"))?;
    let mapping = config.sensor_mapping;
    let resp = probes_with(&mesh, set.responses(), tol, mapping).context(
        "the response channels do not lie on the model (measurement.channels vs model; \
         see measurement.tolerance_m)",
    )?;
    let refs = probes_with(&mesh, set.references(), tol, mapping).context(
        "the reference channels do not lie on the model (measurement.channels vs model)",
    )?;
    let sol = solve_modes(&asm, &ModalParams::lowest(modes), &AsProgress(spinner))?;
    let residual = if config.residual {
        ResidualTerm::Static
    } else {
        ResidualTerm::None
    };
    let young = spec.material.young_pa;
    let model = ModalModel::supported(&asm, &sol, &resp, &refs, young, residual, &supports)?;
    let mut text = format!(
        "{}; {}",
        line(
            mesh.nodes().len().to_string(),
            format!("{} {}", mesh.n_elements(), mesh.order().name()),
        ),
        placement_line(mapping, &[resp.as_slice(), refs.as_slice()].concat())
    );
    if !supports.is_empty() {
        text.push_str(&text::shell_model_on_supports(
            config.supports.len(),
            node_springs.len(),
            model.eigenvalues().len() - sol.modes.len(),
            &model.support_hz(),
        ));
    }
    cache.put("model", key, &pack_model(&text, &model.to_cache_bytes()))?;
    Ok(((model, text), false))
}

/// The part's supports on the shell model: `[[inverse.supports]]` placed on its plan and the
/// model file's node springs ([`GroundedSupport`]).
fn shell_supports(
    mesh: &Mesh,
    node_springs: &[NodeSpring],
    supports: &[PointSupport],
) -> Result<Vec<GroundedSupport>> {
    let mut out = GroundedSupport::on_plan(mesh, supports)?;
    let groups = out.iter().map(|s| s.group + 1).max().unwrap_or(0);
    for s in node_springs
        .iter()
        .flat_map(GroundedSupport::from_node_spring)
    {
        out.push(GroundedSupport {
            group: groups + s.group,
            ..s
        });
    }
    Ok(out)
}

/// A cache entry of the shell model: its description line (mesh size, sensor placement),
/// then the model's bytes; the line's length first, as 8 little-endian bytes.
fn pack_model(text: &str, model: &[u8]) -> Vec<u8> {
    let mut out = (text.len() as u64).to_le_bytes().to_vec();
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(model);
    out
}

/// The description line and the model's bytes of a [`pack_model`] entry; `None` for bytes
/// that are not one.
fn unpack_model(bytes: &[u8]) -> Option<(&str, &[u8])> {
    let (len, rest) = bytes.split_first_chunk::<8>()?;
    let len = usize::try_from(u64::from_le_bytes(*len)).ok()?;
    let text = std::str::from_utf8(rest.get(..len)?).ok()?;
    Some((text, &rest[len..]))
}

/// The paper's fit's misfit lines and RMS curves (paper Fig. 5, Table 3).
#[derive(Debug, Clone, Default)]
struct FitCurves {
    /// Lines of the misfit.
    lines: Vec<usize>,
    /// RMS FRF over the responses, measured, per line (paper Fig. 5).
    measured_rms: Vec<f64>,
    /// As `measured_rms`, from the fitted law.
    fitted_rms: Vec<f64>,
    /// Table 3: peaks of the RMS curves.
    table3: Vec<PeakComparison>,
}

/// The paper's route's fit as run: its result, or, when the layered route is on and can go on
/// alone, why it failed. The layered route does not need the fit: it reads the EMA's poles and
/// starts each from the modulus its pole implies on the shell model (`starts_from_the_poles`).
/// It goes on alone where every pole is damped at most `max_damping_alone`, or where the FRF
/// fit may run (`inverse.frf_fit` not `never`): a fit that finds no resonance peak at all is a
/// sign of poles the EMA cannot resolve, and the rule of [`crate::frf_route`] then makes the fit to
/// the FRFs the answer. Without the layered route the paper's is the only answer and its
/// failure is the run's.
///
/// # Errors
/// The fit's error when `inverse.layered` is off, or when a pole is damped more than
/// `max_damping_alone` and the FRF fit is off (the poles named).
fn without_the_paper_route<T>(
    config: &LayeredConfig,
    ema: &EmaResult,
    route: Result<T>,
) -> Result<std::result::Result<T, PipelineError>> {
    let e = match route {
        Ok(t) => return Ok(Ok(t)),
        Err(e) if config.setup.is_none() => return Err(e),
        Err(e) => e,
    };
    let damped = crate::warnings::damped_beyond(&ema.modes, config.max_damping_alone);
    if damped.is_empty() || config.frf_fit != FrfFitChoice::Never {
        return Ok(Err(e));
    }
    Err(e).context(text::poles_alone_refused(
        &damped,
        ema.modes.len(),
        config.max_damping_alone,
    ))
}

/// The fit and its RMS curves and Table 3.
fn run_fit(
    config: &PaperFitConfig,
    model: &ModalModel,
    set: &FrfSet,
) -> Result<(FitResult, FitCurves)> {
    let mut settings = FitSettings::new(config.law, config.misfit.clone());
    settings.covariance = config.covariance;
    settings.prominence = config.prominence;
    if config.misfit.reference >= set.references().len() {
        bail!(
            "fit.misfit.reference = {} but the measurement has {} reference(s), counted from 0",
            config.misfit.reference,
            set.references().len()
        );
    }
    let r = fit(model, set, &settings)?;
    if r.peaks.is_empty() {
        bail!("no resonance peak in the fit band: check fit.misfit.band_hz");
    }
    let objective = Objective::new(model, set, settings.misfit.clone())?;
    let fitted = objective.model_rms(&|w| r.modulus(w));
    let table3 = compare_peaks(
        set.freqs_hz(),
        objective.measured_rms(),
        &fitted,
        objective.lines(),
        settings.prominence,
    );
    let curves = FitCurves {
        lines: objective.lines().to_vec(),
        measured_rms: objective.measured_rms().to_vec(),
        fitted_rms: fitted,
        table3,
    };
    Ok((r, curves))
}

/// The modal frequencies, Hz, increasing: the fit's RMS peaks (paper Table 3) and every EMA
/// mode that no peak claims (every EMA mode without a fit). A peak claims the EMA mode nearest it
/// within 2 %; a mode left unclaimed (weakly excited, one of a close pair, or a support's bounce
/// that the free shell model lacks) still has a pole, and the layered inverse needs nothing else.
pub fn modal_frequencies(r: Option<&FitResult>, ema: &EmaResult) -> Vec<f64> {
    let peaks: Vec<f64> = r
        .map_or(&[][..], |r| &r.peaks)
        .iter()
        .map(|p| p.freq_hz)
        .collect();
    let claimed: Vec<usize> = peaks
        .iter()
        .filter_map(|&f| nearest_within(ema, f, 0.02))
        .collect();
    let mut hz: Vec<f64> = peaks
        .into_iter()
        .chain(
            ema.modes
                .iter()
                .enumerate()
                .filter(|(k, _)| !claimed.contains(k))
                .map(|(_, m)| m.freq_hz),
        )
        .collect();
    hz.sort_by(f64::total_cmp);
    hz
}

/// Lines of the curves: the job's, else 40 log-spaced lines over the modal frequencies
/// (per-mode law: only there is it identified) or the fit band.
fn curve_grid(config: &PaperFitConfig, r: &FitResult, set: &FrfSet) -> Vec<f64> {
    if let Some(f) = &config.curve_hz {
        return f.clone();
    }
    let peaks: Vec<f64> = r.peaks.iter().map(|p| p.freq_hz).collect();
    let (lo, hi) = match (config.law, config.misfit.band_hz) {
        (lamdyn_fit::fit::LawKind::PerMode, _) | (_, None) => (
            peaks.first().copied().unwrap_or(set.freqs_hz()[0].max(1.0)),
            peaks
                .last()
                .copied()
                .unwrap_or(set.freqs_hz()[set.n_lines() - 1]),
        ),
        (_, Some([a, b])) => (a.max(set.freqs_hz()[1]), b),
    };
    if hi <= lo {
        return vec![lo];
    }
    let n = 40;
    (0..n)
        .map(|k| lo * (hi / lo).powf(k as f64 / (n - 1) as f64))
        .collect()
}

/// Both inverses at `f` Hz for the fitted law.
/// The paper's and the exact inverse at `f` on `stack` (`None`: not a sandwich, both say so).
fn core_point(
    stack: Option<&SandwichStack>,
    options: &PaperInverseOptions,
    r: Option<&FitResult>,
    f: f64,
) -> CorePoint {
    let w = 2.0 * PI * f;
    let e = r.map(|r| r.modulus(w));
    let sd = r.and_then(|r| r.modulus_uncertainty(w).2);
    CorePoint {
        freq_hz: f,
        e_eff_pa: e,
        e_pole_pa: None,
        e_sd: sd,
        paper: sandwich_inverse(stack, e, |s, e| paper_inverse(s, w, e, options)),
        exact: sandwich_inverse(stack, e, |s, e| exact_inverse(s, w, e, options.kinematics)),
        layered: None,
        layered_convergence: None,
        ladder_estimate: None,
        layered_band: None,
    }
}

/// Sets each modal point's `e_pole_pa` (the paper's fit failed): the modulus its EMA pole
/// implies on the shell model ([`lamdyn_fit::fit::pole_moduli`]), for the layered inverse's
/// start. A fixed start (the core's `shear_pa`, else 10 MPa) can sit so far off that the
/// layered model's basis misses the core and poles are matched to neighbouring modes: on the
/// small laminate it matched the third and fourth poles one mode up and missed the fifth.
fn starts_from_the_poles(model: &ModalModel, ema: &EmaResult, modal: &mut [CorePoint]) {
    let poles: Vec<(usize, (f64, f64))> = modal
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let m = &ema.modes[nearest_within(ema, p.freq_hz, 1e-9)?];
            Some((k, (m.freq_hz, m.damping_ratio)))
        })
        .collect();
    let pairs: Vec<(f64, f64)> = poles.iter().map(|(_, pole)| *pole).collect();
    let moduli = lamdyn_fit::fit::pole_moduli(model, &pairs);
    for ((k, _), e) in poles.iter().zip(moduli) {
        modal[*k].e_pole_pa = Some(e).filter(|e| e.re > 0.0 && e.is_finite());
    }
}

/// A sandwich inverse of the effective modulus `e`, or why there is none (no modulus, no
/// three-layer sandwich).
fn sandwich_inverse<T>(
    stack: Option<&SandwichStack>,
    e: Option<Complex64>,
    invert: impl FnOnce(&SandwichStack, Complex64) -> std::result::Result<T, MaterialError>,
) -> std::result::Result<T, NoSandwichInverse> {
    match (stack, e) {
        (_, None) => Err(NoSandwichInverse::NoEffectiveModulus),
        (None, _) => Err(NoSandwichInverse::NotASandwich),
        (Some(s), Some(e)) => invert(s, e).map_err(NoSandwichInverse::Inverse),
    }
}

/// Kramers–Kronig verdicts of one inverse's G*(f) on the curve (where it exists).
fn causality(
    points: &[CorePoint],
    g: fn(&CorePoint) -> Option<Complex64>,
) -> Result<Vec<Option<CausalityVerdict>>> {
    let pts: Vec<(f64, Option<Complex64>)> = points.iter().map(|p| (p.freq_hz, g(p))).collect();
    Ok(lamdyn_material::causality::verdicts_where_known(
        &pts,
        CausalityParams::default(),
    )?)
}

/// The truth table: f_hz, storage_pa, loss_pa (as `lamdyn simulate` writes truth.csv).
fn read_truth(path: &Path) -> Result<Truth> {
    let t = crate::io::CsvTable::read(path).context("truth")?;
    let (f, s, l) = (
        t.require_any(&["f_hz"])?,
        t.require_any(&["storage_pa"])?,
        t.require_any(&["loss_pa"])?,
    );
    t.require_increasing_positive(f)?;
    Ok(Truth {
        source: format!("'{}'", path.display()),
        lines: t
            .rows()
            .iter()
            .map(|(_, v)| (v[f], Complex64::new(v[s], v[l])))
            .collect(),
    })
}

/// A helpful error when a job path is missing.
pub fn check_job_path(p: &Path) -> Result<()> {
    if !p.exists() {
        return Err(err!("job file '{}' does not exist", p.display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The part's supports (`[[inverse.supports]]`) reach the shell model: one group per
    /// support and axis with a stiffness, the model file's node springs after them.
    #[test]
    fn the_shell_model_takes_the_parts_supports() {
        let dir = std::env::temp_dir().join(format!("lamdyn-free-shell-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("m.toml"),
            "[mesh]\nkind = \"rectangle\"\nlength_x_m = 0.5\nlength_y_m = 0.4\nelements_x = 4\n\
             elements_y = 4\n[material]\nyoung_pa = 70e9\npoisson = 0.22\ndensity_kg_m3 = 2400.0\n\
             thickness_m = 3e-3\n",
        )
        .unwrap();
        let job = |supports: &str| -> Job {
            let text = format!(
                "[measurement]\nchannels = \"c.csv\"\nfrf = \"f.csv\"\n[model]\nfile = \"m.toml\"\n\
                 {supports}\
                 [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 2500.0\npoisson = 0.22\n\
                 young_pa = 70e9\n\
                 [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 1070.0\npoisson = 0.49\n\
                 [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 2500.0\npoisson = 0.22\n\
                 young_pa = 70e9\n"
            );
            toml::from_str(&text).unwrap()
        };
        let path = dir.join("job.toml");
        let one =
            "[[inverse.supports]]\nxy_fraction = [0.1, 0.1]\nstiffness_n_m = [1.0, 1.0, 4.0]\n";
        let supported = RunConfig::resolve(&job(&one.repeat(2)), &path).unwrap();
        let free = RunConfig::resolve(&job(""), &path).unwrap();
        assert_eq!(supported.model.supports.len(), 2);
        assert!(free.model.supports.is_empty());
        let (mesh, _) = supported.model.file.spec.build(&dir).unwrap();
        let spring = NodeSpring {
            node: 3,
            translational_n_per_m: [0.0, 0.0, 5.0],
            rotational_nm_per_rad: [0.0; 3],
        };
        let on_shell = shell_supports(&mesh, &[spring], &supported.model.supports).unwrap();
        let groups: Vec<usize> = on_shell.iter().map(|s| s.group).collect();
        // The node spring's group after the six of the supports: 6 + (6 node + dof).
        assert_eq!(groups, [0, 1, 2, 3, 4, 5, 6 + 6 * 3 + 2]);
        let normal: f64 = on_shell
            .iter()
            .filter(|s| s.group % 3 == 2 && s.group < 6)
            .map(|s| s.stiffness_n_m)
            .sum();
        assert_eq!(normal, 8.0);
        assert_eq!(on_shell[6].probe.entries(), [(6 * 3 + 2, 1.0)]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
