//! Each overlapping pair of converged modes fitted to the FRFs ([`super::pair_fit`]): both
//! modes get the pair's G*, and their bands are taken at the model's poles at it with the
//! fit's standard deviations as sources.

use super::pair_fit::{fit_pair, overlapping_pairs};
use super::setup::ModeTarget;
use super::tuning::PairFitTuning;
use crate::band::StorageAndLoss;
use crate::text;
use lamdyn_layered::convergence::{Converged, correction};
use lamdyn_layered::inverse::LayeredInverse;
use num_complex::Complex64;
use rayon::prelude::*;

/// What a pair fit leaves for one of its modes' band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairBand {
    /// The model's eigenvalue −p² of the mode at the pair's G*, rad²/s²: where the band is
    /// taken.
    pub eigenvalue: Complex64,
    /// The fit's standard deviations of ln G' and ln η.
    pub fit_sd: StorageAndLoss,
    /// The spread of ln G' and ln η over the fitted band's width, if more than one fit
    /// succeeded.
    pub lines_sd: Option<StorageAndLoss>,
}

/// The pairs' results: per target (as `targets`), its pair's band where it is one of a pair
/// fitted; per pair a line saying what was done, or why not (the modes then keep their own
/// poles' G*).
pub struct PairsFitted {
    /// Per target.
    pub bands: Vec<Option<PairBand>>,
    /// Per pair.
    pub lines: Vec<String>,
}

/// Fits each overlapping pair of `targets` whose modes both converged in `out`, and puts the
/// pair's G* into `out` for both.
pub fn fit_overlapping_pairs(
    (coarsest, finer): (&LayeredInverse, &[LayeredInverse]),
    tuning: &PairFitTuning,
    data: super::Observations,
    targets: &[ModeTarget],
    out: &mut Converged,
) -> PairsFitted {
    let eigenvalues: Vec<Complex64> = targets.iter().map(|w| w.eigenvalue).collect();
    let hz = |l: Complex64| l.re.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    let pairs = overlapping_pairs(&eigenvalues);
    let meshes = out.meshes.clone();
    let correct = |g: Complex64, rank: usize, target: Complex64| {
        correction(coarsest, finer, &meshes, g, rank, target)
    };
    // Pairs in parallel, each sequential inside: the same bits on any thread count.
    let fits: Vec<_> = pairs
        .par_iter()
        .map(|&[a, b]| match (&out.modes[a], &out.modes[b]) {
            (Ok(ma), Ok(mb)) => Some(fit_pair(
                coarsest,
                tuning,
                data.frfs,
                data.ema,
                [eigenvalues[a], eigenvalues[b]],
                [ma, mb],
                &correct,
            )),
            _ => None,
        })
        .collect();
    let mut bands = vec![None; targets.len()];
    let mut lines = Vec::new();
    for (&[a, b], fit) in pairs.iter().zip(fits) {
        let pair_hz = [hz(eigenvalues[a]), hz(eigenvalues[b])];
        match fit {
            None => {}
            Some(Ok(fit)) => {
                for (i, k) in [a, b].into_iter().enumerate() {
                    if let Ok(m) = &mut out.modes[k] {
                        m.core_shear_pa = fit.g_pa;
                    }
                    bands[k] = Some(PairBand {
                        eigenvalue: fit.targets[i],
                        fit_sd: StorageAndLoss::from_array(fit.rel_sd),
                        lines_sd: fit.band_choice_sd.map(StorageAndLoss::from_array),
                    });
                }
                lines.push(text::pair_fitted(
                    pair_hz,
                    fit.band_hz,
                    fit.lines,
                    [hz(fit.targets[0]), hz(fit.targets[1])],
                    fit.misfit,
                ));
            }
            Some(Err(e)) => lines.push(text::pair_not_fitted(pair_hz, &e)),
        }
    }
    PairsFitted { bands, lines }
}
