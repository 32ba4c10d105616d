//! Is there a second shape under a pole? The test that tells a pole standing for two close
//! modes from one mode.
//!
//! **Why.** With one reference, two modes closer than their half-power bandwidth (a pair
//! 1.3 % apart at ζ = 8 %) give one pole in the diagram; its MPC stays high (both modes'
//! terms are nearly in phase over the band) and nothing else in a mode's evidence says it is
//! two. But the curves still hold both shapes: near the pole λ, the pair
//! φ_a/(s − λ_a) + φ_b/(s − λ_b) is, to first order in Δλ = λ_a − λ_b,
//!
//!   (φ_a + φ_b)/(s − λ) + (φ_a − φ_b)(Δλ/2)/(s − λ)²,
//!
//! with λ the pair's centre: a term in 1/(s − λ)² whose coefficients over the curves are not
//! parallel to the pole's residues. One mode with a pole off by δλ also leaves a
//! 1/(s − λ)² term, δλ times its residues: parallel to them. Any distortion common to every
//! curve (one mode's shape times a function of frequency: leakage, a stiffening part) keeps
//! every coefficient parallel too.
//!
//! **The test.** Within ±2 half-power half-widths of the pole (at least
//! [`crate::local_residues::MIN_HALF_WINDOW_LINES`] lines: the window of the shapes' local
//! fit), every curve is fitted by least squares with 1/(s − λ), 1/(s − λ*) and 1/(s − λ)²
//! for the pole and for each pole whose half-power band reaches the window, and a quadratic
//! in frequency for the modes outside it. With every curve weighted by its noise σ̂
//! (the `noise` module), c the coefficients of 1/(s − λ)² over the curves and ψ those of
//! 1/(s − λ), the part c⊥ of c orthogonal to ψ is noise alone when there is one mode:
//!
//!   Z = |c⊥|² / (2 v (n − 1)),   v = [(AᴴA)⁻¹]₂₂,
//!
//! is a χ² of 2(n − 1) degrees of freedom over its own (mean 1, n curves). Its size beside
//! the pole's own term is
//!
//!   ρ = |c⊥| / (|ψ| ζω_n),
//!
//! the second shape's peak over the pole's peak (1/(s − λ)² peaks at 1/(ζω_n)², 1/(s − λ) at
//! 1/(ζω_n)).
//!
//! **Where it is valid.** Z is a noise test: it means something only where the modal model
//! holds to the noise. On noise-free curves σ̂ is the curves' own curvature, so it is floored
//! at [`NOISE_FLOOR`] of each curve's RMS (the model's own precision); on measured curves
//! whose poles differ from curve to curve (a roving sensor's mass, a part that changes between
//! runs) every mode's Z is large. The verdict ([`crate::quality`]) therefore trusts Z only
//! where the other modes of the same data show it at chance level.
//!
//! What it gives on the damped plates, the measured dam and beam, and the demo roof:
//! docs/ema.md, method step 7.

use crate::band::line_spacing;
use crate::local_residues::PoleWindow;
use crate::lscf::pole_damping;
use crate::noise::CurveNoise;
use crate::quality::{Measured, SecondShape};
use faer::linalg::solvers::SolveLstsq;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, Par, c64};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Each curve's σ̂ is at least this fraction of its RMS over the band (module docs).
pub const NOISE_FLOOR: f64 = 1e-3;

/// [`SecondShape`] of every pole of `poles` on `data`, each curve weighted by its noise level
/// `noise` (estimated over `data.lines`); None for a pole with fewer than two curves, too few
/// lines in its window or a singular local fit.
pub fn second_shapes(
    poles: &[Complex64],
    data: Measured,
    noise: &CurveNoise,
) -> Vec<Option<SecondShape>> {
    if data.curves.len() < 2 {
        return vec![None; poles.len()];
    }
    let sigmas: Vec<f64> = data
        .curves
        .iter()
        .enumerate()
        .map(|(o, c)| floored_noise(c, data.lines, noise.variance(o)))
        .collect();
    let spacing = line_spacing(data.freqs_hz, data.lines);
    (0..poles.len())
        .map(|k| second_shape(poles, k, data, &sigmas, spacing))
        .collect()
}

/// σ̂ of `curve` over `lines` from its estimate σ̂² `variance` there, at least [`NOISE_FLOOR`]
/// of its RMS there; NaN without an estimate.
fn floored_noise(curve: &[Complex64], lines: &[usize], variance: Option<f64>) -> f64 {
    let mean_square =
        lines.iter().map(|&k| curve[k].norm_sqr()).sum::<f64>() / lines.len().max(1) as f64;
    // σ̂² is per part (real, imaginary): the floor's |H|² splits over two.
    let floor = NOISE_FLOOR * NOISE_FLOOR * mean_square / 2.0;
    variance.map_or(f64::NAN, |v| v.max(floor).sqrt())
}

/// The local basis of pole `k` on `window`'s lines (rows, at `freqs`): the pole's three
/// columns first, then each near pole's three, then the quadratic.
fn local_basis(poles: &[Complex64], k: usize, freqs: &[f64], window: &PoleWindow) -> Mat<c64> {
    let near = window.poles_reaching(poles, k);
    let columns = 3 * (1 + near.len()) + 3;
    Mat::from_fn(freqs.len(), columns, |i, c| {
        let s = Complex64::new(0.0, 2.0 * PI * freqs[i]);
        let value = if c < columns - 3 {
            let pole = if c < 3 { poles[k] } else { near[c / 3 - 1] };
            match c % 3 {
                0 => 1.0 / (s - pole),
                1 => 1.0 / (s - pole.conj()),
                _ => 1.0 / ((s - pole) * (s - pole)),
            }
        } else {
            let x = (freqs[i] - window.center_hz) / window.half_hz;
            Complex64::new(x.powi((c + 3 - columns) as i32), 0.0)
        };
        c64::new(value.re, value.im)
    })
}

/// [`SecondShape`] of pole `k` (module docs); `sigmas` each curve's floored σ̂, `spacing` the
/// lines' spacing, Hz.
fn second_shape(
    poles: &[Complex64],
    k: usize,
    data: Measured,
    sigmas: &[f64],
    spacing: f64,
) -> Option<SecondShape> {
    let window = PoleWindow::of(poles[k], data, spacing)?;
    let (wk, zk) = (poles[k].norm(), pole_damping(poles[k]));
    let freqs: Vec<f64> = window.lines.iter().map(|&i| data.freqs_hz[i]).collect();
    let mut a = local_basis(poles, k, &freqs, &window);
    if window.lines.len() < 2 * a.ncols() {
        return None;
    }
    let norms: Vec<f64> = (0..a.ncols()).map(|c| a.col(c).norm_l2()).collect();
    for (c, n) in norms.iter().enumerate() {
        a.col_mut(c).iter_mut().for_each(|x| *x /= *n);
    }
    // Each curve weighted by 1/σ̂: one right-hand side per curve.
    let y = Mat::from_fn(window.lines.len(), data.curves.len(), |i, o| {
        let h = data.curves[o][window.lines[i]] / sigmas[o];
        c64::new(h.re, h.im)
    });
    let qr = a.qr();
    let coefficients = qr.solve_lstsq(&y);
    // v = [(AᴴA)⁻¹]₂₂ = |R⁻ᴴ e₂|² (A = QR).
    let upper = qr.thin_R();
    let mut e2 = Mat::<c64>::zeros(a.ncols(), 1);
    e2[(2, 0)] = c64::new(1.0, 0.0);
    solve_lower_triangular_in_place(upper.adjoint(), e2.as_mut(), Par::Seq);
    let variance = e2.col(0).norm_l2().powi(2);
    let row = |r: usize| -> Vec<Complex64> {
        (0..data.curves.len())
            .map(|o| {
                let c = coefficients[(r, o)];
                Complex64::new(c.re, c.im)
            })
            .collect()
    };
    let (psi, c) = (row(0), row(2));
    let orthogonal = orthogonal_part(&c, &psi)?;
    let n = data.curves.len() as f64;
    let statistic = orthogonal / (2.0 * variance * (n - 1.0));
    let psi_norm = psi.iter().map(Complex64::norm_sqr).sum::<f64>().sqrt();
    let relative_amplitude = orthogonal.sqrt() / psi_norm * norms[0] / norms[2] / (zk * wk);
    (statistic.is_finite() && relative_amplitude.is_finite()).then_some(SecondShape {
        statistic,
        relative_amplitude,
        chance: chi_square_survival(data.curves.len() - 1, (n - 1.0) * statistic),
    })
}

/// |c − ψ (ψᴴc)/(ψᴴψ)|²: the energy of `c` orthogonal to `psi`; None where ψ is zero.
fn orthogonal_part(c: &[Complex64], psi: &[Complex64]) -> Option<f64> {
    let psi_psi: f64 = psi.iter().map(Complex64::norm_sqr).sum();
    if psi_psi.is_nan() || psi_psi <= 0.0 {
        return None;
    }
    let along: Complex64 = psi
        .iter()
        .zip(c)
        .map(|(p, x)| p.conj() * x)
        .sum::<Complex64>()
        / psi_psi;
    Some(
        c.iter()
            .zip(psi)
            .map(|(x, p)| (x - p * along).norm_sqr())
            .sum(),
    )
}

/// P(χ²₂ₘ ≥ 2t) = e^{−t} Σ_{j<m} t^j/j! (an even number 2m of degrees of freedom: the Erlang
/// tail), summed in logarithms so that large m and t neither overflow nor underflow early.
fn chi_square_survival(m: usize, t: f64) -> f64 {
    if t <= 0.0 {
        return 1.0;
    }
    let mut log_term = 0.0_f64; // ln(t^j / j!) at j = 0
    let mut log_terms = Vec::with_capacity(m);
    for j in 0..m {
        if j > 0 {
            log_term += t.ln() - (j as f64).ln();
        }
        log_terms.push(log_term);
    }
    let top = log_terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let sum: f64 = log_terms.iter().map(|l| (l - top).exp()).sum();
    (top + sum.ln() - t).exp().min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::tests::gaussian_sequence;

    /// Pole of a mode at `f_hz` damped `zeta`.
    fn pole(f_hz: f64, zeta: f64) -> Complex64 {
        let w = 2.0 * PI * f_hz;
        Complex64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
    }

    /// Receptances of twelve points of a pinned beam driven at point 0, on 0.05 Hz lines from
    /// 0.05 to 150 Hz: one term per (f, ζ, mode number), its shape sin(nπx); complex white noise
    /// of `noise` times each curve's RMS.
    fn beam_curves(
        modes: &[(f64, f64, usize)],
        noise: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<Vec<Complex64>>) {
        let freqs: Vec<f64> = (1..=3000).map(|k| 0.05 * f64::from(k)).collect();
        let shape = |n: usize, o: usize| (n as f64 * PI * (0.07 + 0.079 * o as f64)).sin();
        let mut normal = gaussian_sequence(seed);
        let curves = (0..12)
            .map(|o| {
                let clean: Vec<Complex64> = freqs
                    .iter()
                    .map(|f| {
                        let w = 2.0 * PI * f;
                        modes
                            .iter()
                            .map(|&(fr, z, n)| {
                                let wr = 2.0 * PI * fr;
                                shape(n, o) * shape(n, 0)
                                    / Complex64::new(wr * wr - w * w, 2.0 * z * wr * w)
                            })
                            .sum()
                    })
                    .collect();
                let rms = (clean.iter().map(Complex64::norm_sqr).sum::<f64>() / clean.len() as f64)
                    .sqrt();
                clean
                    .iter()
                    .map(|h| h + noise * rms * normal() / 2f64.sqrt())
                    .collect()
            })
            .collect();
        (freqs, curves)
    }

    fn tests_of(
        poles: &[Complex64],
        freqs: &[f64],
        curves: &[Vec<Complex64>],
    ) -> Vec<Option<SecondShape>> {
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        second_shapes(
            poles,
            Measured {
                freqs_hz: freqs,
                curves: &refs,
                lines: &lines,
            },
            &CurveNoise::of(&refs, &lines),
        )
    }

    /// Z is a χ² of 22 degrees of freedom over 22 for one mode (twelve curves): above 3 with a
    /// chance of about 1e-6.
    const ONE_MODE_Z: f64 = 3.0;

    #[test]
    fn separate_modes_hold_no_second_shape() {
        let modes = [(40.0, 0.02, 1), (75.0, 0.02, 2), (120.0, 0.08, 3)];
        let poles: Vec<Complex64> = modes.iter().map(|&(f, z, _)| pole(f, z)).collect();
        for seed in 1..=5 {
            let (freqs, curves) = beam_curves(&modes, 0.01, seed);
            for t in tests_of(&poles, &freqs, &curves) {
                let t = t.expect("a test for every pole");
                assert!(t.statistic < ONE_MODE_Z, "seed {seed}: {t:?}");
            }
        }
    }

    #[test]
    fn a_pole_off_its_mode_leaves_a_parallel_term_only() {
        // The pole 0.5 % high in f and 10 % in ζ: a 1/(s − λ)² term of its own shape, which
        // the test does not count.
        let modes = [(40.0, 0.08, 1), (100.0, 0.08, 2)];
        let poles = [pole(40.2, 0.088), pole(100.0, 0.08)];
        let (freqs, curves) = beam_curves(&modes, 0.01, 3);
        let t = tests_of(&poles, &freqs, &curves)[0].unwrap();
        assert!(t.statistic < ONE_MODE_Z, "{t:?}");
    }

    #[test]
    fn one_pole_over_a_close_pair_holds_a_second_shape() {
        // Two modes 1.6 % apart at ζ 8 % (bandwidth 16 %), their shapes different.
        let modes = [(60.0, 0.08, 2), (61.0, 0.08, 3), (120.0, 0.02, 4)];
        let (freqs, curves) = beam_curves(&modes, 0.01, 4);
        let merged = [pole(60.5, 0.08), pole(120.0, 0.02)];
        let t = tests_of(&merged, &freqs, &curves)[0].unwrap();
        assert!(t.statistic > 10.0 * ONE_MODE_Z, "{t:?}");
        assert!(t.relative_amplitude > 0.02, "{t:?}");
        // Both poles given: no second shape left.
        let resolved = [pole(60.0, 0.08), pole(61.0, 0.08), pole(120.0, 0.02)];
        for t in tests_of(&resolved, &freqs, &curves) {
            assert!(t.unwrap().statistic < ONE_MODE_Z, "{t:?}");
        }
    }

    #[test]
    fn the_chance_is_the_chi_square_tail() {
        // Closed forms: 2 degrees of freedom e^{−t}; 4: e^{−t}(1 + t).
        assert!((chi_square_survival(1, 3.0) - (-3.0f64).exp()).abs() < 1e-15);
        assert!((chi_square_survival(2, 3.0) - 4.0 * (-3.0f64).exp()).abs() < 1e-15);
        // scipy.stats.chi2.sf(66, 22) = 2.7742e-06, and at the mean (Z = 1) 0.4599.
        assert!((chi_square_survival(11, 33.0) / 2.774_24e-6 - 1.0).abs() < 1e-4);
        assert!((chi_square_survival(11, 11.0) / 0.45989 - 1.0).abs() < 1e-4);
        // Far tails stay finite and ordered.
        let far = chi_square_survival(25, 2.6e6);
        assert!((0.0..1e-300).contains(&far));
        assert_eq!(chi_square_survival(3, 0.0), 1.0);
    }

    #[test]
    fn one_curve_cannot_tell() {
        let modes = [(60.0, 0.08, 2), (61.0, 0.08, 3)];
        let (freqs, curves) = beam_curves(&modes, 0.01, 5);
        let tests = tests_of(&[pole(60.5, 0.08)], &freqs, &curves[..1]);
        assert_eq!(tests, vec![None]);
    }
}
