//! The refined poles checked in the context of the LSCF model the stabilization diagram was read
//! from: a refined pole replaces the diagram's only where the measured curves say so.
//!
//! **Why.** The refinement ([`crate::lsfd::refine`]) fits the poles with real lower and upper
//! residual terms beside them (the maximum-likelihood estimate for white noise *if* that model
//! held). The modes outside the band and the damped modes' tails do not fit those terms, and a
//! damped pole, broad and flat, takes up the misfit where the diagram's pole is exact. The
//! diagram's pole has the opposite weakness: the linearised LSCF is biased by noise, which the
//! refinement removes. The measurements, and the alternatives measured worse, are in
//! docs/ema.md ("Damped poles").
//!
//! **The context.** The LSCF model of order n is H_o(Ω) = B_o(Ω) A(Ω)⁻¹ with Ω = e^{−iωΔt} and
//! real coefficients ([`crate::lscf`]); its partial fractions (module `denominator`) span the
//! functions the numerators B_o can make (for several references the residues per curve are
//! free, where PolyMAX ties them into rank-one matrices). The roots of the diagram's highest
//! order hold the modes outside the band, the band's edges and the noise (its computational
//! roots); with the roots fixed the model is linear in the residues and the direct term d_o
//! (real).
//!
//! **The check.** With the physical poles' own roots replaced by the poles (x = e^{−λΔt}), the
//! residual sum of squares J of that model (the fixed columns projected out once, the residues
//! eliminated: variable projection [Golub & Pereyra 1973]) is computed at the diagram's poles
//! and, pole by pole, with one refined pole in place of its diagram pole. The refined pole is
//! taken where J drops by more than the 99 % point of χ² with two degrees of freedom times the
//! residual variance (J/dof at the diagram's poles): more than moving one pole's two parameters
//! takes from noise alone. Close poles are coupled (one of a close pair moved alone can fit
//! worse), so neighbours whose half-power bands overlap and neither of which passed alone are
//! tried together, with the χ² point of four degrees of freedom. On noise-free curves the
//! diagram's poles already fit the context model, and the refinement's moves bring no
//! significant drop; with noise the linearised estimator's bias does.
//!
//! **Poles refitted alone.** The local step (module `local_refit`) refits a pole that stands
//! alone on its own lines with the rest of the band's model held, pseudo-modes in place of the
//! outside roots. Where the context model's misfit is systematic (damped modes: the outside
//! roots and the damped tails do not fit, module `local_refit`), the diagram's pole carries
//! that misfit's bias, J is lowest near it, and the less biased refit does not lower J
//! significantly: it was refused where it lay nearer the truth (the virtual plates of
//! docs/ema.md, "Damped poles"). Such a pole is therefore taken unless it *raises* J
//! significantly: by more than the same χ² point times the residual variance or times the
//! curves' noise variance (module `noise`), whichever is smaller. Where the context model
//! misfits beyond the noise (noise-free FRFs of a viscoelastic part, whose modulus follows the
//! frequency so that no pole fits exactly), a rise the noise cannot explain is the context
//! model contradicting the refit. Provided, too, that the refit is a correction: it moves the
//! diagram's pole by more than `LOCAL_RESOLUTION` of its half-power half-width (the local
//! model of the modes outside the band is approximate: on exact FRFs it moves an exact
//! diagram pole by a small fraction of that, docs/ema.md, and a move that small is no
//! evidence) and by no more than `LOCAL_CORRECTION` of it. The noise's bias on the diagram's
//! pole is a small fraction of the half-width; a larger move that the context model does not
//! find better is the data's indifference (a weak mode, a measured record the modal model
//! does not describe: docs/ema.md, method step 4), and there the diagram's pole is kept, its
//! deviation widened by the difference (module `identify`).
//!
//! **Each curve in units of its noise.** The χ² test holds where every residual has one
//! variance. Curves measured with different noise (channels of different sensitivity, noise in
//! proportion to each curve's level) are weighted by 1/σ̂ of each, σ̂ its line-to-line noise
//! estimate (module `noise`); J is then the sum of squares of the weighted residuals, and the
//! test's decision does not depend on any curve's scale or units. The refinement itself stays
//! unweighted: weighting it too traded modes for others (docs/ema.md, "Damped poles").
//!
//! **Several estimates.** An estimator may move a pole where the context cannot follow: with one
//! reference the rank-one fit resolves two modes under a pole over a close pair, where the
//! context has one pole, and the check refuses the pole of the pair. There another estimate of
//! the same pole (the joint refinement's, one pole as the context's) is tried by the same test,
//! against the diagram's poles ([`RefinementCheck::taken_first`]; docs/ema.md, "Where the fit
//! and the context disagree").
//!
//! **Moves that change the model.** The refinement corrects the diagram's poles; a refined pole
//! that ends nearer another diagram pole than its own has merged with or swapped for that
//! neighbour, and is never taken. A pole the refinement lost (one that left its column in the
//! diagram) is put back before the check, and so is each refined pole whose half-power band
//! overlaps that of a lost one (module `columns`): it was fitted beside a pole standing
//! elsewhere and may have taken over that pole's mode. A pole put back is the diagram's, and
//! its trial changes nothing. Where the context model misfits (heavily damped, overlapping
//! modes: its J at the diagram's poles is systematic, not noise) such moves can pass the χ²
//! test (docs/ema.md, "Damped poles").

pub use crate::denominator::LscfContext;
use crate::denominator::{pair_columns, root_columns, scaled_real_matrix};
use crate::lscf::half_power_bands_overlap;
use crate::lsfd::{RefineLines, refinement_lines};
use crate::noise::CurveNoise;
use crate::thin_qr::ThinQr;
use faer::Mat;
use num_complex::Complex64;
use rayon::prelude::*;

/// The context model on the refinement's lines: the data with the fixed columns projected out.
/// With the QR F = Q R of the fixed columns F (rows × k), the projection is taken in Q's
/// coordinates: Qᵀ(I − Q₁Q₁ᵀ)X is Qᵀ X with its first k rows zeroed, so the problem of the free
/// columns is that of the last rows of Qᵀ P and Qᵀ B, and Q is applied as its Householder
/// reflections, never formed.
struct ContextProblem<'a> {
    context: &'a LscfContext,
    /// Ω_k of each line.
    omega: Vec<Complex64>,
    /// The QR of the fixed columns (direct term and fixed roots).
    fixed: ThinQr,
    /// The last rows − k rows of Qᵀ B: the data with the fixed columns projected out, in Q's
    /// coordinates, one column per curve.
    data: Mat<f64>,
}

impl<'a> ContextProblem<'a> {
    /// The problem on `lines` with the roots of `context` fixed but those of `poles`, curve o
    /// weighted by `weights[o]` (its residuals and sums of squares in units of its noise).
    fn new(
        freqs_hz: &[f64],
        curves: &[&[Complex64]],
        weights: &[f64],
        lines: &[usize],
        context: &'a LscfContext,
        poles: &[Complex64],
    ) -> Self {
        let omega = context.omega(freqs_hz, lines);
        let mut cols: Vec<Vec<Complex64>> = vec![vec![Complex64::new(1.0, 0.0); omega.len()]];
        cols.extend(root_columns(&omega, &context.fixed_roots(poles)));
        let rows = 2 * lines.len();
        let fixed = ThinQr::of(scaled_real_matrix(&cols, rows));
        let b = Mat::from_fn(rows, curves.len(), |row, o| {
            let h = curves[o][lines[row / 2]] * weights[o];
            if row % 2 == 0 { h.re } else { h.im }
        });
        let data = projected_out(&fixed, b);
        Self {
            context,
            omega,
            fixed,
            data,
        }
    }

    /// The residual sum of squares with the physical poles `poles` (their residues fitted): the
    /// last rows of Q_Pᵀ times the data, for the QR of the projected pole columns P = Q_P R_P;
    /// None where it is not finite. (The check solves its trials from the diagram's fit,
    /// [`DiagramFit::cost_moved`].)
    #[cfg(test)]
    fn cost(&self, poles: &[Complex64]) -> Option<f64> {
        let columns: Vec<Mat<f64>> = poles.iter().map(|&p| self.pole_columns(p)).collect();
        DiagramFit::of(self, &columns).cost()
    }

    /// The two columns of the physical pole `p`, each scaled to unit norm, with the fixed
    /// columns projected out ([`projected_out`]): the same for every set of poles it is in.
    fn pole_columns(&self, p: Complex64) -> Mat<f64> {
        let (g1, g2) = pair_columns(&self.omega, self.context.root(p));
        projected_out(
            &self.fixed,
            scaled_real_matrix(&[g1, g2], 2 * self.omega.len()),
        )
    }

    /// Degrees of freedom of the residuals with `poles` physical poles.
    fn dof(&self, poles: usize) -> usize {
        let per_curve = 2 * self.omega.len();
        let unknowns = self.fixed.r_rows() + 2 * poles;
        (self.data.ncols() * per_curve.saturating_sub(unknowns)).max(1)
    }
}

/// The last rows of Qᵀ `m` for the QR `fixed` (rows × k): `m` with the span of the fixed
/// columns projected out, in Q's coordinates ([`ContextProblem`]).
fn projected_out(fixed: &ThinQr, mut m: Mat<f64>) -> Mat<f64> {
    fixed.apply_transpose_q(&mut m);
    let k = fixed.r_rows();
    m.subrows(k, m.nrows() - k).to_owned()
}

/// The context problem at the diagram's poles: J there and the fit of the diagram's poles
/// ([`DiagramFit`]), which a trial that moves some poles reuses.
struct DiagramModel<'a> {
    problem: ContextProblem<'a>,
    /// J at the diagram's poles.
    base: f64,
    fit: DiagramFit,
}

/// The diagram's poles fitted in the context problem: the QR of their projected columns
/// P = Q_P R_P ([`ContextProblem::pole_columns`], two per pole in the diagram's order) and
/// Q_Pᵀ times the data. A trial that moves m of the n poles is solved in Q_P's coordinates,
/// where the columns of the poles kept are R_P's, zero below row 2n: with the moved poles'
/// columns N taken to Q_Pᵀ N = [N₁; N₂] and the tall N₂ = Q₂ [T; 0] factorised, the trial's
/// least-squares problem is the small [R_kept, N₁; 0, T] on the first 2n + 2m rows of
/// [Q_Pᵀ B]₁ and Q₂ᵀ[Q_Pᵀ B]₂, plus the rest of Q₂ᵀ[Q_Pᵀ B]₂, which no column reaches. Every
/// step is orthogonal, so its sum of squares is that of the QR of all the trial's columns, at
/// Qᵀ applied to 2m columns and the curves instead of a QR of 2n columns per trial.
struct DiagramFit {
    qr: ThinQr,
    /// Q_Pᵀ B, rows × curves.
    qtd: Mat<f64>,
}

impl DiagramFit {
    /// The fit of the diagram's pole columns `columns` to the `problem`'s data.
    fn of(problem: &ContextProblem<'_>, columns: &[Mat<f64>]) -> Self {
        let qr = ThinQr::of(side_by_side(columns, problem.data.nrows()));
        let mut qtd = problem.data.clone();
        qr.apply_transpose_q(&mut qtd);
        Self { qr, qtd }
    }

    /// J at the diagram's poles: the rows of Q_Pᵀ B below the poles' columns; None where it
    /// is not finite.
    fn cost(&self) -> Option<f64> {
        let k = self.qr.r_rows();
        let j = self.qtd.subrows(k, self.qtd.nrows() - k).squared_norm_l2();
        j.is_finite().then_some(j)
    }

    /// J with each pole of `members` (indices into the diagram's) at the columns `moved` of
    /// the same index, the others at the diagram's (the type's docs); None where it is not
    /// finite.
    fn cost_moved(&self, members: &[usize], moved: &[Mat<f64>]) -> Option<f64> {
        let (rows, k) = (self.qtd.nrows(), self.qr.r_rows());
        let r = self.qr.r();
        let kept: Vec<usize> = (0..r.ncols())
            .filter(|c| !members.contains(&(c / 2)))
            .collect();
        let mut n = side_by_side(moved, rows);
        self.qr.apply_transpose_q(&mut n);
        let below = ThinQr::of(n.subrows(k, rows - k).to_owned());
        let mut d2 = self.qtd.subrows(k, rows - k).to_owned();
        below.apply_transpose_q(&mut d2);
        let (m, t) = (below.r_rows(), below.r());
        let small = Mat::from_fn(k + m, kept.len() + n.ncols(), |i, j| {
            match (i < k, j < kept.len()) {
                (true, true) => r[(i, kept[j])],
                (true, false) => n[(i, j - kept.len())],
                (false, true) => 0.0,
                (false, false) => t[(i - k, j - kept.len())],
            }
        });
        let mut small_d = Mat::from_fn(k + m, self.qtd.ncols(), |i, o| {
            if i < k {
                self.qtd[(i, o)]
            } else {
                d2[(i - k, o)]
            }
        });
        let small_qr = ThinQr::of(small);
        small_qr.apply_transpose_q(&mut small_d);
        let fitted = small_qr.r_rows();
        let j = small_d.subrows(fitted, k + m - fitted).squared_norm_l2()
            + d2.subrows(m, d2.nrows() - m).squared_norm_l2();
        j.is_finite().then_some(j)
    }
}

/// The poles' two columns each (`rows` rows) side by side, in their order.
fn side_by_side(columns: &[Mat<f64>], rows: usize) -> Mat<f64> {
    let mut p = Mat::<f64>::zeros(rows, 2 * columns.len());
    for (r, c) in columns.iter().enumerate() {
        p.subcols_mut(2 * r, 2).copy_from(c);
    }
    p
}

/// The check of refined poles against their diagram poles (module docs), prepared from the
/// diagram's poles alone: the context model with the fixed columns projected out and its sum of
/// squares at the diagram's poles. It does not depend on the refinement, so a caller can build it
/// while the refinement runs.
pub struct RefinementCheck<'a> {
    diagram: Vec<Complex64>,
    /// The context problem at the diagram's poles; None where J is not finite there (the
    /// diagram's poles are kept then).
    model: Option<DiagramModel<'a>>,
    /// The weighted curves' noise variance per residual ([`CurveNoise::weighted_variance`]).
    noise_variance: Option<f64>,
}

impl<'a> RefinementCheck<'a> {
    /// The check of the diagram's poles `diagram` on the lines `fit_lines` chooses in `band_hz`
    /// (the refinement's), in the LSCF model's `context`; `curves` are the values at `freqs_hz`
    /// the LSCF model was fitted to, already checked by the refinement's caller, and `noise`
    /// their noise levels over the band's positive lines ([`crate::band::positive_lines`]).
    pub fn new(
        freqs_hz: &[f64],
        curves: &[&[Complex64]],
        diagram: &[Complex64],
        band_hz: [f64; 2],
        fit_lines: RefineLines,
        context: &'a LscfContext,
        noise: &CurveNoise,
    ) -> Self {
        let band = crate::band::positive_lines(freqs_hz, band_hz);
        let lines = refinement_lines(freqs_hz, &band, diagram, fit_lines);
        let weights = noise.weights();
        let problem = ContextProblem::new(freqs_hz, curves, &weights, &lines, context, diagram);
        let columns: Vec<Mat<f64>> = diagram.iter().map(|&p| problem.pole_columns(p)).collect();
        let fit = DiagramFit::of(&problem, &columns);
        let model = fit.cost().map(|base| DiagramModel { problem, base, fit });
        Self {
            diagram: diagram.to_vec(),
            model,
            noise_variance: noise.weighted_variance(),
        }
    }

    /// The poles taken of `refined` (index-aligned with the diagram's poles; those the
    /// refinement lost already put back by the caller, module docs): each refined pole that
    /// keeps to its own (module docs, "Moves that change the model") and lowers the context's
    /// sum of squares significantly by itself, or, where `refitted_alone` (module
    /// `local_refit`), does not raise it significantly (against the smaller of the residual
    /// variance and the curves' noise variance) and is a correction of the diagram's pole
    /// (module docs, "Poles refitted alone"); then, of each pair of neighbours whose
    /// half-power bands overlap (|f₁ − f₂| < ζ₁f₁ + ζ₂f₂) and neither of which was taken alone,
    /// both refined poles where together they do (coupled in the fit: one of a close pair moved
    /// alone can fit worse); the diagram's pole elsewhere.
    pub fn taken(&self, refined: &[Complex64], refitted_alone: &[bool]) -> Vec<Complex64> {
        let diagram = &self.diagram;
        let Some(DiagramModel { problem, base, fit }) = &self.model else {
            return diagram.clone();
        };
        let variance = base / problem.dof(diagram.len()) as f64;
        let own = stays_with_its_own(diagram, refined);
        // J's drop with `members` refined, None where one of them left its own or J is not
        // finite there.
        let drop = |members: &[usize]| {
            if !members.iter().all(|&r| own[r]) {
                return None;
            }
            let moved: Vec<Mat<f64>> = members
                .iter()
                .map(|&r| problem.pole_columns(refined[r]))
                .collect();
            fit.cost_moved(members, &moved).map(|c| base - c)
        };
        let significant = |members: &[usize]| {
            drop(members).is_some_and(|d| d > chi_square_99(2 * members.len()) * variance)
        };
        let limit = chi_square_99(2) * variance;
        // A rise is judged against the noise where the context misfits beyond it.
        let rise_limit =
            chi_square_99(2) * self.noise_variance.map_or(variance, |n| n.min(variance));
        let alone: Vec<bool> = (0..diagram.len())
            .into_par_iter()
            .map(|r| {
                // A pole put back or left where it was changes nothing: no trial to fit.
                if refined[r] == diagram[r] {
                    return false;
                }
                let local = refitted_alone.get(r) == Some(&true)
                    && a_local_correction(diagram[r], refined[r]);
                drop(&[r]).is_some_and(|d| d > limit || (local && d > -rise_limit))
            })
            .collect();
        let mut taken: Vec<Complex64> = (0..diagram.len())
            .map(|r| if alone[r] { refined[r] } else { diagram[r] })
            .collect();
        for [a, b] in overlapping_pairs(diagram) {
            if !alone[a] && !alone[b] && significant(&[a, b]) {
                taken[a] = refined[a];
                taken[b] = refined[b];
            }
        }
        taken
    }

    /// The poles taken of several `estimates` in order of preference: each pole the first
    /// estimate whose own pole there is [`Self::taken`], each trial judged against the diagram's
    /// poles (the other poles at the diagram's, as with one estimate); the diagram's pole where
    /// none is. Each estimate is a test of its own at the 99 % point, so the chance that noise
    /// alone passes one grows with their number: a later estimate is for the poles an earlier
    /// one could not fit in this context (module docs).
    pub fn taken_first(&self, estimates: &[Estimate<'_>]) -> Vec<Complex64> {
        estimates
            .iter()
            .fold(self.diagram.clone(), |taken, e| self.taken_after(taken, *e))
    }

    /// `taken` (poles already taken, the diagram's where none was) with each pole still the
    /// diagram's replaced by `estimate`'s where that is [`Self::taken`] ([`Self::taken_first`]'s
    /// step).
    pub fn taken_after(&self, mut taken: Vec<Complex64>, estimate: Estimate<'_>) -> Vec<Complex64> {
        let diagram = &self.diagram;
        let open: Vec<bool> = (0..diagram.len()).map(|r| taken[r] == diagram[r]).collect();
        let tried: Vec<Complex64> = (0..diagram.len())
            .map(|r| {
                if open[r] {
                    estimate.poles[r]
                } else {
                    diagram[r]
                }
            })
            .collect();
        let these = self.taken(&tried, estimate.refitted_alone);
        for (r, pole) in these.into_iter().enumerate() {
            if open[r] {
                taken[r] = pole;
            }
        }
        taken
    }
}

/// One estimator's poles for the check: index-aligned with the diagram's poles (those it lost
/// already put back, module docs), and which of them the local step refitted alone (module
/// `local_refit`).
#[derive(Debug, Clone, Copy)]
pub struct Estimate<'e> {
    /// The poles, rad/s.
    pub poles: &'e [Complex64],
    /// Whether each pole is the local step's.
    pub refitted_alone: &'e [bool],
}

/// The local step's resolution as a fraction of a pole's half-power half-width (−Re λ): a
/// refit nearer the diagram's pole than this is no evidence against it (module docs, "Poles
/// refitted alone").
const LOCAL_RESOLUTION: f64 = 3e-4;

/// The furthest a pole refitted alone moves from the diagram's pole, as a fraction of its
/// half-power half-width, and is still taken as a correction of the diagram's bias where the
/// context model does not find it better (module docs, "Poles refitted alone").
const LOCAL_CORRECTION: f64 = 0.03;

/// Whether `refit` lies further from `diagram` than [`LOCAL_RESOLUTION`] of its half-power
/// half-width and no further than [`LOCAL_CORRECTION`] of it.
fn a_local_correction(diagram: Complex64, refit: Complex64) -> bool {
    let moved = (refit - diagram).norm() / -diagram.re;
    moved > LOCAL_RESOLUTION && moved <= LOCAL_CORRECTION
}

/// For each refined pole, whether it lies nearer its own diagram pole than any other (in the
/// complex plane; module docs, "Moves that change the model").
fn stays_with_its_own(diagram: &[Complex64], refined: &[Complex64]) -> Vec<bool> {
    refined
        .iter()
        .enumerate()
        .map(|(r, p)| {
            let own = (p - diagram[r]).norm();
            diagram
                .iter()
                .enumerate()
                .all(|(j, d)| j == r || (p - d).norm() > own)
        })
        .collect()
}

/// Neighbours (by frequency) whose half-power bands overlap ([`half_power_bands_overlap`]), as
/// indices into `poles`.
fn overlapping_pairs(poles: &[Complex64]) -> Vec<[usize; 2]> {
    let mut order: Vec<usize> = (0..poles.len()).collect();
    order.sort_by(|&a, &b| poles[a].im.total_cmp(&poles[b].im));
    order
        .windows(2)
        .filter(|w| half_power_bands_overlap(poles[w[0]], poles[w[1]]))
        .map(|w| [w[0], w[1]])
        .collect()
}

/// The 99 % point of χ² with `dof` degrees of freedom (Wilson–Hilferty: within 0.5 % from two
/// degrees of freedom up; 9.21 for two).
pub(crate) fn chi_square_99(dof: usize) -> f64 {
    let v = dof as f64;
    let a = 2.0 / (9.0 * v);
    v * (1.0 - a + 2.326_348 * a.sqrt()).powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::tests::gaussian_sequence;
    use std::f64::consts::PI;

    #[test]
    fn chi_square_points_match_the_tables() {
        // 99 % points of χ² (Abramowitz & Stegun, table 26.8): 2, 4, 6, 10 degrees of freedom.
        for (dof, want) in [(2, 9.210), (4, 13.277), (6, 16.812), (10, 23.209)] {
            let got = chi_square_99(dof);
            assert!((got / want - 1.0).abs() < 5e-3, "{dof}: {got} vs {want}");
        }
    }

    /// A refined pole that moved past the midpoint towards its neighbour has merged with it.
    #[test]
    fn a_refined_pole_nearer_another_diagram_pole_is_not_its_own() {
        let pole = |f: f64| Complex64::new(-0.08 * 2.0 * PI * f, 2.0 * PI * f);
        let diagram = [pole(150.625), pole(152.5), pole(175.6)];
        let refined = [pole(152.006), pole(152.49), pole(175.0)];
        assert_eq!(
            stays_with_its_own(&diagram, &refined),
            vec![false, true, true]
        );
    }

    /// Two curves of one mode in the context model's own form (direct term and one pair of
    /// partial fractions), one with a thousandth of the other's noise. The diagram's pole is
    /// off by so little that the loud curve cannot tell (its misfit a quarter of its noise
    /// variance), the quiet one by thousands of its variances: the refined pole is taken, and
    /// so it is with the quiet curve scaled by 1000. Unweighted, the pooled variance is the
    /// loud curve's and the pole was refused unscaled, taken scaled.
    #[test]
    fn a_quiet_curve_is_heard_beside_a_loud_one() {
        let pole = |f: f64| Complex64::new(-0.02 * 2.0 * PI * f, 2.0 * PI * f);
        let context = LscfContext {
            dt: 1.0 / 140.0,
            roots: vec![],
        };
        let freqs: Vec<f64> = (0..=7000).map(|k| 0.01 * f64::from(k)).collect();
        let (band, every) = ([30.0, 70.0], RefineLines::All);
        let all: Vec<usize> = (0..freqs.len()).collect();
        let (g1, g2) = pair_columns(&context.omega(&freqs, &all), context.root(pole(50.0)));
        let clean: Vec<Complex64> = g1.iter().zip(&g2).map(|(a, b)| a + 0.3 * b).collect();
        let lines = crate::band::positive_lines(&freqs, band);
        let misfit = |df: f64| {
            let problem = ContextProblem::new(&freqs, &[&clean], &[1.0], &lines, &context, &[]);
            problem.cost(&[pole(50.0 * (1.0 + df))]).unwrap()
        };
        let rms =
            (lines.iter().map(|&k| clean[k].norm_sqr()).sum::<f64>() / lines.len() as f64).sqrt();
        let (quiet, loud) = (1e-4 * rms, 0.1 * rms);
        let df = 1e-5 * (0.25 * loud * loud / misfit(1e-5)).sqrt();
        let (mut noise_a, mut noise_b) = (gaussian_sequence(5), gaussian_sequence(6));
        let a: Vec<Complex64> = clean.iter().map(|h| h + quiet * noise_a()).collect();
        let b: Vec<Complex64> = clean.iter().map(|h| h + loud * noise_b()).collect();
        let a_scaled: Vec<Complex64> = a.iter().map(|h| h * 1000.0).collect();
        let (diagram, refined) = ([pole(50.0 * (1.0 + df))], [pole(50.0)]);
        for quiet_curve in [&a, &a_scaled] {
            let curves: [&[Complex64]; 2] = [quiet_curve, &b];
            let noise = CurveNoise::of(&curves, &crate::band::positive_lines(&freqs, band));
            let check =
                RefinementCheck::new(&freqs, &curves, &diagram, band, every, &context, &noise);
            assert_eq!(check.taken(&refined, &[false]), refined.to_vec());
        }
    }

    /// A trial solved from the diagram's fit (one pole moved, then two) has the sum of squares
    /// of the QR of all its columns: three damped modes (two overlapping) on two curves with
    /// noise, each trial pole 0.5 % off its diagram pole.
    #[test]
    fn a_trial_from_the_diagrams_fit_is_the_fit_of_all_its_columns() {
        let pole = |f: f64, z: f64| Complex64::new(-z * 2.0 * PI * f, 2.0 * PI * f);
        let context = LscfContext {
            dt: 1.0 / 140.0,
            roots: vec![],
        };
        let freqs: Vec<f64> = (0..=7000).map(|k| 0.01 * f64::from(k)).collect();
        let all: Vec<usize> = (0..freqs.len()).collect();
        let omega = context.omega(&freqs, &all);
        let diagram = [pole(40.0, 0.03), pole(50.0, 0.05), pole(52.0, 0.04)];
        let curve = |weights: [f64; 3], seed: u64| -> Vec<Complex64> {
            let mut noise = gaussian_sequence(seed);
            let mut h = vec![Complex64::default(); freqs.len()];
            for (p, w) in diagram.iter().zip(weights) {
                let (g1, g2) = pair_columns(&omega, context.root(*p));
                for (k, v) in h.iter_mut().enumerate() {
                    *v += w * (g1[k] + 0.3 * g2[k]);
                }
            }
            h.iter().map(|v| v + 0.01 * noise()).collect()
        };
        let (a, b) = (curve([1.0, 0.5, -0.8], 3), curve([0.2, -1.0, 0.6], 4));
        let lines = crate::band::positive_lines(&freqs, [30.0, 70.0]);
        let problem =
            ContextProblem::new(&freqs, &[&a, &b], &[1.0, 2.0], &lines, &context, &diagram);
        let columns: Vec<Mat<f64>> = diagram.iter().map(|&p| problem.pole_columns(p)).collect();
        let fit = DiagramFit::of(&problem, &columns);
        let moved = |r: usize| diagram[r] * Complex64::new(1.005, 0.0);
        for members in [vec![1], vec![0], vec![1, 2]] {
            let trial: Vec<Complex64> = (0..3)
                .map(|r| {
                    if members.contains(&r) {
                        moved(r)
                    } else {
                        diagram[r]
                    }
                })
                .collect();
            let want = problem.cost(&trial).unwrap();
            let new: Vec<Mat<f64>> = members
                .iter()
                .map(|&r| problem.pole_columns(moved(r)))
                .collect();
            let got = fit.cost_moved(&members, &new).unwrap();
            assert!(
                (got - want).abs() < 1e-10 * want,
                "{members:?}: {got} against {want}"
            );
            assert!(want > fit.cost().unwrap(), "{members:?}");
        }
    }

    /// One mode at 50 Hz, ζ 5 %, in the context model's own form (one pair of partial
    /// fractions, no other roots) on 0.01 Hz lines, checked over 30–70 Hz.
    struct OneMode {
        context: LscfContext,
        freqs: Vec<f64>,
        lines: Vec<usize>,
        truth: Complex64,
        /// The mode's curve at every line.
        clean: Vec<Complex64>,
    }

    impl OneMode {
        const BAND: [f64; 2] = [30.0, 70.0];

        fn new() -> Self {
            let context = LscfContext {
                dt: 1.0 / 140.0,
                roots: vec![],
            };
            let freqs: Vec<f64> = (0..=7000).map(|k| 0.01 * f64::from(k)).collect();
            let all: Vec<usize> = (0..freqs.len()).collect();
            let truth = Complex64::new(-0.05 * 2.0 * PI * 50.0, 2.0 * PI * 50.0);
            let (g1, g2) = pair_columns(&context.omega(&freqs, &all), context.root(truth));
            let clean = g1.iter().zip(&g2).map(|(a, b)| a + 0.3 * b).collect();
            let lines = crate::band::positive_lines(&freqs, Self::BAND);
            Self {
                context,
                freqs,
                lines,
                truth,
                clean,
            }
        }

        /// The mode's curve with complex noise of `level` times its RMS over the band's
        /// lines (seed `seed`).
        fn with_noise(&self, level: f64, seed: u64) -> Vec<Complex64> {
            let lines = &self.lines;
            let rms = (lines.iter().map(|&k| self.clean[k].norm_sqr()).sum::<f64>()
                / lines.len() as f64)
                .sqrt();
            let mut noise = gaussian_sequence(seed);
            self.clean
                .iter()
                .map(|h| h + level * rms * noise())
                .collect()
        }

        /// The check of the diagram's pole `diagram` on `curves`.
        fn check<'a>(
            &'a self,
            curves: &'a [&'a [Complex64]],
            diagram: Complex64,
        ) -> RefinementCheck<'a> {
            RefinementCheck::new(
                &self.freqs,
                curves,
                &[diagram],
                Self::BAND,
                RefineLines::All,
                &self.context,
                &CurveNoise::of(curves, &self.lines),
            )
        }
    }

    /// One mode with noise; the diagram's pole off by so little that moving it to the truth
    /// lowers J by less than the χ² point: refused as a joint refinement, taken as a pole
    /// refitted alone (module docs, "Poles refitted alone").
    #[test]
    fn a_pole_refitted_alone_is_taken_where_the_context_cannot_tell() {
        let mode = OneMode::new();
        let curve = mode.with_noise(0.05, 11);
        let curves: [&[Complex64]; 1] = [&curve];
        let truth = mode.truth;
        let check = mode.check(&curves, truth * Complex64::new(1.0 + 1e-4, 0.0));
        let diagram = check.diagram.clone();
        assert!(a_local_correction(diagram[0], truth));
        assert_eq!(check.taken(&[truth], &[false]), diagram);
        assert_eq!(check.taken(&[truth], &[true]), vec![truth]);
    }

    /// One mode with noise, the diagram's pole 0.3 % off in frequency. An estimate the check
    /// refuses (further off still) gives way to the next one, and of two estimates it would
    /// take, the first is taken.
    #[test]
    fn a_later_estimate_is_tried_where_an_earlier_one_is_refused() {
        let mode = OneMode::new();
        let curve = mode.with_noise(0.05, 13);
        let curves: [&[Complex64]; 1] = [&curve];
        let truth = mode.truth;
        let off = |by: f64| truth * Complex64::new(1.0 + by, 0.0);
        let check = mode.check(&curves, off(3e-3));
        let diagram = check.diagram.clone();
        let (worse, near) = ([off(6e-3)], [off(5e-4)]);
        assert_eq!(check.taken(&worse, &[false]), diagram);
        assert_eq!(check.taken(&near, &[false]), near.to_vec());
        assert_eq!(check.taken(&[truth], &[false]), vec![truth]);
        fn estimate(poles: &[Complex64]) -> Estimate<'_> {
            Estimate {
                poles,
                refitted_alone: &[false],
            }
        }
        let truth = [truth];
        let refused_first = [estimate(&worse), estimate(&truth)];
        assert_eq!(check.taken_first(&refused_first), truth.to_vec());
        let both_pass = [estimate(&near), estimate(&truth)];
        assert_eq!(check.taken_first(&both_pass), near.to_vec());
        assert_eq!(check.taken_first(&[estimate(&worse)]), diagram);
    }

    /// One mode and a smooth background the context model lacks, with noise a ten-thousandth
    /// of that background: J/dof is the misfit, far above the noise. A refit that raises J by
    /// less than the χ² point times J/dof, but by more than the noise explains, is taken when
    /// judged against J/dof alone and refused against the noise (module docs, "Poles refitted
    /// alone").
    #[test]
    fn a_refit_that_raises_a_misfitting_context_beyond_the_noise_is_refused() {
        let mode = OneMode::new();
        let mut noise = gaussian_sequence(12);
        let curve: Vec<Complex64> = (0..mode.freqs.len())
            .map(|k| {
                let background = 3.0 * ((mode.freqs[k] - 50.0) / 20.0).powi(3);
                mode.clean[k] + background + 3e-4 * noise()
            })
            .collect();
        let curves: [&[Complex64]; 1] = [&curve];
        let truth = mode.truth;
        let mut check = mode.check(&curves, truth);
        let floor = check.noise_variance;
        assert!(floor.is_some());
        // Moves of k thousandths of the half-power half-width, within a local correction's.
        let moves = (1..=30).map(|k| truth * Complex64::new(1.0, 1e-3 * f64::from(k) * 0.05));
        let taken_without_the_floor: Vec<Complex64> = moves
            .filter(|&p| {
                check.noise_variance = None;
                check.taken(&[p], &[true]) == vec![p]
            })
            .collect();
        assert!(!taken_without_the_floor.is_empty());
        check.noise_variance = floor;
        for p in taken_without_the_floor {
            assert_eq!(check.taken(&[p], &[true]), vec![truth], "{p}");
        }
    }

    #[test]
    fn a_local_correction_moves_a_pole_more_than_its_resolution_and_little() {
        // Half-power half-width 10 rad/s; a move of `fraction` of it along the imaginary axis.
        let diagram = Complex64::new(-10.0, 500.0);
        let moved = |fraction: f64| diagram + Complex64::new(0.0, 10.0 * fraction);
        let is_a_correction = |fraction: f64| a_local_correction(diagram, moved(fraction));
        assert!(!is_a_correction(0.5 * LOCAL_RESOLUTION));
        assert!(is_a_correction(2.0 * LOCAL_RESOLUTION));
        assert!(is_a_correction(0.99 * LOCAL_CORRECTION));
        assert!(!is_a_correction(1.5 * LOCAL_CORRECTION));
    }

    #[test]
    fn overlapping_neighbours_are_paired() {
        let pole = |f: f64, z: f64| {
            let w = 2.0 * PI * f;
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        };
        let poles = [
            pole(40.056, 0.012),
            pole(15.0, 0.01),
            pole(40.0, 0.01),
            pole(65.0, 0.008),
        ];
        assert_eq!(overlapping_pairs(&poles), vec![[2, 0]]);
    }
}
