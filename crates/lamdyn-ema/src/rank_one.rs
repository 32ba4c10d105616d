//! The joint pole fit with rank-one residues: each mode's residues over responses o and
//! references j are ψ_o L_j (one shape, one participation vector), not one free residue per
//! curve. With one reference L is 1 and the shape's residues are free; the fit then differs
//! from the refinement of [`crate::lsfd`] by the modes it holds beside the selected ones.
//!
//! **Why.** The refinement of [`crate::lsfd`] gives each curve its own residue per mode. Two
//! close damped modes then trade residues on every curve, and the curves cannot say where
//! either pole lies: the Cramér–Rao bound of a damped close pair is far wider with free
//! residues than with rank-one ones (docs/ema.md, "What the free residues cost at a close
//! pair", measured there). The modal model ties them: the pair's two participation vectors
//! differ, and each reference's curves weigh the two modes differently.
//!
//! **The model.** On the lines ω_k, curve (o, j) is
//!
//!   H_oj(ω) = (iω)^q Σ_r [ψ_or L_rj/(iω − λ_r) + (ψ_or L_rj)*/(iω − λ_r*)] + (block terms)_oj,
//!
//! with (iω)^q the quantity's factor, and as block terms per curve the lower and upper
//! residuals and free residues at the pseudo-modes above the band ([`pseudo_modes_above`]),
//! as the joint fit holds them. For fixed poles and participation factors every response's
//! curves, their rows stacked over the references, are linear in that response's unknowns
//! (ψ_o and its block terms) with one basis shared by all responses; the unknowns are
//! eliminated by least squares (variable projection [Golub & Pereyra 1973]) and the poles
//! and participation factors are fitted by Levenberg–Marquardt on the projected residual,
//! with Kaufman's Jacobian −P⊥ D_u X (its gradient is exact; [Kaufman 1975]). Each mode's
//! L is held at 1 at its pivot reference (where it is largest at the start), the other
//! L_rj free.
//!
//! **The start.** The poles given (the diagram's), and each mode's L from the free residues
//! at those poles ([`crate::projection::solve_by_blocks`]): the dominant right singular
//! vector of the mode's residue matrix (responses × references).
//!
//! **The modes left out.** A mode of the curves that the model lacks pulls its neighbours
//! towards it. The stable poles of the diagram's highest order that are none of the given
//! poles' own ([`left_out`]) are candidates; after each fit the one the curves need most joins
//! it, where the drop of the sum of squares it brings exceeds what noise alone gives
//! ([`fitted_with_the_modes_needed`]). With one reference the diagram has one pole over two
//! close damped modes, and no column for the second; a second mode under each pole the caller
//! names (where the curves hold a second shape under it, [`crate::second_shape`]) is then a
//! candidate too ([`split_candidates`]).
//!
//! **The standard deviations.** The sandwich covariance of Kaufman's Jacobian at the fit's end,
//! each curve's residual variance in the middle ([`deviations`]): the noise's part of the
//! error, as [`crate::lsfd::pole_deviations`] gives for the refinement.

use crate::band::pseudo_modes_above;
use crate::context::chi_square_99;
use crate::denominator::without_own;
use crate::error::EmaError;
use crate::lscf::{pole_at, pole_damping, pole_freq_hz};
use crate::lsfd::{PoleSd, pole_sd, sandwich};
use crate::pole_fit::{converged_share, marquardt_step, pole_parameters, to_poles};
use crate::projection::{
    ColumnMap, LineBasis, LineSamples, expanded_gram, expanded_products, solve_by_blocks,
    unit_columns,
};
use crate::residual_spread::SecondOrderTerm;
use crate::shapes::participation;
use crate::thin_qr::ThinQr;
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Mat, Par};
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The curves of one band, stacked as the rank-one model's rows: row 2(j·lines + k) + part
/// holds line k of reference j (part 0 real, 1 imaginary), one column per response.
pub(crate) struct StackedCurves {
    omega: Vec<f64>,
    quantity: Quantity,
    references: usize,
    data: Mat<f64>,
    /// Each reference's block columns (module docs), zero outside its own rows: they do not
    /// move with the parameters, so they are built once.
    blocks: Mat<f64>,
}

impl StackedCurves {
    /// The curves (response-major: curve o·references + j) at `lines` of `freqs_hz`, values of
    /// `quantity`, with the pseudo-modes above `upper_hz`.
    ///
    /// # Errors
    /// [`EmaError::Invalid`] for a value that is not finite.
    pub(crate) fn new(
        freqs_hz: &[f64],
        curves: &[&[Complex64]],
        references: usize,
        quantity: Quantity,
        lines: &[usize],
        upper_hz: f64,
    ) -> Result<Self, EmaError> {
        let (nl, responses) = (lines.len(), curves.len() / references);
        let data = Mat::from_fn(2 * nl * references, responses, |row, o| {
            let (j, k) = ((row / 2) / nl, (row / 2) % nl);
            let h = curves[o * references + j][lines[k]];
            if row % 2 == 0 { h.re } else { h.im }
        });
        if !data.is_all_finite() {
            return Err(crate::error::invalid(
                "FRFs",
                "a value in the band is not finite".into(),
            ));
        }
        let omega: Vec<f64> = lines.iter().map(|&k| 2.0 * PI * freqs_hz[k]).collect();
        let blocks = block_columns(&omega, quantity, references, upper_hz);
        Ok(Self {
            omega,
            quantity,
            references,
            data,
            blocks,
        })
    }

    /// The basis of `poles` with participation factors `participation` (module docs): two
    /// columns per mode, then each reference's block columns.
    fn basis(&self, poles: &[Complex64], participation: &[Vec<Complex64>]) -> Mat<f64> {
        let nl = self.omega.len();
        let n = 2 * poles.len();
        let mut a = Mat::zeros(self.data.nrows(), n + self.blocks.ncols());
        a.subcols_mut(n, self.blocks.ncols())
            .copy_from(&self.blocks);
        let mut line = LineBasis::new(poles, self.quantity, 0.0);
        for (k, &w) in self.omega.iter().enumerate() {
            line.set(poles, self.quantity, w);
            for j in 0..self.references {
                for (r, &(a1, a2)) in line.fractions.iter().enumerate() {
                    let l = participation[r][j];
                    put_pair(
                        &mut a,
                        j * nl + k,
                        2 * r,
                        line.factor,
                        l * a1,
                        l.conj() * a2,
                    );
                }
            }
        }
        a
    }

    /// The base columns of each parameter pair of a mode ([`ColumnMap`]): each as the complex
    /// values at every row pair, pairs of columns (module docs). First the pole's (ln σ, ω_d),
    /// ∂(mode columns)/∂λ with e = L_rj and the squared fractions (∂/∂ln σ is Re λ times them,
    /// ∂/∂ω_d their [`ColumnMap::TURNED`]); then, for each reference j of `free`, L_rj's
    /// (re, im): the mode's columns with e = 1 on reference j's rows (e = i turns them).
    fn pair_derivatives(&self, pole: Complex64, l: &[Complex64], free: &[usize]) -> Vec<Mat<f64>> {
        let nl = self.omega.len();
        let rows = self.data.nrows();
        let mut out: Vec<Mat<f64>> = (0..1 + free.len()).map(|_| Mat::zeros(rows, 2)).collect();
        let mut line = LineBasis::new(&[pole], self.quantity, 0.0);
        for (k, &w) in self.omega.iter().enumerate() {
            line.set(&[pole], self.quantity, w);
            let (a1, a2) = line.fractions[0];
            for j in 0..self.references {
                let row = j * nl + k;
                let e = l[j];
                put_pair(
                    &mut out[0],
                    row,
                    0,
                    line.factor,
                    e * a1 * a1,
                    e.conj() * a2 * a2,
                );
                if let Some(i) = free.iter().position(|&f| f == j) {
                    put_pair(&mut out[1 + i], row, 0, line.factor, a1, a2);
                }
            }
        }
        out
    }

    /// The columns of a second-order term at `pole`: (iω)^q [c_j/(iω − λ)² + c_j*/(iω − λ*)²]
    /// with one complex coefficient c_j per reference j, at columns 2j, 2j + 1 (its real and
    /// imaginary part, as [`put_pair`]) on reference j's rows at the lines `window` marks (the
    /// pole's, [`crate::residual_spread::window_of`]), zero elsewhere.
    fn second_order_columns(&self, pole: Complex64, window: &[bool]) -> Mat<f64> {
        let nl = self.omega.len();
        let mut g = Mat::zeros(self.data.nrows(), 2 * self.references);
        let mut line = LineBasis::new(&[pole], self.quantity, 0.0);
        for (k, &w) in self.omega.iter().enumerate() {
            if !window[k] {
                continue;
            }
            line.set(&[pole], self.quantity, w);
            let (a1, a2) = line.fractions[0];
            for j in 0..self.references {
                put_pair(&mut g, j * nl + k, 2 * j, line.factor, a1 * a1, a2 * a2);
            }
        }
        g
    }
}

/// Writes, at row pair `i` (rows 2i, 2i + 1), a complex coefficient's two real columns at `c`,
/// `c` + 1: f(g₁ + g₂) for its real part and f·i(g₁ − g₂) for its imaginary part, where
/// g₁ = e/(iω − λ) and g₂ its conjugate pole's term (e* /(iω − λ*)).
fn put_pair(a: &mut Mat<f64>, i: usize, c: usize, f: Complex64, g1: Complex64, g2: Complex64) {
    LineSamples::put(a, i, c, f * (g1 + g2));
    LineSamples::put(a, i, c + 1, f * Complex64::i() * (g1 - g2));
}

/// Each of `references` blocks' columns on the stacked rows of the lines `omega` (module docs):
/// two per pseudo-mode above `upper_hz` ([`pseudo_modes_above`]), the lower and the upper
/// residual, each zero outside its own reference's rows.
fn block_columns(omega: &[f64], quantity: Quantity, references: usize, upper_hz: f64) -> Mat<f64> {
    let pseudo = pseudo_modes_above(upper_hz);
    let (nl, nb) = (omega.len(), 2 * pseudo.len() + 2);
    let mut a = Mat::zeros(2 * nl * references, nb * references);
    for (k, &w) in omega.iter().enumerate() {
        let line = LineBasis::new(&pseudo, quantity, w);
        for j in 0..references {
            let (i, c) = (j * nl + k, nb * j);
            for (m, &(a1, a2)) in line.fractions.iter().enumerate() {
                put_pair(&mut a, i, c + 2 * m, line.factor, a1, a2);
            }
            LineSamples::put(&mut a, i, c + nb - 2, line.factor * line.lower);
            LineSamples::put(&mut a, i, c + nb - 1, line.factor);
        }
    }
    a
}

/// The fit's unknowns: the poles' parameters ([`pole_parameters`]), then re and im of each
/// mode's L at each reference but its pivot.
struct Parameters {
    pivots: Vec<usize>,
    references: usize,
}

impl Parameters {
    fn free(&self, r: usize) -> Vec<usize> {
        (0..self.references)
            .filter(|&j| j != self.pivots[r])
            .collect()
    }

    fn pack(&self, poles: &[Complex64], participation: &[Vec<Complex64>]) -> Vec<f64> {
        let mut u = pole_parameters(poles);
        for (r, l) in participation.iter().enumerate() {
            u.extend(self.free(r).into_iter().flat_map(|j| [l[j].re, l[j].im]));
        }
        u
    }

    fn unpack(&self, u: &[f64]) -> (Vec<Complex64>, Vec<Vec<Complex64>>) {
        let n = self.pivots.len();
        let poles = to_poles(&u[..2 * n]);
        let mut at = 2 * n;
        let participation = (0..n)
            .map(|r| {
                let mut l = vec![Complex64::new(1.0, 0.0); self.references];
                for j in self.free(r) {
                    l[j] = Complex64::new(u[at], u[at + 1]);
                    at += 2;
                }
                l
            })
            .collect();
        (poles, participation)
    }
}

/// The residue problem at one point of the parameters: its QR, unknowns and residual.
struct Projected {
    qr: ThinQr,
    /// Unknowns (basis order) × responses, unscaled.
    unknowns: Mat<f64>,
    /// Qᵀ(B − A X): the residual in Q's coordinates (its first rows zero).
    residual_in_q: Mat<f64>,
}

impl Projected {
    /// The least-squares solution on the basis `a`; None where singular or not finite.
    fn of(mut a: Mat<f64>, data: &Mat<f64>) -> Option<Self> {
        if a.nrows() <= a.ncols() {
            return None;
        }
        let scale = unit_columns(&mut a);
        let n = a.ncols();
        let qr = ThinQr::of(a);
        let mut residual_in_q = data.clone();
        qr.apply_transpose_q(&mut residual_in_q);
        let mut unknowns = residual_in_q.subrows(0, n).to_owned();
        solve_upper_triangular_in_place(qr.r().as_ref(), unknowns.as_mut(), Par::Seq);
        for (c, s) in scale.iter().enumerate() {
            unknowns.row_mut(c).iter_mut().for_each(|v| *v /= s);
        }
        residual_in_q.subrows_mut(0, n).fill(0.0);
        (unknowns.is_all_finite() && residual_in_q.is_all_finite()).then_some(Self {
            qr,
            unknowns,
            residual_in_q,
        })
    }

    fn cost(&self) -> f64 {
        self.residual_in_q.squared_norm_l2()
    }
}

/// The rank-one fit's poles, matched to their starts, and their standard deviations.
pub(crate) struct RankOneFit {
    pub poles: Vec<Complex64>,
    /// As estimates of the fit ([`deviations`]), the noise's part; None where JᵀJ is
    /// singular.
    pub deviations: Option<Vec<PoleSd>>,
    /// How far each pole may lie beyond the noise's part ([`unmodelled_spreads`]), rad/s.
    pub spreads: Vec<f64>,
}

impl RankOneFit {
    /// The fit in the order of `starts` ([`matched_order`]).
    fn matched_to(self, starts: &[Complex64]) -> Self {
        let order = matched_order(starts, &self.poles);
        self.in_order(&order)
    }

    /// The poles `order` names (indices into this fit's), in that order, with their
    /// deviations.
    pub(crate) fn in_order(self, order: &[usize]) -> Self {
        Self {
            poles: order.iter().map(|&k| self.poles[k]).collect(),
            deviations: self
                .deviations
                .map(|sd| order.iter().map(|&k| sd[k]).collect()),
            spreads: order.iter().map(|&k| self.spreads[k]).collect(),
        }
    }
}

/// The rank-one joint fit (module docs) from `poles` on `samples`, at most `iterations`
/// Levenberg–Marquardt steps (`on_iteration(k, iterations)` as step k starts); the fitted
/// poles matched to their starts ([`matched_order`]: two close poles may trade places in the
/// fit), or None where the residue problem fails at the start.
pub(crate) fn rank_one_poles(
    samples: &StackedCurves,
    poles: &[Complex64],
    participation: Vec<Vec<Complex64>>,
    iterations: usize,
    on_iteration: &dyn Fn(usize, usize),
) -> Option<RankOneFit> {
    let params = Parameters {
        pivots: participation.iter().map(|l| pivot(l)).collect(),
        references: samples.references,
    };
    let participation: Vec<Vec<Complex64>> = participation
        .iter()
        .zip(&params.pivots)
        .map(|(l, &k)| l.iter().map(|v| v / l[k]).collect())
        .collect();
    let project = |u: &[f64]| {
        let (p, l) = params.unpack(u);
        Projected::of(samples.basis(&p, &l), &samples.data)
    };
    let mut u = params.pack(poles, &participation);
    let mut at = project(&u)?;
    let mut cost = at.cost();
    let mut lambda = 1e-3;
    // Projected::of has fewer unknowns than rows.
    let (rows, responses) = samples.data.shape();
    let dof = (responses * (rows - at.unknowns.nrows())).saturating_sub(u.len());
    let converged = converged_share(dof);
    // The Jacobian at `u`, kept for the deviations where the steps end there.
    let mut jacobian = None;
    'steps: for k in 0..iterations {
        on_iteration(k + 1, iterations);
        let here = ProjectedJacobian::at(samples, &params, &u, &at);
        let (jtj, jtr) = normal_equations(samples, &here, &at);
        jacobian = Some(here);
        let p = u.len();
        let mut improved = false;
        for _ in 0..8 {
            let step = marquardt_step(&jtj, |a| jtr[a], lambda);
            let promised: f64 = (0..p).map(|a| -jtr[a] * step[(a, 0)]).sum();
            if promised.is_finite() && promised <= converged * cost {
                break 'steps;
            }
            let trial: Vec<f64> = (0..p).map(|a| u[a] + step[(a, 0)]).collect();
            if let Some(next) = project(&trial) {
                let ct = next.cost();
                if ct < cost {
                    improved = (cost - ct) / cost > 1e-10;
                    (u, at, cost) = (trial, next, ct);
                    jacobian = None;
                    lambda = (lambda / 3.0).max(1e-12);
                    break;
                }
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    let jacobian = jacobian.unwrap_or_else(|| ProjectedJacobian::at(samples, &params, &u, &at));
    let mut residual = at.residual_in_q.clone();
    at.qr.apply_q(&mut residual);
    let variances = curve_variances(samples, &u, &at, &residual);
    let (deviations, spreads) = rayon::join(
        || deviations(samples, &params, &u, &at, &variances, &jacobian),
        || unmodelled_spreads(samples, &params, &u, &at, &residual),
    );
    let fit = RankOneFit {
        poles: params.unpack(&u).0,
        deviations,
        spreads,
    };
    Some(fit.matched_to(poles))
}

/// Each curve's residual variance per real row at `u` (the fit's end, `at` its residue
/// problem, `residual` its residual in the curves' coordinates), responses × references: its
/// sum of squares over its rows less its share of the unknowns and of the parameters.
fn curve_variances(
    samples: &StackedCurves,
    u: &[f64],
    at: &Projected,
    residual: &Mat<f64>,
) -> Mat<f64> {
    let (refs, responses) = (samples.references, samples.data.ncols());
    let rows = samples.data.nrows() / refs;
    let own = (at.unknowns.nrows() as f64 + u.len() as f64 / responses as f64) / refs as f64;
    let dof = (rows as f64 - own).max(1.0);
    Mat::from_fn(responses, refs, |o, j| {
        residual.col(o).subrows(j * rows, rows).squared_norm_l2() / dof
    })
}

/// The standard deviations of the poles at `u` (the fit's end, `at` its residue problem,
/// `jacobian` Kaufman's Jacobian there) as estimates of the fit: the sandwich covariance
/// (JᵀJ)⁻¹ (Jᵀ Σ J) (JᵀJ)⁻¹ ([`normal_equations`]), Σ each curve's residual variance `variances`
/// ([`curve_variances`]), carried to f and ζ as [`crate::lsfd::pole_deviations`] does. The
/// curves of one response share its unknowns but not their noise (a reference's curves may be
/// noisier), hence Σ curve by curve: the Gram matrix of E = P⊥ D_u split by reference
/// ([`ProjectedJacobian::grams_by_reference`]). As there, the noise's part of the error only
/// ([`unmodelled_spreads`] has the rest).
fn deviations(
    samples: &StackedCurves,
    params: &Parameters,
    u: &[f64],
    at: &Projected,
    variances: &Mat<f64>,
    jacobian: &ProjectedJacobian,
) -> Option<Vec<PoleSd>> {
    let grams = jacobian.grams_by_reference(samples, at);
    let unknowns = ModeUnknowns {
        at,
        mode_of: &jacobian.mode_of,
    };
    let jtj = unknowns.assembled(&grams, |_, _| 1.0);
    let meat = unknowns.assembled(&grams, |o, j| variances[(o, j)]);
    let cov = sandwich(&jtj, &meat)?;
    let n = params.pivots.len();
    let poles = to_poles(&u[..2 * n]);
    Some(
        (0..n)
            .map(|k| {
                let (a, b) = (2 * k, 2 * k + 1);
                pole_sd(poles[k], [cov[(a, a)], cov[(a, b)], cov[(b, b)]])
            })
            .collect(),
    )
}

/// Each pole's spread beyond the noise at `u` ([`unmodelled_spread`]), rad/s, `residual` the
/// fit's residual at `at` in the curves' coordinates.
fn unmodelled_spreads(
    samples: &StackedCurves,
    params: &Parameters,
    u: &[f64],
    at: &Projected,
    residual: &Mat<f64>,
) -> Vec<f64> {
    use rayon::prelude::*;
    let (poles, participation) = params.unpack(u);
    poles
        .par_iter()
        .zip(&participation)
        .enumerate()
        .map(|(index, (&pole, l))| {
            let mode = ResidualMode { index, pole, l };
            unmodelled_spread(samples, &mode, at, residual)
        })
        .collect()
}

/// One mode of the fit, as [`unmodelled_spread`] takes it: its index in the basis, its pole
/// and participation factors.
struct ResidualMode<'a> {
    index: usize,
    pole: Complex64,
    l: &'a [Complex64],
}

/// How far the pole of `mode` may lie from the truth beyond the noise's part, δ (rad/s): the
/// second-order term at the pole that the fit's residual at `at` holds
/// ([`crate::residual_spread`]), one complex coefficient per curve (per reference of each
/// response), the residues' energy Σ|ψ_o L_j|², at most the pole's half-power half-width.
/// `residual` is the residual in the curves' coordinates.
fn unmodelled_spread(
    samples: &StackedCurves,
    mode: &ResidualMode<'_>,
    at: &Projected,
    residual: &Mat<f64>,
) -> f64 {
    let window = crate::residual_spread::window_of(mode.pole, &samples.omega);
    let nl = samples.omega.len();
    let window_lines: Vec<usize> = (0..nl).filter(|&k| window[k]).collect();
    let window_energy: Vec<f64> = (0..samples.data.ncols())
        .map(|o| {
            let col = residual.col(o);
            (0..samples.references)
                .flat_map(|j| window_lines.iter().map(move |&k| j * nl + k))
                .map(|i| col[2 * i].powi(2) + col[2 * i + 1].powi(2))
                .sum()
        })
        .collect();
    let mut g = samples.second_order_columns(mode.pole, &window);
    at.qr.apply_transpose_q(&mut g);
    g.subrows_mut(0, at.qr.r_rows()).fill(0.0);
    let u = &at.unknowns;
    let own: f64 = (0..samples.data.ncols())
        .map(|o| {
            let psi = Complex64::new(u[(2 * mode.index, o)], u[(2 * mode.index + 1, o)]);
            mode.l.iter().map(|lj| (psi * lj).norm_sqr()).sum::<f64>()
        })
        .sum();
    let term = SecondOrderTerm {
        columns: g.as_ref(),
        residual: at.residual_in_q.as_ref(),
        window_energy: &window_energy,
        window_rows: 2 * window_lines.len() * samples.references,
    };
    term.spread(own, -mode.pole.re)
}

/// The order of `fitted` in which each lies by its own start in `starts`: two poles trade
/// places wherever that shortens the sum of their distances to their starts, until no trade
/// does (the modes are a set; a pair that traded places in the fit has not left its columns).
fn matched_order(starts: &[Complex64], fitted: &[Complex64]) -> Vec<usize> {
    let n = fitted.len();
    let mut order: Vec<usize> = (0..n).collect();
    for _ in 0..n * n {
        let mut traded = false;
        for r in 0..n {
            for q in r + 1..n {
                let (a, b) = (fitted[order[r]], fitted[order[q]]);
                let kept = (a - starts[r]).norm() + (b - starts[q]).norm();
                let swapped = (b - starts[r]).norm() + (a - starts[q]).norm();
                if swapped < kept {
                    order.swap(r, q);
                    traded = true;
                }
            }
        }
        if !traded {
            break;
        }
    }
    order
}

/// The reference where `l` is largest.
fn pivot(l: &[Complex64]) -> usize {
    (0..l.len())
        .max_by(|&a, &b| l[a].norm().total_cmp(&l[b].norm()))
        .unwrap_or(0)
}

/// Kaufman's Jacobian −P⊥ D_u X at one point of the parameters, as the normal equations and
/// the deviations take it: the base columns of every parameter pair, P⊥ applied, in Q's
/// coordinates (pair q at columns 2q, 2q + 1, [`projected_derivatives`]); each parameter's
/// [`ColumnMap`] (E_u = P⊥ D_u = base · T_u: half the columns are projected, P⊥ commuting
/// with T); the Gram matrix of the E_u (2 × 2 block u, v at rows 2u, columns 2v); and each
/// parameter's mode.
struct ProjectedJacobian {
    base: Mat<f64>,
    maps: Vec<ColumnMap>,
    gram: Mat<f64>,
    mode_of: Vec<usize>,
}

impl ProjectedJacobian {
    /// The Jacobian at `u`, `at` its residue problem.
    fn at(samples: &StackedCurves, params: &Parameters, u: &[f64], at: &Projected) -> Self {
        let (base, maps, mode_of) = projected_derivatives(samples, params, u, at);
        let gram = expanded_gram(&(base.transpose() * &base), &maps);
        Self {
            base,
            maps,
            gram,
            mode_of,
        }
    }

    /// E_uᵀ r for every parameter u (rows 2u, 2u + 1) and column of `r` (in Q's coordinates).
    fn transposed_times(&self, r: &Mat<f64>) -> Mat<f64> {
        expanded_products(&(self.base.transpose() * r), &self.maps)
    }

    /// The Gram matrix of the E_u's rows of each reference in the curves' coordinates: with one
    /// reference [`Self::gram`] itself (Q is orthogonal), else the base columns taken back by Q
    /// ([`ThinQr::apply_q`]) and their rows split by reference.
    fn grams_by_reference(&self, samples: &StackedCurves, at: &Projected) -> Vec<Mat<f64>> {
        if samples.references == 1 {
            return vec![self.gram.clone()];
        }
        let mut base = self.base.clone();
        at.qr.apply_q(&mut base);
        let rows = samples.data.nrows() / samples.references;
        (0..samples.references)
            .map(|j| {
                let bj = base.subrows(j * rows, rows);
                expanded_gram(&(bj.transpose() * bj), &self.maps)
            })
            .collect()
    }
}

/// JᵀJ and Jᵀr of Kaufman's Jacobian −P⊥ D_u X (module docs) from `jacobian`, its E_u = P⊥ D_u,
/// without forming J: with x_uo the two unknowns of u's mode for response o,
/// (JᵀJ)_uv = Σ_o x_uoᵀ E_uᵀE_v x_vo and (Jᵀr)_u = −Σ_o x_uoᵀ E_uᵀ r_o.
fn normal_equations(
    samples: &StackedCurves,
    jacobian: &ProjectedJacobian,
    at: &Projected,
) -> (Mat<f64>, Vec<f64>) {
    let etr = jacobian.transposed_times(&at.residual_in_q);
    let unknowns = ModeUnknowns {
        at,
        mode_of: &jacobian.mode_of,
    };
    let jtj = unknowns.assembled(std::slice::from_ref(&jacobian.gram), |_, _| 1.0);
    let jtr = (0..jacobian.mode_of.len())
        .map(|a| {
            -(0..samples.data.ncols())
                .map(|o| {
                    let xa = unknowns.of(a, o);
                    xa[0] * etr[(2 * a, o)] + xa[1] * etr[(2 * a + 1, o)]
                })
                .sum::<f64>()
        })
        .collect();
    (jtj, jtr)
}

/// The base columns of every parameter pair at `u` ([`StackedCurves::pair_derivatives`]; the
/// pair of parameters 2q, 2q + 1 at columns 2q, 2q + 1), taken into Q's coordinates with their
/// first rows zeroed (P⊥ applied); each parameter's [`ColumnMap`] and mode.
fn projected_derivatives(
    samples: &StackedCurves,
    params: &Parameters,
    u: &[f64],
    at: &Projected,
) -> (Mat<f64>, Vec<ColumnMap>, Vec<usize>) {
    let (poles, participation) = params.unpack(u);
    let mut mode_of = vec![0; u.len()];
    let mut maps = vec![ColumnMap::TURNED; u.len()];
    let mut base = Mat::<f64>::zeros(samples.data.nrows(), u.len());
    let mut next_free = 2 * poles.len();
    for (r, &pole) in poles.iter().enumerate() {
        let free = params.free(r);
        for (m, d) in samples
            .pair_derivatives(pole, &participation[r], &free)
            .into_iter()
            .enumerate()
        {
            let first = if m == 0 {
                2 * r
            } else {
                next_free + 2 * (m - 1)
            };
            mode_of[first..first + 2].fill(r);
            maps[first] = ColumnMap::scaled(if m == 0 { pole.re } else { 1.0 });
            base.subcols_mut(first, 2).copy_from(&d);
        }
        next_free += 2 * free.len();
    }
    at.qr.apply_transpose_q(&mut base);
    base.subrows_mut(0, at.qr.r_rows()).fill(0.0);
    (base, maps, mode_of)
}

/// The unknowns x_uo that multiply each parameter u's derivative columns for response o: the
/// two of u's mode ([`normal_equations`]).
struct ModeUnknowns<'a> {
    at: &'a Projected,
    mode_of: &'a [usize],
}

impl ModeUnknowns<'_> {
    fn of(&self, param: usize, o: usize) -> [f64; 2] {
        let r = self.mode_of[param];
        [
            self.at.unknowns[(2 * r, o)],
            self.at.unknowns[(2 * r + 1, o)],
        ]
    }

    /// Σ_o Σ_g w(o, g) x_aoᵀ G_g,ab x_bo over the Gram matrices `grams` of the derivative
    /// columns (G_g,ab the 2 × 2 block of parameters a, b).
    fn assembled(&self, grams: &[Mat<f64>], weight: impl Fn(usize, usize) -> f64) -> Mat<f64> {
        let p = self.mode_of.len();
        let responses = self.at.unknowns.ncols();
        Mat::from_fn(p, p, |a, b| {
            let mut v = 0.0;
            for o in 0..responses {
                let (xa, xb) = (self.of(a, o), self.of(b, o));
                for (g, gram) in grams.iter().enumerate() {
                    let w = weight(o, g);
                    for c in 0..2 {
                        for d in 0..2 {
                            v += w * xa[c] * gram[(2 * a + c, 2 * b + d)] * xb[d];
                        }
                    }
                }
            }
            v
        })
    }
}

/// The poles of `top` (the diagram's highest order: its stable poles in the band, rad/s) that
/// are none of `poles`' own, taken as the context takes its roots ([`without_own`]: each of
/// `poles` takes the nearest within three half-power half-widths, or 1 % of |λ|). What is left
/// are modes the selection left out (a pick by frequency that took only some of the band's
/// modes, a column the selection did not keep).
pub(crate) fn left_out(top: &[Complex64], poles: &[Complex64]) -> Vec<Complex64> {
    without_own(top.to_vec(), poles, |q| q)
}

/// The rank-one fit with the modes it holds beside the poles it started from.
pub(crate) struct HeldFit {
    /// The poles, those of the starts first (index-aligned), then the held modes in the order
    /// they joined.
    pub fit: RankOneFit,
    /// Per held mode: the start it was found beside (a second mode under it, or that start's
    /// own pole where a held mode took its place, [`nearest_to_their_starts`]), None for a mode
    /// of the candidates.
    pub found_beside: Vec<Option<usize>>,
}

/// The rank-one fit from `poles` (module docs, [`rank_one_poles`]) with the modes the curves
/// need beside them: after each fit the mode [`next_needed`] names joins the fitted poles and
/// the fit runs again from there, until none is needed. The modes tried are those of
/// `candidates` and a second mode under each of the poles `splittable` names (indices into
/// `poles`), once each ([`split_candidates`]): one reference cannot tell two close damped modes
/// apart in the diagram (one pole over the pair), but their shapes over the responses differ,
/// and a missing mode under a pole leaves far more in the residual than noise. Each mode keeps
/// to its own start ([`RankOneFit::matched_to`]), and each given pole ends as the split mode
/// nearest its start where one is nearer ([`nearest_to_their_starts`]). None where the residue
/// problem fails at the start; where it fails once a mode has joined, the fit without it. Each
/// fit counts its own steps to `on_iteration` ([`rank_one_poles`]).
pub(crate) fn fitted_with_the_modes_needed(
    samples: &StackedCurves,
    poles: &[Complex64],
    candidates: &[Complex64],
    splittable: &[usize],
    participation_of: impl Fn(&[Complex64]) -> Option<Participation>,
    iterations: usize,
    on_iteration: &dyn Fn(usize, usize),
) -> Option<HeldFit> {
    let fit_from =
        |starts: &[Complex64], l| rank_one_poles(samples, starts, l, iterations, on_iteration);
    let mut fit = fit_from(poles, participation_of(poles)?)?;
    let mut origins = poles.to_vec();
    let mut found_beside = vec![];
    let mut rest: Vec<Trial> = candidates.iter().map(|&c| Trial::Candidate(c)).collect();
    rest.extend(splittable.iter().map(|&r| Trial::SecondUnder(r)));
    loop {
        // (entry of `rest`, start): a candidate tries one start, a split two.
        let tried: Vec<(usize, Complex64)> = rest
            .iter()
            .enumerate()
            .flat_map(|(i, trial)| match *trial {
                Trial::Candidate(c) => vec![(i, c)],
                Trial::SecondUnder(r) => split_candidates(fit.poles[r]).map(|c| (i, c)).to_vec(),
            })
            .collect();
        let tried_starts: Vec<Complex64> = tried.iter().map(|t| t.1).collect();
        let Some(k) = next_needed(samples, &fit.poles, &tried_starts, &participation_of) else {
            break;
        };
        let (i, joining) = tried[k];
        let trial = rest.remove(i);
        let starts: Vec<Complex64> = fit.poles.iter().copied().chain([joining]).collect();
        let next = participation_of(&starts).and_then(|l| fit_from(&starts, l));
        let Some(next) = next else { break };
        origins.push(joining);
        found_beside.push(match trial {
            Trial::Candidate(_) => None,
            Trial::SecondUnder(r) => Some(r),
        });
        // A pole the previous fit pulled towards the missing mode may trade places with it
        // now: each mode goes back to its own start.
        fit = next.matched_to(&origins);
    }
    let held = HeldFit { fit, found_beside };
    Some(nearest_to_their_starts(held, poles))
}

/// A mode tried beside the fitted poles: a candidate's start, or a second mode under the given
/// pole of that index ([`split_candidates`] of its current fit).
enum Trial {
    Candidate(Complex64),
    SecondUnder(usize),
}

/// `held` with each of the first `starts.len()` poles (the given ones) traded with a held mode
/// found beside one of them that lies nearer its start, until none does (the held mode's
/// origin then that start): the fit's modes are a set, and a split's own
/// start is one side of its pole taken at random, so which of the modes a given pole ends as
/// is the one nearest where it was given. Each trade shortens the given poles' summed distance
/// to their starts, so the trades end.
fn nearest_to_their_starts(held: HeldFit, starts: &[Complex64]) -> HeldFit {
    let HeldFit {
        fit,
        mut found_beside,
    } = held;
    let n = starts.len();
    let mut order: Vec<usize> = (0..fit.poles.len()).collect();
    let distance = |k: usize, r: usize| (fit.poles[k] - starts[r]).norm();
    let mut traded = true;
    while traded {
        traded = false;
        for r in 0..n {
            for q in n..order.len() {
                let split = found_beside[q - n].is_some();
                if split && distance(order[q], r) < distance(order[r], r) {
                    order.swap(r, q);
                    found_beside[q - n] = Some(r);
                    traded = true;
                }
            }
        }
    }
    HeldFit {
        fit: fit.in_order(&order),
        found_beside,
    }
}

/// The two starts of a second mode under `pole` (rad/s): its natural frequency moved by its
/// half-power half-width ζω_n either way, its damping kept.
fn split_candidates(pole: Complex64) -> [Complex64; 2] {
    let (f, zeta) = (pole_freq_hz(pole), pole_damping(pole));
    [
        pole_at(f * (1.0 - zeta), zeta),
        pole_at(f * (1.0 + zeta), zeta),
    ]
}

/// The one of `candidates` the curves need most beside the fitted `poles`: the one whose mode
/// lowers the projected sum of squares most (its participation factors, and theirs, from
/// `participation_of`, as [`start_participation`]), if that drop exceeds the 99 % point of χ²
/// with the mode's 2(responses + references) degrees of freedom times the residual variance
/// (the sum of squares over its degrees of freedom). At the fit's end the residual is the
/// noise where no mode is missing, and a pole no mode stands behind lowers it by no more than
/// noise does; a missing mode leaves far more. None at once without candidates.
fn next_needed(
    samples: &StackedCurves,
    poles: &[Complex64],
    candidates: &[Complex64],
    participation_of: impl Fn(&[Complex64]) -> Option<Participation>,
) -> Option<usize> {
    if candidates.is_empty() {
        return None;
    }
    let cost_of = |set: &[Complex64]| {
        let l = participation_of(set)?;
        Projected::of(samples.basis(set, &l), &samples.data).map(|p| p.cost())
    };
    let cost = cost_of(poles)?;
    let (responses, refs) = (samples.data.ncols(), samples.references);
    let unknowns = (2 * poles.len() + samples.blocks.ncols()) * responses + 2 * poles.len() * refs;
    let dof = (samples.data.nrows() * responses).saturating_sub(unknowns);
    let variance = cost / dof.max(1) as f64;
    let (k, drop) = candidates
        .iter()
        .enumerate()
        .filter_map(|(k, &c)| {
            let set: Vec<Complex64> = poles.iter().copied().chain([c]).collect();
            cost_of(&set).map(|with| (k, cost - with))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (drop > chi_square_99(2 * (responses + refs)) * variance).then_some(k)
}

/// Participation factors: per mode, one per reference.
pub(crate) type Participation = Vec<Vec<Complex64>>;

/// Each mode's participation factors from the free residues at `poles` on the curves
/// ([`participation`] of its responses × references residue matrix); None where the residue
/// problem fails. With one reference every mode's factor is 1 whatever its residues, and no
/// residue problem is solved (the rank-one fit's own fails where it is singular).
///
/// # Errors
/// [`EmaError::Invalid`] for a value that is not finite.
pub(crate) fn start_participation(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    references: usize,
    quantity: Quantity,
    lines: &[usize],
    poles: &[Complex64],
) -> Result<Option<Participation>, EmaError> {
    if references == 1 {
        return Ok(Some(vec![vec![Complex64::new(1.0, 0.0)]; poles.len()]));
    }
    let Some(x) = solve_by_blocks(freqs_hz, curves, quantity, lines, poles)? else {
        return Ok(None);
    };
    let responses = curves.len() / references;
    let vectors = (0..poles.len())
        .map(|r| {
            let residues: Vec<Complex64> = (0..curves.len())
                .map(|c| Complex64::new(x[(2 * r, c)], x[(2 * r + 1, c)]))
                .collect();
            participation(&residues, responses, references)
        })
        .collect();
    Ok(Some(vectors))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_frfs::{accelerance, pole};

    /// Modes (f Hz, ζ) of shapes `phi[r]` over six responses, the references at responses 0, 2
    /// and 4; accelerance, curves response-major (o·3 + j).
    fn multi_reference(
        freqs: &[f64],
        modes: &[(f64, f64)],
        phi: &[[f64; 6]],
    ) -> Vec<Vec<Complex64>> {
        (0..6)
            .flat_map(|o| [0, 2, 4].map(|j| accelerance(freqs, modes, |r| phi[r][o] * phi[r][j])))
            .collect()
    }

    const MODES: [(f64, f64); 3] = [(60.0, 0.08), (100.0, 0.08), (101.2, 0.08)];
    const SHAPES: [[f64; 6]; 3] = [
        [1.0, 0.8, 0.5, -0.3, -0.7, -1.0],
        [0.9, -0.4, 1.0, 0.6, -0.8, 0.3],
        [0.5, 1.0, -0.6, 0.9, 0.7, -0.4],
    ];

    fn samples(freqs: &[f64], curves: &[Vec<Complex64>]) -> StackedCurves {
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        StackedCurves::new(freqs, &refs, 3, Quantity::Accelerance, &lines, 200.0).unwrap()
    }

    #[test]
    fn a_close_damped_pair_is_fitted_exactly_from_a_biased_start() {
        let freqs: Vec<f64> = (0..=1800).map(|k| 20.0 + 0.1 * f64::from(k)).collect();
        let curves = multi_reference(&freqs, &MODES, &SHAPES);
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        // Each frequency 0.3 % high and each damping 10 % high: more than the pair's spacing
        // allows a free-residue start to sort out.
        let start: Vec<Complex64> = MODES
            .iter()
            .map(|&(f, z)| pole(1.003 * f, 1.1 * z))
            .collect();
        let l0 = start_participation(&freqs, &refs, 3, Quantity::Accelerance, &lines, &start)
            .unwrap()
            .unwrap();
        let fitted = rank_one_poles(&samples(&freqs, &curves), &start, l0, 60, &|_, _| {})
            .unwrap()
            .poles;
        for (p, &(f, z)) in fitted.iter().zip(&MODES) {
            let t = pole(f, z);
            assert!((p - t).norm() < 1e-6 * t.norm(), "{p} against {t}");
        }
    }

    /// The curves of [`multi_reference`] with complex white noise of `relative` times each
    /// curve's RMS in each part (seeded).
    fn noisy(curves: &[Vec<Complex64>], relative: f64, seed: u64) -> Vec<Vec<Complex64>> {
        let mut noise = crate::noise::tests::gaussian_sequence(seed);
        curves
            .iter()
            .map(|c| {
                let rms = (c.iter().map(|v| v.norm_sqr()).sum::<f64>() / c.len() as f64).sqrt();
                c.iter().map(|v| v + relative * rms * noise()).collect()
            })
            .collect()
    }

    /// The start's participation factors on every line of `curves`.
    fn start_of(freqs: &[f64], curves: &[Vec<Complex64>], poles: &[Complex64]) -> Participation {
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        start_participation(freqs, &refs, 3, Quantity::Accelerance, &lines, poles)
            .unwrap()
            .unwrap()
    }

    #[test]
    fn each_pole_takes_its_own_of_the_top_order_and_the_rest_is_left_out() {
        let top = [
            pole(60.2, 0.08),
            pole(99.7, 0.08),
            pole(101.5, 0.08),
            pole(150.0, 0.3),
        ];
        let picked = [pole(60.0, 0.08), pole(101.1, 0.08)];
        assert_eq!(
            left_out(&top, &picked),
            vec![pole(150.0, 0.3), pole(99.7, 0.08)]
        );
    }

    /// Of a mode the pick left out (100 Hz) and a pole no mode stands behind (130 Hz), only
    /// the first joins the fit, and with it the picked close neighbour is fitted as if picked
    /// with it. At 1 % noise the spurious pole lowers the sum of squares by about its degrees
    /// of freedom times the variance, the missing mode by orders more.
    #[test]
    fn only_a_mode_the_curves_hold_joins_the_picked_ones() {
        let freqs: Vec<f64> = (0..=1800).map(|k| 20.0 + 0.1 * f64::from(k)).collect();
        let curves = noisy(&multi_reference(&freqs, &MODES, &SHAPES), 0.01, 7);
        let picked = [pole(60.0, 0.08), pole(101.2, 0.08)];
        let candidates = [pole(130.0, 0.05), pole(100.3, 0.085)];
        let s = samples(&freqs, &curves);
        let fit = fitted_with_the_modes_needed(
            &s,
            &picked,
            &candidates,
            &[],
            |set| Some(start_of(&freqs, &curves, set)),
            60,
            &|_, _| {},
        )
        .unwrap();
        assert_eq!(fit.found_beside, [None]);
        let fit = fit.fit;
        assert_eq!(fit.poles.len(), 3);
        let all = fitted_with_the_modes_needed(
            &s,
            &[picked[0], candidates[1], picked[1]],
            &[],
            &[],
            |set| Some(start_of(&freqs, &curves, set)),
            60,
            &|_, _| {},
        )
        .unwrap()
        .fit;
        for (p, q) in fit
            .poles
            .iter()
            .zip([all.poles[0], all.poles[2], all.poles[1]])
        {
            assert!((p - q).norm() < 1e-6 * q.norm(), "{p} against {q}");
        }
    }

    /// A given pole whose fit ended at another mode (160 Hz) while the mode split from beside it
    /// lies by its start takes that mode's place, the held one now found beside it; a mode of
    /// the candidates (from the diagram, its own start) trades with none.
    #[test]
    fn a_given_pole_takes_the_split_mode_nearest_its_start() {
        let starts = [pole(60.0, 0.08), pole(103.0, 0.03)];
        let fit = RankOneFit {
            poles: vec![
                pole(60.1, 0.08),
                pole(160.0, 0.08),
                pole(102.9, 0.03),
                pole(102.5, 0.08),
            ],
            deviations: None,
            spreads: vec![0.0; 4],
        };
        let held = HeldFit {
            fit,
            found_beside: vec![None, Some(0)],
        };
        let traded = nearest_to_their_starts(held, &starts);
        assert_eq!(
            traded.fit.poles,
            [
                pole(60.1, 0.08),
                pole(102.5, 0.08),
                pole(102.9, 0.03),
                pole(160.0, 0.08)
            ]
        );
        assert_eq!(traded.found_beside, [None, Some(1)]);
    }

    /// Six responses to the one reference at response 0 (curve o is response o), modes of
    /// `MODES` with `SHAPES`.
    fn one_reference(freqs: &[f64], modes: &[(f64, f64)]) -> Vec<Vec<Complex64>> {
        (0..6)
            .map(|o| accelerance(freqs, modes, |r| SHAPES[r][o] * SHAPES[r][0]))
            .collect()
    }

    /// With one reference the participation factor that a mode's free residues give is 1,
    /// whatever the residues (here a noisy weak neighbour's), as `start_participation` takes
    /// it without solving them.
    #[test]
    fn one_reference_participation_is_one_whatever_the_residues() {
        let freqs: Vec<f64> = (0..=800).map(|k| 40.0 + 0.1 * k as f64).collect();
        let curves = weak_neighbour(&freqs, 1);
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        let poles: Vec<Complex64> = WEAK_NEIGHBOUR.iter().map(|&(f, z)| pole(f, z)).collect();
        let x = solve_by_blocks(&freqs, &refs, Quantity::Accelerance, &lines, &poles)
            .unwrap()
            .unwrap();
        for r in 0..poles.len() {
            let residues: Vec<Complex64> = (0..refs.len())
                .map(|c| Complex64::new(x[(2 * r, c)], x[(2 * r + 1, c)]))
                .collect();
            assert_eq!(participation(&residues, refs.len(), 1), [Complex64::ONE]);
        }
        let shortcut = start_participation(&freqs, &refs, 1, Quantity::Accelerance, &lines, &poles);
        assert_eq!(shortcut.unwrap().unwrap(), vec![vec![Complex64::ONE]; 3]);
    }

    /// The one-reference fit of `curves` from `picked`, no candidates.
    fn one_reference_fit(
        freqs: &[f64],
        curves: &[Vec<Complex64>],
        picked: &[Complex64],
    ) -> HeldFit {
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        let s = StackedCurves::new(freqs, &refs, 1, Quantity::Accelerance, &lines, 200.0).unwrap();
        let l = |set: &[Complex64]| Some(vec![vec![Complex64::ONE]; set.len()]);
        let all: Vec<usize> = (0..picked.len()).collect();
        fitted_with_the_modes_needed(&s, picked, &[], &all, l, 60, &|_, _| {}).unwrap()
    }

    /// The curves of one reference over 60, 100 and 103 Hz (ζ 8 %), the 103 Hz mode weak (0.3
    /// of its shape), its shape `SHAPES[shape]`, 1 % noise.
    fn weak_neighbour(freqs: &[f64], shape: usize) -> Vec<Vec<Complex64>> {
        let exact: Vec<Vec<Complex64>> = (0..6)
            .map(|o| {
                crate::test_frfs::accelerance(freqs, &WEAK_NEIGHBOUR, |r| {
                    let of = if r == 2 {
                        0.3 * SHAPES[shape][o]
                    } else {
                        SHAPES[r][o]
                    };
                    of * SHAPES[r][0]
                })
            })
            .collect();
        noisy(&exact, 0.01, 11)
    }

    /// The one-reference samples of `curves` on every line of `freqs`.
    fn one_reference_samples(freqs: &[f64], curves: &[Vec<Complex64>]) -> StackedCurves {
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        StackedCurves::new(freqs, &refs, 1, Quantity::Accelerance, &lines, 200.0).unwrap()
    }

    const WEAK_NEIGHBOUR: [(f64, f64); 3] = [(60.0, 0.08), (100.0, 0.08), (103.0, 0.08)];

    /// A pole fitted alone over a mode and a weak neighbour 3 % above it (one reference, the
    /// neighbour not in the model) lies off the mode by ten times its noise sd, and the
    /// residual's second-order term says so: the spread reaches the bias and stays within the
    /// pole's half-power half-width. With the neighbour in the model no pole takes a spread
    /// beyond its noise sd. A neighbour of the pole's own shape leaves no second shape: its
    /// bias goes unseen (module `residual_spread`, "What it cannot see").
    #[test]
    fn a_pole_over_a_weak_neighbour_is_widened_by_the_residual() {
        let freqs: Vec<f64> = (0..=1800).map(|k| 20.0 + 0.1 * f64::from(k)).collect();
        let curves = weak_neighbour(&freqs, 2);
        let s = one_reference_samples(&freqs, &curves);
        let starts = [pole(60.0, 0.08), pole(100.6, 0.08)];
        let one = vec![vec![Complex64::ONE]; 2];
        let alone = rank_one_poles(&s, &starts, one, 60, &|_, _| {}).unwrap();
        let fitted = alone.poles[1];
        let bias = (fitted - pole(100.0, 0.08)).norm();
        let noise_sd = 2.0 * PI * alone.deviations.as_ref().unwrap()[1].freq_hz;
        eprintln!(
            "alone: bias {bias} rad/s, noise sd {noise_sd}, spreads {:?}",
            alone.spreads
        );
        assert!(noise_sd < bias / 5.0, "noise sd {noise_sd}, bias {bias}");
        assert!(
            alone.spreads[1] >= bias,
            "{:?} against {bias}",
            alone.spreads
        );
        assert!(alone.spreads[1] <= -fitted.re, "{:?}", alone.spreads);
        let all: Vec<Complex64> = WEAK_NEIGHBOUR.iter().map(|&(f, z)| pole(f, z)).collect();
        let three = vec![vec![Complex64::ONE]; 3];
        let held = rank_one_poles(&s, &all, three, 60, &|_, _| {}).unwrap();
        let sd = held.deviations.unwrap();
        eprintln!("held: spreads {:?}, sd {sd:?}", held.spreads);
        for (k, spread) in held.spreads.iter().enumerate() {
            let noise_sd = 2.0 * PI * sd[k].freq_hz;
            assert!(*spread <= noise_sd, "{k}: {spread} against {noise_sd}");
        }
        let same_shape = one_reference_samples(&freqs, &weak_neighbour(&freqs, 1));
        let one = vec![vec![Complex64::ONE]; 2];
        let unseen = rank_one_poles(&same_shape, &starts, one, 60, &|_, _| {}).unwrap();
        let bias = (unseen.poles[1] - pole(100.0, 0.08)).norm();
        eprintln!(
            "same shape: bias {bias} rad/s, spreads {:?}",
            unseen.spreads
        );
        assert!(
            bias > 1.0 && unseen.spreads[1] == 0.0,
            "{bias}, {:?}",
            unseen.spreads
        );
    }

    /// With one reference a pole picked over the damped pair 100 / 101.2 Hz (1.2 % apart, a
    /// seventh of a half-power bandwidth) holds a second mode under it, and the two fitted poles
    /// are the pair's, each within four of its standard deviations (1 % noise); an isolated
    /// mode's pole holds none.
    #[test]
    fn one_reference_holds_the_second_mode_under_a_pole_over_a_pair() {
        let freqs: Vec<f64> = (0..=1800).map(|k| 20.0 + 0.1 * f64::from(k)).collect();
        let curves = noisy(&one_reference(&freqs, &MODES), 0.01, 11);
        let held = one_reference_fit(&freqs, &curves, &[pole(60.0, 0.08), pole(100.6, 0.06)]);
        assert_eq!(held.found_beside, [Some(1)]);
        let sd = held.fit.deviations.unwrap();
        for (&(f, z), truth_at) in MODES.iter().zip([0, 1, 2]) {
            let k = (0..3)
                .min_by(|&a, &b| {
                    let d = |q: usize| (pole_freq_hz(held.fit.poles[q]) - f).abs();
                    d(a).total_cmp(&d(b))
                })
                .unwrap();
            let p = held.fit.poles[k];
            assert!(
                (pole_freq_hz(p) - f).abs() < 4.0 * sd[k].freq_hz
                    && (pole_damping(p) - z).abs() < 4.0 * sd[k].damping_ratio,
                "mode {truth_at}: {} Hz, {} against {f} Hz, {z} (sd {:?})",
                pole_freq_hz(p),
                pole_damping(p),
                sd[k]
            );
        }
        let alone = noisy(&one_reference(&freqs, &MODES[..2]), 0.01, 11);
        let held = one_reference_fit(&freqs, &alone, &[pole(60.0, 0.08), pole(100.0, 0.08)]);
        assert!(held.found_beside.is_empty(), "{:?}", held.fit.poles);
    }

    /// Over 40 noise seeds (1 % of each curve's RMS) the scatter of the fitted close pair's f
    /// and ζ matches the mean predicted standard deviation: their ratio's sampling error over 40
    /// seeds is about 11 %, and 0.7–1.4 is three of it.
    #[test]
    fn the_deviations_match_the_scatter_over_noise_seeds() {
        let freqs: Vec<f64> = (0..=1800).map(|k| 20.0 + 0.1 * f64::from(k)).collect();
        let clean = multi_reference(&freqs, &MODES, &SHAPES);
        let truth: Vec<Complex64> = MODES.iter().map(|&(f, z)| pole(f, z)).collect();
        let seeds = 40;
        let (mut squared, mut predicted) = ([[0.0; 2]; 3], [[0.0; 2]; 3]);
        for seed in 0..seeds {
            let curves = noisy(&clean, 0.01, 100 + seed);
            let l0 = start_of(&freqs, &curves, &truth);
            let fit =
                rank_one_poles(&samples(&freqs, &curves), &truth, l0, 60, &|_, _| {}).unwrap();
            let sd = fit.deviations.unwrap();
            for r in 0..3 {
                let (f, z) = (
                    fit.poles[r].norm() / (2.0 * PI),
                    -fit.poles[r].re / fit.poles[r].norm(),
                );
                squared[r][0] += (f - MODES[r].0).powi(2) / seeds as f64;
                squared[r][1] += (z - MODES[r].1).powi(2) / seeds as f64;
                predicted[r][0] += sd[r].freq_hz.powi(2) / seeds as f64;
                predicted[r][1] += sd[r].damping_ratio.powi(2) / seeds as f64;
            }
        }
        for r in 0..3 {
            for q in 0..2 {
                let ratio = (squared[r][q] / predicted[r][q]).sqrt();
                assert!(
                    (0.7..1.4).contains(&ratio),
                    "mode {r}, quantity {q}: {ratio}"
                );
            }
        }
    }

    #[test]
    fn poles_that_traded_places_are_matched_to_their_starts() {
        let starts = [pole(174.9, 0.087), pole(180.5, 0.078), pole(60.0, 0.02)];
        let fitted = [pole(180.4, 0.079), pole(175.8, 0.082), pole(60.1, 0.02)];
        assert_eq!(matched_order(&starts, &fitted), vec![1, 0, 2]);
    }

    #[test]
    fn the_gradient_is_that_of_the_projected_sum_of_squares() {
        let freqs: Vec<f64> = (0..=600).map(|k| 40.0 + 0.2 * f64::from(k)).collect();
        let curves = multi_reference(&freqs, &MODES, &SHAPES);
        let s = samples(&freqs, &curves);
        let poles: Vec<Complex64> = MODES
            .iter()
            .map(|&(f, z)| pole(1.002 * f, 1.05 * z))
            .collect();
        let l: Vec<Vec<Complex64>> = (0..3)
            .map(|r| {
                vec![
                    Complex64::new(1.0, 0.0),
                    Complex64::new(0.7, 0.1 * r as f64),
                    Complex64::new(-0.4, 0.2),
                ]
            })
            .collect();
        let params = Parameters {
            pivots: vec![0; 3],
            references: 3,
        };
        let u = params.pack(&poles, &l);
        let cost = |u: &[f64]| {
            let (p, l) = params.unpack(u);
            Projected::of(s.basis(&p, &l), &s.data).unwrap().cost()
        };
        let at = Projected::of(s.basis(&poles, &l), &s.data).unwrap();
        let jacobian = ProjectedJacobian::at(&s, &params, &u, &at);
        let (_, jtr) = normal_equations(&s, &jacobian, &at);
        for a in 0..u.len() {
            let h = 1e-6 * u[a].abs().max(1.0);
            let (mut up, mut down) = (u.clone(), u.clone());
            up[a] += h;
            down[a] -= h;
            // d(½‖r‖²)/du = Jᵀr.
            let numeric = 0.25 * (cost(&up) - cost(&down)) / h;
            let scale = jtr.iter().map(|g| g.abs()).fold(0.0, f64::max);
            assert!(
                (numeric - jtr[a]).abs() < 1e-6 * scale,
                "parameter {a}: {numeric} against {}",
                jtr[a]
            );
        }
    }
}
