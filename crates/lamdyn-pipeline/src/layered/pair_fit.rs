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
//! bands gain the fit's standard deviation as a source
//! ([`BandSource::PairFit`](crate::band::BandSource::PairFit)) and the spread over the fitted
//! band's width ([`BandSource::PairFitLines`](crate::band::BandSource::PairFitLines)).

use super::tuning::PairFitTuning;
use crate::err;
use crate::error::Result;
use lamdyn_ema::identify::EmaResult;
use lamdyn_fit::lm::{LmSettings, levenberg_marquardt};
use lamdyn_frf::FrfSet;
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::ConvergedMode;
use lamdyn_layered::inverse::LayeredInverse;
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

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
    /// The sample standard deviations of ln G' and ln η over the fits on the tuning's half-widths
    /// and its other half-widths (those that succeed; `None` if only the first did).
    pub band_choice_sd: Option<[f64; 2]>,
}

/// Frequency (Hz) and damping ratio of an eigenvalue λ = ω²(1 + iη) (η = 2ζ).
fn freq_and_zeta(l: Complex64) -> (f64, f64) {
    (l.re.max(0.0).sqrt() / (2.0 * PI), 0.5 * l.im / l.re)
}

/// The pole p = i√λ of an eigenvalue λ = −p² with Im λ ≥ 0 (the targets' convention): the
/// decaying one, positive imaginary part.
pub(super) fn pole_of(l: Complex64) -> Complex64 {
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

/// The ladder's correction of a mode: δ = λ_∞/λ_0 at G* for the mode of a rank near a target
/// ([`lamdyn_layered::convergence::correction`]).
pub type Correction<'a> =
    dyn Fn(Complex64, usize, Complex64) -> std::result::Result<Complex64, LayeredError> + 'a;

/// Fits the pair (`targets`, the identification's eigenvalues −p² of its two modes, and the
/// ladder's results for them) to the measured FRFs of `set` (module docs): on the lines within
/// `tuning.half_widths` of the pair, and again within `tuning.other_half_widths` for the spread.
///
/// # Errors
/// A message (for the layered line) when a mode is lost, both poles matched one mode of the
/// model and it has no neighbour or no ladder correction, the band holds too few lines, the
/// fit fails or does not settle, or the fitted poles are not the two modes' by rank.
pub fn fit_pair(
    coarsest: &LayeredInverse,
    tuning: &PairFitTuning,
    set: &FrfSet,
    ema: &EmaResult,
    targets: [Complex64; 2],
    modes: [&ConvergedMode; 2],
    correction: &Correction,
) -> Result<PairFit> {
    let pair = Pair::new(coarsest, targets, modes, correction)?;
    let data = Data::new(set, ema);
    // The fit, and the same over narrower and wider bands: how much the answer depends on
    // the lines chosen (the core's modulus changes over the band, the fixed neighbours' poles
    // weigh differently), a source of its own in the band. Side by side, each sequential
    // inside: the same bits on any thread count.
    let (main, others) = rayon::join(
        || pair.fit(&data, tuning.half_widths, tuning.reach),
        || {
            tuning
                .other_half_widths
                .par_iter()
                .map(|&h| pair.fit(&data, h, tuning.reach))
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
        fit.band_choice_sd = Some(crate::stats::sample_sd(&logs));
    }
    Ok(fit)
}

/// The measured data every band's fit shares.
struct Data<'a> {
    freqs: &'a [f64],
    curves: Vec<&'a [Complex64]>,
    quantity: lamdyn_frf::Quantity,
    ema: &'a EmaResult,
}

impl<'a> Data<'a> {
    fn new(set: &'a FrfSet, ema: &'a EmaResult) -> Self {
        let curves = (0..set.responses().len())
            .flat_map(|i| (0..set.references().len()).map(move |j| (i, j)))
            .map(|(i, j)| set.curve(i, j))
            .collect();
        Self {
            freqs: set.freqs_hz(),
            curves,
            quantity: set.quantity(),
            ema,
        }
    }
}

/// The pair on the model: its modes' ranks, each pole's start on the coarsest model and the
/// ladder's correction δ, and x = (ln G'/G'₀, ln η/η₀) from the mean G₀ of the two modes' own
/// G*.
struct Pair<'a> {
    coarsest: &'a LayeredInverse,
    targets: [Complex64; 2],
    ranks: [usize; 2],
    start: [Complex64; 2],
    delta: [Complex64; 2],
    g0: Complex64,
}

/// The lines one band's fit reads and its unknowns per curve.
struct Band {
    band_hz: [f64; 2],
    lines: Vec<usize>,
    others: Vec<Complex64>,
    unknowns: usize,
}

impl<'a> Pair<'a> {
    /// The pair of `targets` whose ladder results are `modes`. Where both poles matched one
    /// mode of the model (a nearly double pair), the pair is that mode and its neighbour
    /// nearer the pair (by the branch's mean δ), the lower rank for the lower pole, each with
    /// its own δ from the ladder's levels at G₀.
    fn new(
        coarsest: &'a LayeredInverse,
        targets: [Complex64; 2],
        modes: [&ConvergedMode; 2],
        correction: &Correction,
    ) -> Result<Self> {
        let mut start = [Complex64::default(); 2];
        let mut delta = [Complex64::default(); 2];
        for (i, (mode, target)) in modes.iter().zip(targets).enumerate() {
            start[i] = coarsest
                .pole_eigenvalue(mode.core_shear_pa, mode.rank, target)
                .ok_or_else(|| lost(mode.rank))?;
            delta[i] = target / start[i];
        }
        let g0 = 0.5 * (modes[0].core_shear_pa + modes[1].core_shear_pa);
        let mut pair = Self {
            coarsest,
            targets,
            ranks: [modes[0].rank, modes[1].rank],
            start,
            delta,
            g0,
        };
        if modes[0].rank == modes[1].rank {
            pair.split_the_branch(correction)?;
        }
        Ok(pair)
    }

    /// Both poles on one branch: the ranks, starts and corrections of the branch and its
    /// nearer neighbour ([`Pair::new`]).
    fn split_the_branch(&mut self, correction: &Correction) -> Result<()> {
        let (coarsest, targets, g0) = (self.coarsest, self.targets, self.g0);
        let r = self.ranks[0];
        let mean_delta = 0.5 * (self.delta[0] + self.delta[1]);
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
        self.ranks = [r.min(other), r.max(other)];
        for (i, (rank, target)) in self.ranks.into_iter().zip(targets).enumerate() {
            self.start[i] = coarsest
                .pole_eigenvalue(g0, rank, target)
                .ok_or_else(|| lost(rank))?;
            self.delta[i] = correction(g0, rank, target)
                .map_err(|e| err!("no ladder correction of the model's mode {}: {e}", rank + 1))?;
        }
        Ok(())
    }

    /// G* at x = (ln G'/G'₀, ln η/η₀).
    fn g_of(&self, x: &[f64]) -> Complex64 {
        let eta0 = self.g0.im / self.g0.re;
        let storage = self.g0.re * x[0].exp();
        Complex64::new(storage, storage * eta0 * x[1].exp())
    }

    /// The model's two poles at `g`, ladder-corrected: each tracked from its start (cheap);
    /// where that loses one or both land on one mode (a nearly double pair), by rank (an
    /// eigendecomposition each).
    fn model_pair(&self, g: Complex64) -> Option<[Complex64; 2]> {
        let c = self.coarsest;
        let tracked = c
            .pole_near(g, self.start[0])
            .zip(c.pole_near(g, self.start[1]))
            .filter(|(a, b)| (a - b).norm() > 1e-6 * a.norm());
        let (a, b) = match tracked {
            Some(t) => t,
            None => (
                c.pole_eigenvalue(g, self.ranks[0], self.targets[0])?,
                c.pole_eigenvalue(g, self.ranks[1], self.targets[1])?,
            ),
        };
        Some([self.delta[0] * a, self.delta[1] * b])
    }

    /// The lines within `half_widths` of the pair, the identification's other poles there and
    /// the unknowns per curve.
    fn band(&self, data: &Data, half_widths: f64) -> Result<Band> {
        let ((fa, za), (fb, zb)) = (
            freq_and_zeta(self.targets[0]),
            freq_and_zeta(self.targets[1]),
        );
        let band_hz = [
            (fa * (1.0 - half_widths * za)).max(data.ema.band_hz[0]),
            (fb * (1.0 + half_widths * zb)).min(data.ema.band_hz[1]),
        ];
        // The lines the residues are fitted on, also those the misfit is summed over.
        let lines = lamdyn_ema::band::positive_lines(data.freqs, band_hz);
        let others = neighbours(data.ema, self.targets, band_hz);
        let unknowns = 2 * (2 + others.len()) + 2;
        if lines.len() < unknowns {
            return Err(err!(
                "{} lines in {:.2}-{:.2} Hz for {unknowns} unknowns per curve",
                lines.len(),
                band_hz[0],
                band_hz[1]
            ));
        }
        Ok(Band {
            band_hz,
            lines,
            others,
            unknowns,
        })
    }

    /// The residuals H − Ĥ (real and imaginary parts, curve by curve) of the least-squares
    /// residues with the pair's poles at `pair` and the band's other poles.
    fn residuals(&self, data: &Data, band: &Band, pair: [Complex64; 2]) -> Option<Vec<f64>> {
        let mut poles = vec![pole_of(pair[0]), pole_of(pair[1])];
        poles.extend(&band.others);
        let fit = lamdyn_ema::lsfd::lsfd(
            data.freqs,
            &data.curves,
            data.quantity,
            &poles,
            band.band_hz,
        )
        .ok()?;
        let mut r = Vec::with_capacity(2 * data.curves.len() * band.lines.len());
        for (o, c) in data.curves.iter().enumerate() {
            for &k in &band.lines {
                let d = c[k] - fit.synthesize(o, data.freqs[k]);
                r.extend([d.re, d.im]);
            }
        }
        Some(r)
    }

    /// The fit over the lines within `half_widths` of the pair, x within `reach` of 0.
    fn fit(&self, data: &Data, half_widths: f64, reach: f64) -> Result<PairFit> {
        let band = self.band(data, half_widths)?;
        let residuals = |x: &[f64]| {
            // Within the basis's range about the start ([`PairFitTuning::reach`]).
            if x.iter().any(|v| v.abs() > reach) {
                return None;
            }
            self.residuals(data, &band, self.model_pair(self.g_of(x))?)
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
        let g = self.g_of(&out.x);
        let fitted = self.checked_by_rank(g)?;
        let ema_residuals = self
            .residuals(data, &band, self.targets)
            .ok_or_else(|| err!("no residues at the EMA's poles"))?;
        let sum_sq = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
        let norm: f64 = data
            .curves
            .iter()
            .map(|c| band.lines.iter().map(|&k| c[k].norm_sqr()).sum::<f64>())
            .sum();
        let rel_sd = relative_sd(&out, data.curves.len() * band.unknowns + 2)?;
        Ok(PairFit {
            g_pa: g,
            targets: fitted,
            rel_sd,
            band_hz: band.band_hz,
            lines: band.lines.len(),
            band_choice_sd: None,
            misfit: [
                (sum_sq(&ema_residuals) / norm).sqrt(),
                (out.cost / norm).sqrt(),
            ],
        })
    }

    /// The model's poles at the fitted `g`, checked to be the two modes' by rank (a close
    /// pair can swap when tracked).
    fn checked_by_rank(&self, g: Complex64) -> Result<[Complex64; 2]> {
        let fitted = self
            .model_pair(g)
            .ok_or_else(|| err!("the fitted poles are lost"))?;
        for (i, fit) in fitted.iter().enumerate() {
            let by_rank = self
                .coarsest
                .pole_eigenvalue(g, self.ranks[i], self.targets[i])
                .ok_or_else(|| lost(self.ranks[i]))?;
            if (self.delta[i] * by_rank - fit).norm() > 1e-6 * fit.norm() {
                return Err(err!(
                    "the fit's pole at {:.3} Hz is not the model's elastic mode {} at G* = {g:.4e} \
                     Pa",
                    freq_and_zeta(*fit).0,
                    self.ranks[i] + 1
                ));
            }
        }
        Ok(fitted)
    }
}

/// The standard deviations of ln G' and ln η from a fit's s² (JᵀJ)⁻¹, s² = S/(m − n) with `n`
/// every unknown of the fit (module docs).
fn relative_sd(out: &lamdyn_fit::lm::LmOutcome, n: usize) -> Result<[f64; 2]> {
    let m = out.residuals.len();
    if m <= n {
        return Err(err!("{m} residuals for {n} unknowns"));
    }
    let s2 = out.cost / (m - n) as f64;
    let jtj = out.jacobian.transpose() * &out.jacobian;
    let det = jtj[(0, 0)] * jtj[(1, 1)] - jtj[(0, 1)] * jtj[(1, 0)];
    if det.is_nan() || det <= 0.0 {
        return Err(err!("the FRFs do not determine G' and eta at the pair"));
    }
    Ok([
        (s2 * jtj[(1, 1)] / det).sqrt(),
        (s2 * jtj[(0, 0)] / det).sqrt(),
    ])
}

/// A mode of the model that no longer has a pole.
fn lost(rank: usize) -> crate::PipelineError {
    err!("the model's elastic mode {} lost", rank + 1)
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
