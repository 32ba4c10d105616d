//! The layered route: the core's G* at each identified pole through a layered solid model of
//! the part ([`lamdyn_layered::inverse`]), converged over a ladder of meshes
//! ([`lamdyn_layered::convergence`]), then the core's law fitted to all modes.
//!
//! For each modal point, the EMA pole p within 2 % of its frequency gives the target
//! eigenvalue λ = −p² = ω_n²(1 + iη); the core's G* is the one at which the model has that
//! eigenvalue, corrected by the Richardson extrapolation of each mode's eigenvalue over meshes
//! refined from the coarsest until the estimated frequency error is below `inverse.tolerance`.
//!
//! The stage is a one-way flow of small modules, each returning a value to the next:
//!
//! | step | module | gives |
//! |---|---|---|
//! | setup | [`setup`] | [`LayeredSetup`] (plate, ladder, priors, law) from the job; starts, targets, G_ref |
//! | ladder | [`ladder`] | the cached builds of every level; the ladder's converged modes |
//! | pairs | [`pairs`], [`pair_fit`] | overlapping pairs fitted to the FRFs |
//! | bands | [`pole_scatter`](mod@pole_scatter), [`bands`] | each mode's [`LayeredBand`] |
//! | law | [`law`] | the core's law over all modes, the supports it found, G* at the real frequency |
//! | FRF fit | [`frf_fit`] | the core's law fitted to the measured FRFs, where the rule calls for it ([`crate::frf_route`]) |
//!
//! [`run`] does the first four; the chain ([`crate::stages`]) calls [`fit_law`] after it,
//! [`run`] again at the supports the law found ([`supports_found`],
//! [`LayeredSetup::at_supports`]), then [`fit_to_frfs`] where the rule calls for it.

mod bands;
mod frf_fit;
mod ladder;
mod law;
mod pair_fit;
mod pairs;
mod pole_scatter;
mod setup;
#[cfg(test)]
mod tests;
mod tuning;

pub use frf_fit::{FrfFitInput, fit_to_frfs};
pub use law::{fit_law, supports_found, to_real_frequency};
pub use pole_scatter::PoleChecks;
pub use setup::LayeredSetup;

use crate::Reporter;
use crate::band::LayeredBand;
use crate::chain::{CorePoint, NoLayered};
use crate::error::{Context, Result};
use crate::text;
use bands::{MovedBySd, band};
use ladder::{BuiltAhead, LevelBuilds, NoThroughThickness, THROUGH};
use lamdyn_ema::identify::EmaResult;
use lamdyn_frf::FrfSet;
use lamdyn_layered::convergence::{Converged, ConvergedMode, converge_keeping_levels};
use lamdyn_layered::inverse::LayeredInverse;
use num_complex::Complex64;
use pairs::{PairBand, fit_overlapping_pairs};
use pole_scatter::pole_scatter;
use rayon::prelude::*;
use setup::{ModeTarget, basis_modulus, targets};

/// What the layered stage leaves beside each mode's result.
pub struct LayeredOutcome {
    /// A line describing the model and what was done, or why nothing was.
    pub line: String,
    /// The coarsest model with its inputs' derivatives, on which the joint law fit
    /// re-linearises ([`fit_law`]); `None` when the ladder did not converge.
    pub coarsest: Option<LayeredInverse>,
    /// Whether every model came from the cache.
    pub all_cached: bool,
    /// The ladder's levels: in-plane elements and dofs, coarsest first (empty: not converged).
    pub levels: Vec<([usize; 2], usize)>,
}

/// The measured data the layered stage reads.
#[derive(Clone, Copy)]
pub struct Observations<'a> {
    /// The FRFs (for the pair fits).
    pub frfs: &'a FrfSet,
    /// The identification.
    pub ema: &'a EmaResult,
    /// The identifications beside it, for the poles' scatter.
    pub checks: &'a PoleChecks,
}

/// Runs the layered inverse of `setup` at every modal point: each gets its G* and band, or why
/// not ([`NoLayered`]).
///
/// # Errors
/// The layered model cannot be meshed, or its coarsest level cannot be built.
pub fn run(
    setup: &LayeredSetup,
    data: Observations,
    modal: &mut [CorePoint],
    cache: &crate::cache::Cache,
    spinner: &dyn Reporter,
) -> Result<LayeredOutcome> {
    let starts = setup.starts(modal);
    let g_ref = basis_modulus(&starts);
    let t = std::time::Instant::now();
    let targets = targets(data.ema, modal);
    for p in modal.iter_mut() {
        p.layered = Some(Err(NoLayered::NoPole { freq_hz: p.freq_hz }));
        (p.layered_band, p.layered_convergence) = (None, None);
    }
    // A coarsest mesh above the dof cap is not built: every mode says why.
    let plate = &setup.plate;
    let coarsest_dofs = plate
        .dofs(setup.start)
        .context("cannot mesh the layered model")?;
    if coarsest_dofs > setup.ladder.max_dofs {
        let why = text::coarsest_above_cap(
            &plate.plan.level_label(setup.start),
            coarsest_dofs,
            setup.ladder.max_dofs,
        );
        return Ok(no_layered(modal, &targets, "not built", why));
    }
    let builds = LevelBuilds::new(setup, cache, g_ref);
    let ahead = builds.levels_ahead();
    let labels: Vec<String> = ahead.iter().map(|&m| plate.plan.level_label(m)).collect();
    spinner.stage(&text::building_ahead(&labels, THROUGH));
    let BuiltAhead {
        coarsest,
        through_thickness,
    } = builds
        .build_ahead(&ahead)
        .context("cannot build the layered model")?;
    let eigenvalues: Vec<Complex64> = targets.iter().map(|w| w.eigenvalue).collect();
    let first: Vec<Complex64> = targets.iter().map(|w| starts[w.point]).collect();
    let converged = climb(setup, (&coarsest, &builds), (&eigenvalues, &first), spinner);
    let build_s = t.elapsed().as_secs_f64();
    let (mut out, finer) = match converged {
        Ok(o) => o,
        Err(e) => return Ok(no_layered(modal, &targets, "not converged", e.to_string())),
    };
    let models = (&coarsest, finer.as_slice());
    let pairs = fit_overlapping_pairs(models, &setup.tuning.pair_fit, data, &targets, &mut out);
    record_modes(modal, &targets, &out);
    let thick = through_thickness.as_ref().ok();
    let bands = mode_bands(
        setup,
        data,
        (&coarsest, thick),
        modal,
        &targets,
        &out,
        &pairs.bands,
    );
    for (t, b) in targets.iter().zip(bands) {
        if let Some(b) = b {
            modal[t.point].layered_band = Some(b);
        }
    }
    let all_cached = builds.all_cached();
    let line = describe(
        setup,
        &out,
        &through_thickness,
        g_ref,
        (build_s, all_cached),
    );
    let line = if pairs.lines.is_empty() {
        line
    } else {
        format!("{line}; {}", pairs.lines.join("; "))
    };
    Ok(LayeredOutcome {
        line,
        coarsest: Some(coarsest),
        all_cached,
        levels: out
            .meshes
            .iter()
            .copied()
            .zip(out.dofs.iter().copied())
            .collect(),
    })
}

/// What the FRF fit needs to run the ladder again on a few of the pole route's modes
/// ([`converge_again`]).
#[derive(Clone, Copy)]
pub struct LadderAgain<'a> {
    /// The run's cache (the ladder's levels are there from the layered stage).
    pub cache: &'a crate::cache::Cache,
    /// The identification, whose poles are the targets.
    pub ema: &'a EmaResult,
}

/// The ladder of `setup` run again for the modal points `points` (indices into `modal`) from
/// the starts `starts` (G*, Pa), as [`run`] runs it from the pole route's: each point's
/// converged mode, or the ladder's estimate where it missed its tolerance, where its core is
/// passive; None for a point without a pole or without a passive answer. The FRF fit calls it
/// for poles the pole route matched to another branch of the model's modes, from its own law
/// (`frf_fit`, [`crate::frf_route::DiscretizationCorrection`]).
///
/// # Errors
/// The coarsest model cannot be built; the ladder's own errors.
pub(crate) fn converge_again(
    setup: &LayeredSetup,
    again: LadderAgain,
    modal: &[CorePoint],
    (points, starts): (&[usize], &[Complex64]),
    spinner: &dyn Reporter,
) -> Result<Vec<Option<ConvergedMode>>> {
    let all = targets(again.ema, modal);
    // (index into `points`, the pole's eigenvalue, the start).
    let chosen: Vec<(usize, Complex64, Complex64)> = (points.iter().zip(starts).enumerate())
        .filter_map(|(k, (&p, &s))| {
            let t = all.iter().find(|t| t.point == p)?;
            Some((k, t.eigenvalue, s))
        })
        .collect();
    let mut found = vec![None; points.len()];
    if chosen.is_empty() {
        return Ok(found);
    }
    // The same G_ref as the layered stage's, so its levels come from the cache.
    let builds = LevelBuilds::new(setup, again.cache, basis_modulus(&setup.starts(modal)));
    let coarsest = builds
        .coarsest()
        .context("cannot build the layered model")?;
    let eigenvalues: Vec<Complex64> = chosen.iter().map(|c| c.1).collect();
    let first: Vec<Complex64> = chosen.iter().map(|c| c.2).collect();
    let (out, _) = climb(setup, (&coarsest, &builds), (&eigenvalues, &first), spinner)
        .context("the ladder run again failed")?;
    for (&(k, _, _), (mode, estimate)) in chosen
        .iter()
        .zip(out.modes.iter().zip(&out.beyond_tolerance))
    {
        let m = mode.as_ref().ok().or(estimate.as_ref());
        found[k] = m.and_then(|m| physical(m).ok()).cloned();
    }
    Ok(found)
}

/// The ladder of `setup` from its coarsest model on the eigenvalues `targets`, each from its
/// start G* in `starts` (Pa), the finer levels from `builds`
/// ([`converge_keeping_levels`]); progress on `spinner`.
fn climb(
    setup: &LayeredSetup,
    (coarsest, builds): (&LayeredInverse, &LevelBuilds),
    (targets, starts): (&[Complex64], &[Complex64]),
    spinner: &dyn Reporter,
) -> std::result::Result<(Converged, Vec<LayeredInverse>), lamdyn_layered::LayeredError> {
    converge_keeping_levels(
        coarsest,
        setup.start,
        builds,
        targets,
        starts,
        &setup.ladder,
        &|m| spinner.stage(&text::layered_progress(m)),
    )
}

/// Each target's converged mode into its modal point: its G* where it is passive, else why
/// not.
fn record_modes(modal: &mut [CorePoint], targets: &[ModeTarget], out: &Converged) {
    for ((t, m), estimate) in targets.iter().zip(&out.modes).zip(&out.beyond_tolerance) {
        modal[t.point].ladder_estimate = estimate.clone();
        let m = m
            .as_ref()
            .map_err(|e| NoLayered::Ladder(e.to_string()))
            .and_then(physical);
        let p = &mut modal[t.point];
        p.layered = Some(m.as_ref().map(|m| m.core_shear_pa).map_err(Clone::clone));
        p.layered_convergence = m.ok().cloned();
    }
}

/// Each converged target's band (in parallel; sequential inside, so the same bits); `None`
/// for a target whose ladder failed. A mode of a fitted pair takes its band at the model's
/// pole at the pair's G*, with the fit's sources, and holds at its real frequency (it was
/// fitted to the FRFs on the real axis).
fn mode_bands(
    setup: &LayeredSetup,
    data: Observations,
    models: (&LayeredInverse, Option<&LayeredInverse>),
    modal: &[CorePoint],
    targets: &[ModeTarget],
    out: &Converged,
    pair_bands: &[Option<PairBand>],
) -> Vec<Option<std::result::Result<LayeredBand, lamdyn_layered::LayeredError>>> {
    use crate::band::BandSource;
    let wide = setup.tuning.law.wide_prior;
    let moved = MovedBySd::build(models.0, &setup.plate, &setup.priors, wide);
    targets
        .par_iter()
        .zip(&out.modes)
        .zip(pair_bands)
        .map(|((t, m), pair)| {
            let m = m.as_ref().ok()?;
            let freq_hz = modal[t.point].freq_hz;
            let scatter = pole_scatter(data.ema, data.checks, freq_hz);
            let target = pair.as_ref().map_or(t.eigenvalue, |p| p.eigenvalue);
            let b = band(models, &moved, m, target, scatter, setup.supports_at);
            Some(match pair {
                Some(p) => b.map(|b| {
                    let mut b = b.with_source(BandSource::PairFit, p.fit_sd);
                    if let Some(spread) = p.lines_sd {
                        b = b.with_source(BandSource::PairFitLines, spread);
                    }
                    LayeredBand {
                        found_at_hz: Complex64::new(freq_hz, 0.0),
                        ..b
                    }
                }),
                None => b,
            })
        })
        .collect()
}

/// The layered stage's line: the model, the ladder's meshes, how many modes met the
/// tolerance, the basis, the time.
fn describe(
    setup: &LayeredSetup,
    out: &Converged,
    through_thickness: &std::result::Result<LayeredInverse, NoThroughThickness>,
    g_ref: f64,
    (build_s, cached): (f64, bool),
) -> String {
    let plan = &setup.plate.plan;
    let meshes: Vec<String> = out
        .meshes
        .iter()
        .zip(&out.dofs)
        .map(|(&m, &d)| text::level(&plan.level_label(m), d))
        .collect();
    let why_not = through_thickness.as_ref().err().map(ToString::to_string);
    text::layered_line(&text::LayeredLine {
        through_thickness: why_not.as_deref(),
        through: THROUGH,
        plan: &plan.describe(),
        meshes: &meshes,
        tolerance: setup.ladder.tolerance,
        met: out.modes.iter().filter(|m| m.is_ok()).count(),
        modes: out.modes.len(),
        g_ref,
        build_s,
        cached,
    })
}

/// The layered stage's outcome when no mode gets a layered G*: each target's mode says `why`,
/// and so does the line (`what: why`).
fn no_layered(
    modal: &mut [CorePoint],
    targets: &[ModeTarget],
    what: &str,
    why: String,
) -> LayeredOutcome {
    for t in targets {
        modal[t.point].layered = Some(Err(NoLayered::Stage(why.clone())));
    }
    LayeredOutcome {
        line: format!("{what}: {why}"),
        coarsest: None,
        all_cached: false,
        levels: Vec::new(),
    }
}

/// A converged mode whose core is passive (G' > 0, G'' > 0), else why not: a pole damped
/// less than the faces and supports alone damp that mode (an EMA damping too low, dashpots
/// too strong) gives G'' < 0, which no material has.
fn physical(m: &ConvergedMode) -> std::result::Result<&ConvergedMode, NoLayered> {
    let g = m.core_shear_pa;
    if g.re > 0.0 && g.im > 0.0 {
        Ok(m)
    } else {
        Err(NoLayered::NotPassive { core_shear_pa: g })
    }
}
