//! The joint pole fit with rank-one residues: with several references, each mode's residues
//! over responses o and references j are ψ_o L_j (one shape, one participation vector), not
//! one free residue per curve.
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

use crate::band::pseudo_modes_above;
use crate::error::EmaError;
use crate::pole_fit::{marquardt_step, pole_parameters, to_poles};
use crate::projection::{LineBasis, LineSamples, solve_by_blocks, unit_columns};
use crate::shapes::participation;
use crate::thin_qr::ThinQr;
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Mat, Par};
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The relative reduction of the sum of squares the steps stop below (as
/// [`crate::pole_fit`]'s).
const CONVERGED: f64 = 1e-12;

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
        for (k, &w) in self.omega.iter().enumerate() {
            let line = LineBasis::new(poles, self.quantity, w);
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

    /// ∂(mode columns)/∂u for each parameter u of mode `r` (ln σ, ω_d, then re and im of L_rj
    /// for every free reference j), each as the complex values at every row pair, pairs of
    /// columns (module docs): the pole's with e = L_rj c and the squared fractions (c = ∂λ/∂u),
    /// L's with e = 1 or i on its own reference's rows.
    fn mode_derivatives(&self, pole: Complex64, l: &[Complex64], free: &[usize]) -> Vec<Mat<f64>> {
        let nl = self.omega.len();
        let rows = self.data.nrows();
        let dpole = [Complex64::new(pole.re, 0.0), Complex64::i()];
        let mut out: Vec<Mat<f64>> = (0..2 + 2 * free.len())
            .map(|_| Mat::zeros(rows, 2))
            .collect();
        for (k, &w) in self.omega.iter().enumerate() {
            let line = LineBasis::new(&[pole], self.quantity, w);
            let (a1, a2) = line.fractions[0];
            for j in 0..self.references {
                let row = j * nl + k;
                for (m, c) in dpole.iter().enumerate() {
                    let e = l[j] * c;
                    put_pair(
                        &mut out[m],
                        row,
                        0,
                        line.factor,
                        e * a1 * a1,
                        e.conj() * a2 * a2,
                    );
                }
                if let Some(i) = free.iter().position(|&f| f == j) {
                    for (m, e) in [Complex64::new(1.0, 0.0), Complex64::i()]
                        .iter()
                        .enumerate()
                    {
                        let d = &mut out[2 + 2 * i + m];
                        put_pair(d, row, 0, line.factor, e * a1, e.conj() * a2);
                    }
                }
            }
        }
        out
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
        let qr = ThinQr::new(&a);
        let n = a.ncols();
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

/// The rank-one joint fit (module docs) from `poles` on `samples`, at most `iterations`
/// Levenberg–Marquardt steps; the fitted poles matched to their starts ([`matched_to`]: two
/// close poles may trade places in the fit), or None where the residue problem fails at the
/// start.
pub(crate) fn rank_one_poles(
    samples: &StackedCurves,
    poles: &[Complex64],
    participation: Vec<Vec<Complex64>>,
    iterations: usize,
) -> Option<Vec<Complex64>> {
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
    for _ in 0..iterations {
        let (jtj, jtr) = normal_equations(samples, &params, &u, &at);
        let p = u.len();
        let mut improved = false;
        for _ in 0..8 {
            let step = marquardt_step(&jtj, |a| jtr[a], lambda);
            let promised: f64 = (0..p).map(|a| -jtr[a] * step[(a, 0)]).sum();
            if promised.is_finite() && promised <= CONVERGED * cost {
                return Some(params.unpack(&u).0);
            }
            let trial: Vec<f64> = (0..p).map(|a| u[a] + step[(a, 0)]).collect();
            if let Some(next) = project(&trial) {
                let ct = next.cost();
                if ct < cost {
                    improved = (cost - ct) / cost > 1e-10;
                    (u, at, cost) = (trial, next, ct);
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
    Some(matched_to(poles, params.unpack(&u).0))
}

/// `fitted` reordered so that each lies by its own start in `starts`: two poles trade places
/// wherever that shortens the sum of their distances to their starts, until no trade does
/// (the modes are a set; a pair that traded places in the fit has not left its columns).
fn matched_to(starts: &[Complex64], mut fitted: Vec<Complex64>) -> Vec<Complex64> {
    let n = fitted.len();
    for _ in 0..n * n {
        let mut traded = false;
        for r in 0..n {
            for q in r + 1..n {
                let kept = (fitted[r] - starts[r]).norm() + (fitted[q] - starts[q]).norm();
                let swapped = (fitted[q] - starts[r]).norm() + (fitted[r] - starts[q]).norm();
                if swapped < kept {
                    fitted.swap(r, q);
                    traded = true;
                }
            }
        }
        if !traded {
            break;
        }
    }
    fitted
}

/// The reference where `l` is largest.
fn pivot(l: &[Complex64]) -> usize {
    (0..l.len())
        .max_by(|&a, &b| l[a].norm().total_cmp(&l[b].norm()))
        .unwrap_or(0)
}

/// JᵀJ and Jᵀr of Kaufman's Jacobian −P⊥ D_u X at `u` (module docs), without forming it: with
/// E_u = P⊥ D_u (its two columns, taken into Q's coordinates with their first rows zeroed) and
/// x_uo the two unknowns of u's mode for response o, (JᵀJ)_uv = Σ_o x_uoᵀ E_uᵀE_v x_vo and
/// (Jᵀr)_u = −Σ_o x_uoᵀ E_uᵀ r_o.
fn normal_equations(
    samples: &StackedCurves,
    params: &Parameters,
    u: &[f64],
    at: &Projected,
) -> (Mat<f64>, Vec<f64>) {
    let (poles, participation) = params.unpack(u);
    let responses = samples.data.ncols();
    // Each parameter's mode and its two derivative columns at 2·(the parameter's index).
    let mut mode_of = vec![0; u.len()];
    let mut e = Mat::<f64>::zeros(samples.data.nrows(), 2 * u.len());
    let mut next_free = 2 * poles.len();
    for (r, &pole) in poles.iter().enumerate() {
        let free = params.free(r);
        for (m, d) in samples
            .mode_derivatives(pole, &participation[r], &free)
            .into_iter()
            .enumerate()
        {
            let param = if m < 2 { 2 * r + m } else { next_free + m - 2 };
            mode_of[param] = r;
            e.subcols_mut(2 * param, 2).copy_from(&d);
        }
        next_free += 2 * free.len();
    }
    at.qr.apply_transpose_q(&mut e);
    e.subrows_mut(0, at.qr.r_rows()).fill(0.0);
    let gram = e.transpose() * &e;
    let etr = e.transpose() * &at.residual_in_q;
    let x = |param: usize, o: usize| {
        let r = mode_of[param];
        [at.unknowns[(2 * r, o)], at.unknowns[(2 * r + 1, o)]]
    };
    let p = u.len();
    let jtj = Mat::from_fn(p, p, |a, b| {
        (0..responses)
            .map(|o| {
                let (xa, xb) = (x(a, o), x(b, o));
                let mut v = 0.0;
                for c in 0..2 {
                    for d in 0..2 {
                        v += xa[c] * gram[(2 * a + c, 2 * b + d)] * xb[d];
                    }
                }
                v
            })
            .sum()
    });
    let jtr = (0..p)
        .map(|a| {
            -(0..responses)
                .map(|o| {
                    let xa = x(a, o);
                    xa[0] * etr[(2 * a, o)] + xa[1] * etr[(2 * a + 1, o)]
                })
                .sum::<f64>()
        })
        .collect();
    (jtj, jtr)
}

/// Each mode's participation factors from the free residues at `poles` on the curves
/// ([`participation`] of its responses × references residue matrix); None where the residue
/// problem fails.
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
) -> Result<Option<Vec<Vec<Complex64>>>, EmaError> {
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
        let fitted = rank_one_poles(&samples(&freqs, &curves), &start, l0, 60).unwrap();
        for (p, &(f, z)) in fitted.iter().zip(&MODES) {
            let t = pole(f, z);
            assert!((p - t).norm() < 1e-6 * t.norm(), "{p} against {t}");
        }
    }

    #[test]
    fn poles_that_traded_places_are_matched_to_their_starts() {
        let starts = [pole(174.9, 0.087), pole(180.5, 0.078), pole(60.0, 0.02)];
        let fitted = vec![pole(180.4, 0.079), pole(175.8, 0.082), pole(60.1, 0.02)];
        let matched = matched_to(&starts, fitted.clone());
        assert_eq!(matched, vec![fitted[1], fitted[0], fitted[2]]);
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
        let (_, jtr) = normal_equations(&s, &params, &u, &at);
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
