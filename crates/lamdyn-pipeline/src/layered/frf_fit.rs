//! The layered stage's FRF fit: the core's law fitted to the measured FRFs through the layered
//! model on the ladder's finest level up to [`FRF_MAX_DOFS`] ([`lamdyn_fit::frf_fit`]), the inputs under the job's
//! priors, then corrected for the mesh by the ladder ([`crate::frf_route`]).
//!
//! The model is that level of the ladder read at every response channel and driven at
//! every reference by the surface's shape functions ([`ObservedModel::build`]), on a basis of
//! `inverse.layered_modes` modes at two core moduli that bracket the start law over the band
//! (at least G_ref/2 … 2 G_ref: [`FrfBasis::default`]), two orders of core sensitivities and
//! the references' residual vectors. It starts from the pole route's law where there is one,
//! else from the best constant moduli of a grid.

use super::setup::{LayeredSetup, basis_modulus, input_rel_sd};
use crate::Reporter;
use crate::chain::CorePoint;
use crate::error::{Context, Result};
use crate::frf_route::{DiscretizationCorrection, FrfCurve, FrfRoute, WhyFrfFit};
use lamdyn_fit::frf_fit::{FrfFit, FrfFitSettings, FrfLaw, InputPrior, fit_core_to_frfs};
use lamdyn_fit::joint::CoreLawFit;
use lamdyn_frf::{Channel, FrfSet};
use lamdyn_layered::frf::{FrfBasis, MeasuredPoint, ObservedModel};
use lamdyn_layered::inverse::BASIS_COVER;
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
    /// The ladder's levels (elements, dofs), coarsest first: the fit takes the finest up to
    /// [`FRF_MAX_DOFS`] (the coarsest when empty).
    pub levels: &'a [([usize; 2], usize)],
}

/// The largest level (dofs) the FRF fit's model is built on. Its cost per line does not grow
/// with the level (one LU of the reduced basis), its build does (the basis's eigen solves and
/// the inputs' assemblies); a finer level leaves less for the ladder's correction to carry.
pub const FRF_MAX_DOFS: usize = 60_000;

/// Fits the core's law to the FRFs through `setup`'s layered model (module docs); `why` says
/// why it is the answer (empty: it is beside the pole route).
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
    let set = input.set;
    let (g_ref, ratios) = basis_moduli(setup, input);
    let basis = FrfBasis {
        modes: setup.modes,
        ratios,
        ..FrfBasis::default()
    };
    let priors = input_priors(setup);
    let inputs: Vec<Input> = priors.iter().map(|p| p.input).collect();
    let (sensors, references) = (points(set.responses()), points(set.references()));
    let level = input
        .levels
        .iter()
        .filter(|l| l.1 <= FRF_MAX_DOFS)
        .map(|l| l.0)
        .next_back()
        .unwrap_or(setup.start);
    let label = setup.plate.plan.level_label(level);
    spinner.stage(&format!(
        "FRF fit: layered model {label} read at {} channel(s), {} reference(s)",
        sensors.len(),
        references.len()
    ));
    let t = Instant::now();
    let model = ObservedModel::build(
        &setup.plate,
        level,
        g_ref,
        &basis,
        (&sensors, &references),
        &inputs,
    )
    .context("cannot build the FRF fit's layered model")?;
    let build_s = t.elapsed().as_secs_f64();
    // The basis holds the modes below BASIS_COVER of its highest one (at its softest core).
    let held_hz = BASIS_COVER * model.model().top_eigenvalue.max(0.0).sqrt() / (2.0 * PI);
    let band_hz = [input.band_hz[0], input.band_hz[1].min(held_hz)];
    if band_hz[1] <= band_hz[0] {
        return Err(crate::err!(
            "the FRF fit's basis holds the model only up to {held_hz:.1} Hz, below the band {:.1}-{:.1} Hz: raise inverse.layered_modes",
            input.band_hz[0],
            input.band_hz[1]
        ));
    }
    let law = FrfLaw::generalized_maxwell_over(band_hz[0], band_hz[1]);
    let mut settings = FrfFitSettings::over(band_hz);
    settings.inputs = priors;
    spinner.stage(&format!(
        "FRF fit: {} on {} basis vectors over {:.1}-{:.1} Hz",
        law.name(),
        model.basis_size(),
        band_hz[0],
        band_hz[1]
    ));
    let t = Instant::now();
    let start = input
        .start
        .map(|law| move |w: f64| law.modulus(w / (2.0 * PI)).unwrap_or_default());
    let start_ref = start
        .as_ref()
        .map(|f| f as &(dyn Fn(f64) -> Complex64 + Sync));
    let fit = fit_core_to_frfs(&model, set, law, g_ref, start_ref, &settings)?;
    let fit_s = t.elapsed().as_secs_f64();
    let curves = shown_curves(&model, &fit, set)?;
    Ok(FrfRoute {
        model_line: format!(
            "C3D20 {label} ({} basis vectors at G_ref {:.4e} Pa x {:?}), inputs under their priors: {}",
            model.basis_size(),
            g_ref,
            basis.ratios,
            inputs
                .iter()
                .map(|i| i.name())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        fit,
        why,
        correction: DiscretizationCorrection::from_ladder(
            input.modal,
            setup.start[0] as f64 / level[0] as f64,
        ),
        curves,
        times_s: [build_s, fit_s],
    })
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
/// prior (a wider one says the input is not known: the law would trade against it), the
/// supports' only where there are supports.
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
fn shown_curves(model: &ObservedModel, fit: &FrfFit, set: &FrfSet) -> Result<Vec<FrfCurve>> {
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
