//! Overlapping pairs of poles: the core's G* fitted to the FRFs around the pair, with the
//! pair's two poles tied to the layered model.
//!
//! Two modes closer than the sum of their half-power half-widths, |f₂ − f₁| < ζ₁f₁ + ζ₂f₂,
//! are one hump in every FRF. An identification then splits the hump between its two poles by
//! a few parts in 1e4 in frequency and a few per cent in damping differently from the truth,
//! even from noise-free FRFs: a core whose damping depends on frequency makes the hump no
//! exact sum of two constant poles (the in-band foam roof's pair at 20.1 / 20.5 Hz, ζ 5 %,
//! 0.17 of its half-widths apart, came out 13–22 % off in G* from noise-free FRFs). On modes
//! that shear the core little, that is tens of per cent in G*.
//!
//! The layered model knows how the pair splits: at a core modulus G* both poles follow,
//! p_i(G*) = i √(δ_i λ_i(G*)), with λ_i the coarsest model's pole of the mode's rank
//! ([`LayeredInverse::pole_near`], the supports' dashpots acting at the pole's own frequency)
//! and δ_i = λ_∞/λ_0 the ladder's correction of that mode (taken where the ladder left it,
//! t_i / λ_i(G*_i) for the mode's own target t_i and G*_i). So the pair has two real unknowns,
//! G' and η, where the identification had four. They are fitted to the measured FRFs over the
//! lines within three half-widths of the pair, by variable projection [Golub & Pereyra 1973]:
//! for each trial G* the residues of every curve, and of the nearest poles below and above the
//! pair (the identification's, fixed), with lower and upper residual terms, are the least-
//! squares solution ([`lamdyn_ema::lsfd`]); Levenberg–Marquardt ([`lamdyn_fit::lm`]) moves
//! x = (ln G', ln η) to the least Σ|H − Ĥ|². Its standard deviations are
//! s² (JᵀJ)⁻¹ with s² = S/(m − n), m the real residuals and n every unknown of the fit.
//!
//! Both modes then carry the pair's G* (one modulus for two modes 1–2 % apart in frequency;
//! the roof's law moves by 0.7 % over its pair), matched to the model's poles at it, and their
//! bands gain the fit's standard deviation as a source ([`PAIR_FIT`]).

use crate::err;
use crate::error::Result;
use lamdyn_ema::identify::EmaResult;
use lamdyn_fit::lm::{LmSettings, levenberg_marquardt};
use lamdyn_frf::FrfSet;
use lamdyn_layered::convergence::ConvergedMode;
use lamdyn_layered::inverse::LayeredInverse;
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// The band's source made of the pair fit's own standard deviation.
pub const PAIR_FIT: &str = "FRF fit of the overlapping pair";

/// Half-widths each side of the pair whose lines the fit uses.
pub const HALF_WIDTHS: f64 = 3.0;

/// The other bands the fit is repeated on, in half-widths each side of the pair: their spread
/// is the source [`BAND_CHOICE`].
pub const OTHER_HALF_WIDTHS: [f64; 2] = [2.0, 4.0];

/// The band's source made of the spread of the pair's G* over the fits on bands of 2, 3 and 4
/// half-widths each side.
pub const BAND_CHOICE: &str = "lines of the pair fit";

/// How far (|ln G'/G'₀|, |ln η/η₀|) the fit may move from its start, the mean of the two
/// modes' own G*: a factor 2, within the coarsest basis's G_ref/4 … 4 G_ref about a start
/// that lies within √2 of G_ref. Beyond it the reduced model is not checked, and a pair
/// whose modes barely feel the core (a hump the residues can follow) let the fit wander to a
/// G' of 0.5 % and an η of 10⁷ of the start.
const REACH: f64 = std::f64::consts::LN_2;

/// An overlapping pair's fit.
#[derive(Debug, Clone, PartialEq)]
pub struct PairFit {
    /// The pair's G*, Pa.
    pub g_pa: Complex64,
    /// The model's eigenvalues −p² of the two modes at `g_pa` (ladder-corrected), rad²/s²:
    /// the targets the modes' G* and bands are taken at.
    pub targets: [Complex64; 2],
    /// Standard deviations of ln G' and ln η from the fit.
    pub rel_sd: [f64; 2],
    /// The lines' band, Hz, and their number.
    pub band_hz: [f64; 2],
    /// Lines in the band.
    pub lines: usize,
    /// √(S/Σ|H|²) with the identification's two poles and with the fitted ones.
    pub misfit: [f64; 2],
    /// The sample standard deviations of ln G' and ln η over the fits on [`HALF_WIDTHS`] and
    /// [`OTHER_HALF_WIDTHS`] (those that succeed; `None` if only the first did).
    pub band_choice_sd: Option<[f64; 2]>,
}

/// Frequency (Hz) and damping ratio of an eigenvalue λ = ω²(1 + iη) (η = 2ζ).
fn freq_and_zeta(l: Complex64) -> (f64, f64) {
    (l.re.max(0.0).sqrt() / (2.0 * PI), 0.5 * l.im / l.re)
}

/// The pole p = i√λ of an eigenvalue λ = −p² with Im λ ≥ 0 (the targets' convention): the
/// decaying one, positive imaginary part.
pub(crate) fn pole_of(l: Complex64) -> Complex64 {
    let p = Complex64::i() * l.sqrt();
    if p.im < 0.0 { p.conj() } else { p }
}

/// The pairs of `targets` (eigenvalues −p²) that overlap, |f₂ − f₁| < ζ₁f₁ + ζ₂f₂, as indices,
/// lower frequency first; in a chain of three or more, disjoint pairs from the lowest up.
pub fn overlapping_pairs(targets: &[Complex64]) -> Vec<[usize; 2]> {
    let mut order: Vec<usize> = (0..targets.len()).collect();
    order.sort_by(|&a, &b| targets[a].re.total_cmp(&targets[b].re));
    let mut pairs = Vec::new();
    let mut k = 0;
    while k + 1 < order.len() {
        let (a, b) = (order[k], order[k + 1]);
        let ((fa, za), (fb, zb)) = (freq_and_zeta(targets[a]), freq_and_zeta(targets[b]));
        if fb - fa < za * fa + zb * fb {
            pairs.push([a, b]);
            k += 2;
        } else {
            k += 1;
        }
    }
    pairs
}

/// The identification's poles other than the pair's (`targets`): those inside `band_hz` and
/// the nearest below and above it.
fn neighbours(ema: &EmaResult, targets: [Complex64; 2], band_hz: [f64; 2]) -> Vec<Complex64> {
    let is_pair = |p: Complex64| {
        let l = -(p * p);
        targets
            .iter()
            .any(|t| (l - t).norm().min((l.conj() - t).norm()) <= 1e-9 * t.norm())
    };
    let mut others: Vec<(f64, Complex64)> = ema
        .modes
        .iter()
        .chain(&ema.rejected)
        .filter(|m| !is_pair(m.pole))
        .map(|m| (m.freq_hz, m.pole))
        .collect();
    others.sort_by(|a, b| a.0.total_cmp(&b.0));
    let below = others.iter().rev().find(|o| o.0 < band_hz[0]);
    let above = others.iter().find(|o| o.0 > band_hz[1]);
    let inside = others
        .iter()
        .filter(|o| o.0 >= band_hz[0] && o.0 <= band_hz[1]);
    below
        .into_iter()
        .chain(inside)
        .chain(above)
        .map(|o| o.1)
        .collect()
}

/// Fits the pair (`targets`, the identification's eigenvalues −p² of its two modes, and the
/// ladder's results for them) to the measured FRFs of `set` (module docs).
///
/// # Errors
/// A message (for the layered line) when a mode is lost, both poles matched one mode of the
/// model and it has no neighbour or no ladder correction, the band holds too few lines, the
/// fit fails or does not settle, or the fitted poles are not the two modes' by rank.
pub fn fit_pair(
    coarsest: &LayeredInverse,
    set: &FrfSet,
    ema: &EmaResult,
    targets: [Complex64; 2],
    modes: [&ConvergedMode; 2],
    correction: &dyn Fn(Complex64, usize, Complex64) -> std::result::Result<Complex64, String>,
) -> Result<PairFit> {
    let lost = |r: usize| err!("the model's elastic mode {} lost", r + 1);
    // Each mode's coarsest pole at its own G* and the ladder's correction there.
    let mut start = [Complex64::default(); 2];
    let mut delta = [Complex64::default(); 2];
    for i in 0..2 {
        start[i] = coarsest
            .pole_eigenvalue(modes[i].core_shear_pa, modes[i].rank, targets[i])
            .ok_or_else(|| lost(modes[i].rank))?;
        delta[i] = targets[i] / start[i];
    }
    let g0 = 0.5 * (modes[0].core_shear_pa + modes[1].core_shear_pa);
    let ranks = if modes[0].rank == modes[1].rank {
        // Both poles on one branch (the pair is nearly double): the pair is that mode and
        // its neighbour nearer the pair (by the branch's mean δ), the lower rank for the lower
        // pole, each with its own δ from the ladder's levels at the start.
        let r = modes[0].rank;
        let mean_delta = 0.5 * (delta[0] + delta[1]);
        let mid = 0.5 * (targets[0] + targets[1]);
        let other = [r.checked_sub(1), Some(r + 1)]
            .into_iter()
            .flatten()
            .filter_map(|c| {
                let l = coarsest.pole_eigenvalue(g0, c, mid)?;
                Some((c, (mean_delta * l - mid).norm()))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|c| c.0)
            .ok_or_else(|| {
                err!(
                    "both poles matched the model's elastic mode {}, which has no neighbour",
                    r + 1
                )
            })?;
        let ranks = [r.min(other), r.max(other)];
        for i in 0..2 {
            start[i] = coarsest
                .pole_eigenvalue(g0, ranks[i], targets[i])
                .ok_or_else(|| lost(ranks[i]))?;
            delta[i] = correction(g0, ranks[i], targets[i]).map_err(|e| {
                err!(
                    "no ladder correction of the model's mode {}: {e}",
                    ranks[i] + 1
                )
            })?;
        }
        ranks
    } else {
        [modes[0].rank, modes[1].rank]
    };
    // What every band's fit shares: the curves, and x = (ln G'/G'₀, ln η/η₀) from the mean of
    // the two modes' own G*.
    let freqs = set.freqs_hz();
    let curves: Vec<&[Complex64]> = (0..set.responses().len())
        .flat_map(|i| (0..set.references().len()).map(move |j| (i, j)))
        .map(|(i, j)| set.curve(i, j))
        .collect();
    let quantity = set.quantity();
    let eta0 = g0.im / g0.re;
    let g_of = |x: &[f64]| {
        let storage = g0.re * x[0].exp();
        Complex64::new(storage, storage * eta0 * x[1].exp())
    };
    // The fit over the lines within `half_widths` of the pair.
    let fit_with = |half_widths: f64| -> Result<PairFit> {
        let ((fa, za), (fb, zb)) = (freq_and_zeta(targets[0]), freq_and_zeta(targets[1]));
        let band_hz = [
            (fa * (1.0 - half_widths * za)).max(ema.band_hz[0]),
            (fb * (1.0 + half_widths * zb)).min(ema.band_hz[1]),
        ];
        // The lines the residues are fitted on, also those the misfit is summed over.
        let lines = lamdyn_ema::band::positive_lines(freqs, band_hz);
        let others = neighbours(ema, targets, band_hz);
        let unknowns = 2 * (2 + others.len()) + 2;
        if lines.len() < unknowns {
            return Err(err!(
                "{} lines in {:.2}-{:.2} Hz for {unknowns} unknowns per curve",
                lines.len(),
                band_hz[0],
                band_hz[1]
            ));
        }
        let residuals_for = |pair: [Complex64; 2]| -> Option<Vec<f64>> {
            let mut poles = vec![pole_of(pair[0]), pole_of(pair[1])];
            poles.extend(&others);
            let fit = lamdyn_ema::lsfd::lsfd(freqs, &curves, quantity, &poles, band_hz).ok()?;
            let mut r = Vec::with_capacity(2 * curves.len() * lines.len());
            for (o, c) in curves.iter().enumerate() {
                for &k in &lines {
                    let d = c[k] - fit.synthesize(o, freqs[k]);
                    r.extend([d.re, d.im]);
                }
            }
            Some(r)
        };
        // Each pole tracked from its start (cheap); where that loses one or both land on one
        // mode (a nearly double pair), by rank (an eigendecomposition each).
        let model_pair = |g: Complex64| -> Option<[Complex64; 2]> {
            let tracked = coarsest
                .pole_near(g, start[0])
                .zip(coarsest.pole_near(g, start[1]))
                .filter(|(a, b)| (a - b).norm() > 1e-6 * a.norm());
            let (a, b) = match tracked {
                Some(t) => t,
                None => (
                    coarsest.pole_eigenvalue(g, ranks[0], targets[0])?,
                    coarsest.pole_eigenvalue(g, ranks[1], targets[1])?,
                ),
            };
            Some([delta[0] * a, delta[1] * b])
        };
        let residuals = |x: &[f64]| {
            // Within the basis's range about the start ([`REACH`]).
            if x.iter().any(|v| v.abs() > REACH) {
                return None;
            }
            residuals_for(model_pair(g_of(x))?)
        };
        let settings = LmSettings {
            max_iterations: 30,
            cost_tolerance: 1e-8,
            gradient_tolerance: 1e-12,
        };
        let out = levenberg_marquardt(&residuals, &[0.0, 0.0], settings)
            .ok_or_else(|| err!("the fit lost the model's poles of the pair"))?;
        if !out.converged {
            return Err(err!(
                "the fit did not settle in {} iterations",
                settings.max_iterations
            ));
        }
        let g = g_of(&out.x);
        // The fitted poles must be the two modes' by rank (a close pair can swap when tracked).
        let fitted = model_pair(g).ok_or_else(|| err!("the fitted poles are lost"))?;
        for i in 0..2 {
            let by_rank = coarsest
                .pole_eigenvalue(g, ranks[i], targets[i])
                .ok_or_else(|| lost(ranks[i]))?;
            if (delta[i] * by_rank - fitted[i]).norm() > 1e-6 * fitted[i].norm() {
                return Err(err!(
                    "the fit's pole at {:.3} Hz is not the model's elastic mode {} at G* = {g:.4e} Pa",
                    freq_and_zeta(fitted[i]).0,
                    ranks[i] + 1
                ));
            }
        }
        let ema_residuals =
            residuals_for(targets).ok_or_else(|| err!("no residues at the EMA's poles"))?;
        let sum_sq = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
        let norm: f64 = curves
            .iter()
            .map(|c| lines.iter().map(|&k| c[k].norm_sqr()).sum::<f64>())
            .sum();
        let m = out.residuals.len();
        let n = curves.len() * unknowns + 2;
        if m <= n {
            return Err(err!("{m} residuals for {n} unknowns"));
        }
        let s2 = out.cost / (m - n) as f64;
        let jtj = out.jacobian.transpose() * &out.jacobian;
        let det = jtj[(0, 0)] * jtj[(1, 1)] - jtj[(0, 1)] * jtj[(1, 0)];
        if det.is_nan() || det <= 0.0 {
            return Err(err!("the FRFs do not determine G' and eta at the pair"));
        }
        let rel_sd = [
            (s2 * jtj[(1, 1)] / det).sqrt(),
            (s2 * jtj[(0, 0)] / det).sqrt(),
        ];
        Ok(PairFit {
            g_pa: g,
            targets: fitted,
            rel_sd,
            band_hz,
            lines: lines.len(),
            band_choice_sd: None,
            misfit: [
                (sum_sq(&ema_residuals) / norm).sqrt(),
                (out.cost / norm).sqrt(),
            ],
        })
    };
    // The fit, and the same over narrower and wider bands: how much the answer depends on
    // the lines chosen (the core's modulus changes over the band, the fixed neighbours' poles
    // weigh differently), a source of its own in the band. Side by side, each sequential
    // inside: the same bits on any thread count.
    let (main, others) = rayon::join(
        || fit_with(HALF_WIDTHS),
        || {
            OTHER_HALF_WIDTHS
                .par_iter()
                .map(|&h| fit_with(h))
                .collect::<Vec<_>>()
        },
    );
    let mut fit = main?;
    let mut found = vec![fit.g_pa];
    found.extend(others.into_iter().filter_map(|f| f.ok()).map(|f| f.g_pa));
    if found.len() > 1 {
        let logs: Vec<[f64; 2]> = found
            .iter()
            .map(|g| [g.re.ln(), (g.im / g.re).ln()])
            .collect();
        fit.band_choice_sd = Some(crate::layered::sample_sd(&logs));
    }
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eig(f: f64, zeta: f64) -> Complex64 {
        let w = 2.0 * PI * f;
        Complex64::new(w * w, 2.0 * zeta * w * w)
    }

    #[test]
    fn overlapping_pairs_are_closer_than_their_half_widths() {
        // 20.0 / 20.5 Hz at 2 % (half-widths 0.4 + 0.41 Hz): a pair; 30 Hz alone; 40 / 40.2 /
        // 40.4 Hz at 1 %: the lowest two, the third left alone.
        let t = [
            eig(30.0, 0.02),
            eig(20.5, 0.02),
            eig(20.0, 0.02),
            eig(40.0, 0.01),
            eig(40.2, 0.01),
            eig(40.4, 0.01),
        ];
        assert_eq!(overlapping_pairs(&t), vec![[2, 1], [3, 4]]);
        // Far apart against their damping: none.
        assert!(overlapping_pairs(&[eig(20.0, 0.005), eig(20.5, 0.005)]).is_empty());
    }

    #[test]
    fn a_pole_is_the_root_of_its_eigenvalue() {
        let p = Complex64::new(-3.0, 120.0);
        let l = -(p * p);
        // λ = ω²(1 + iη) with η > 0 (the targets' convention): the decaying pole.
        assert!(l.im > 0.0);
        assert!((pole_of(l) - p).norm() < 1e-12 * p.norm());
    }
}
