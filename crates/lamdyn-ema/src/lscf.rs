//! Poles by the least-squares complex frequency-domain estimator (LSCF), the z-domain rational
//! fraction polynomial with a common denominator (the paper's RFP-Z) [Guillaume et al. 2003;
//! Verboven 2002, eq. 5.26].
//!
//! Each FRF H_o(ω_k), o = 1..N_o (every response × reference curve), is modelled as
//! B_o(Ω_k)/A(Ω_k) with Ω_k = e^{−iω_kΔt}, Δt = 1/(2 f_max) (the band mapped onto the upper half
//! of the unit circle) and real polynomial coefficients of order n. Linearised with unit weights,
//! the normal equations eliminate each B_o:
//!
//!   M = 2 Σ_o (T_o − S_oᵀ R⁻¹ S_o),   M a = 0 with a_n = 1 (least squares)
//!
//! where R, S_o, T_o are (n+1) × (n+1) Toeplitz matrices: R_jl = Re Σ_k Ω_k^{l−j},
//! S_o,jl = −Re Σ_k H_o,k Ω_k^{l−j}, T_o,jl = Re Σ_k |H_o,k|² Ω_k^{l−j}. Their generating sums
//! are computed once for the highest order; a lower order uses their leading blocks (the basis
//! is nested), so a whole stabilization diagram costs one pass over the data, and one
//! triangular solve plus one Gram product per row serve the reduced matrices of all orders
//! (see `Reduced`). When the lines
//! sit on a grid f_k = kΔf (the usual case), Ω_k^m = e^{−2πi mk/(2K)} with K = f_max/Δf and
//! the sums for all lags are one FFT of length 2K per curve (as in OpenModal and sdypy-EMA);
//! otherwise they are summed directly. Per order: one
//! Cholesky of R, one triangular solve with all S_o as right-hand sides, one Gram product.
//! The roots x_r of A give the poles λ_r = −ln(x_r)/Δt; the physical ones (Im λ > 0, Re λ < 0,
//! |λ|/2π in the band) are kept.

use crate::error::{EmaError, check_curves, invalid};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use num_complex::Complex64;
use rayon::prelude::*;
use serde::Serialize;
use std::f64::consts::PI;

/// The poles found at one model order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrderPoles {
    /// Model order n (denominator degree).
    pub order: usize,
    /// Physical poles λ (rad/s), increasing frequency.
    pub poles: Vec<Complex64>,
}

/// Natural frequency (Hz) of a pole: |λ|/2π.
pub fn pole_freq_hz(p: Complex64) -> f64 {
    p.norm() / (2.0 * PI)
}

/// Viscous damping ratio of a pole: −Re λ/|λ|.
pub fn pole_damping(p: Complex64) -> f64 {
    -p.re / p.norm()
}

/// The generating sums of the Toeplitz matrices for orders up to `n_max`.
struct Sums {
    /// r(m) = Re Σ_k Ω_k^m, m = 0..=n_max.
    r: Vec<f64>,
    /// t(m) = Re Σ_o Σ_k |H_o,k|² Ω_k^m, m = 0..=n_max.
    t: Vec<f64>,
    /// s_o(m) = −Re Σ_k H_o,k Ω_k^m for m = −n_max..=n_max (index m + n_max), per curve.
    s: Vec<Vec<f64>>,
}

/// The sums by FFT when every line index k = f/Δf is an integer up to K = f_max/Δf (`grid` =
/// the indices).
fn sums_fft(curves: &[&[Complex64]], grid: &[usize], k_max: usize, n_max: usize) -> Sums {
    let len = 2 * k_max;
    let fft = rustfft::FftPlanner::<f64>::new().plan_fft_forward(len);
    let transform = |values: &mut dyn Iterator<Item = (usize, Complex64)>| {
        let mut x = vec![Complex64::new(0.0, 0.0); len];
        for (k, v) in values {
            x[k] = v;
        }
        fft.process(&mut x);
        x
    };
    let r = transform(&mut grid.iter().map(|&k| (k, Complex64::new(1.0, 0.0))));
    let r: Vec<f64> = (0..=n_max).map(|m| r[m].re).collect();
    let per_curve: Vec<(Vec<f64>, Vec<f64>)> = curves
        .par_iter()
        .map(|h| {
            let x = transform(&mut grid.iter().zip(h.iter()).map(|(&k, v)| (k, *v)));
            let a = transform(
                &mut grid
                    .iter()
                    .zip(h.iter())
                    .map(|(&k, v)| (k, Complex64::new(v.norm_sqr(), 0.0))),
            );
            let s: Vec<f64> = (0..=2 * n_max)
                .map(|i| {
                    let m = i as isize - n_max as isize;
                    let idx = if m >= 0 {
                        m as usize
                    } else {
                        len - (-m) as usize
                    };
                    -x[idx].re
                })
                .collect();
            let t: Vec<f64> = (0..=n_max).map(|m| a[m].re).collect();
            (s, t)
        })
        .collect();
    combine(r, per_curve, n_max)
}

/// The sums from per-curve (s_o, t_o): t summed over the curves.
fn combine(r: Vec<f64>, per_curve: Vec<(Vec<f64>, Vec<f64>)>, n_max: usize) -> Sums {
    let mut t = vec![0.0; n_max + 1];
    let mut s = Vec::with_capacity(per_curve.len());
    for (sc, tc) in per_curve {
        for (a, b) in t.iter_mut().zip(&tc) {
            *a += b;
        }
        s.push(sc);
    }
    Sums { r, t, s }
}

/// Line indices k = f/Δf if the band's lines sit on one grid from 0 Hz with f_max a grid point.
fn grid_indices(freqs: &[f64], hi: f64) -> Option<(Vec<usize>, usize)> {
    if freqs.len() < 2 {
        return None;
    }
    let df = freqs[1] - freqs[0];
    if df <= 0.0 {
        return None;
    }
    let idx = |f: f64| {
        let k = (f / df).round();
        ((f / df - k).abs() < 1e-6).then_some(k as usize)
    };
    let k_max = idx(hi)?;
    let grid: Vec<usize> = freqs.iter().map(|&f| idx(f)).collect::<Option<_>>()?;
    (grid.windows(2).all(|w| w[1] > w[0]) && *grid.last()? <= k_max && k_max > 0)
        .then_some((grid, k_max))
}

fn sums(curves: &[&[Complex64]], omega_dt: &[f64], n_max: usize) -> Sums {
    let nf = omega_dt.len();
    // Ω_k^m for m = 0..=n_max, row-major by k.
    let powers: Vec<Complex64> = omega_dt
        .iter()
        .flat_map(|w| (0..=n_max).map(move |m| Complex64::from_polar(1.0, -w * m as f64)))
        .collect();
    let pw = |k: usize, m: usize| powers[k * (n_max + 1) + m];
    let r: Vec<f64> = (0..=n_max)
        .map(|m| (0..nf).map(|k| pw(k, m).re).sum())
        .collect();
    let per_curve: Vec<(Vec<f64>, Vec<f64>)> = curves
        .par_iter()
        .map(|h| {
            let mut s = vec![0.0; 2 * n_max + 1];
            let mut t = vec![0.0; n_max + 1];
            for (k, hk) in h.iter().enumerate() {
                let a2 = hk.norm_sqr();
                for m in 0..=n_max {
                    let p = pw(k, m);
                    // H Ω^m and H Ω^{−m} = H conj(Ω^m).
                    s[n_max + m] -= (hk * p).re;
                    if m > 0 {
                        s[n_max - m] -= (hk * p.conj()).re;
                    }
                    t[m] += a2 * p.re;
                }
            }
            (s, t)
        })
        .collect();
    combine(r, per_curve, n_max)
}

/// Settings of [`lscf`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LscfSettings {
    /// Band [f_lo, f_hi] in Hz.
    pub band_hz: [f64; 2],
    /// Lowest model order.
    pub min_order: usize,
    /// Highest model order.
    pub max_order: usize,
    /// Order step (2 keeps the conjugate pairs balanced, as sdypy-EMA does).
    pub step: usize,
}

/// Poles at every order of `settings` from the FRF curves `curves` sampled at `freqs_hz`.
///
/// # Errors
/// [`EmaError::Invalid`] for an empty or reversed band, a band with fewer lines than the highest
/// order needs (n + 1), curves of the wrong length, non-finite values, or orders out of range.
pub fn lscf(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    settings: &LscfSettings,
) -> Result<Vec<OrderPoles>, EmaError> {
    let [lo, hi] = settings.band_hz;
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
        return Err(invalid(
            "band",
            format!("[{lo}, {hi}] Hz must be finite, non-negative and increasing"),
        ));
    }
    if curves.is_empty() {
        return Err(invalid("FRFs", "no FRF given".into()));
    }
    check_curves(freqs_hz, curves)?;
    let lines: Vec<usize> = (0..freqs_hz.len())
        .filter(|&k| freqs_hz[k] >= lo && freqs_hz[k] <= hi)
        .collect();
    let (min_o, max_o, step) = (
        settings.min_order.max(1),
        settings.max_order,
        settings.step.max(1),
    );
    if max_o < min_o {
        return Err(invalid(
            "orders",
            format!("highest order {max_o} below the lowest {min_o}"),
        ));
    }
    if lines.len() < max_o + 1 {
        return Err(invalid(
            "band",
            format!(
                "{} lines in [{lo}, {hi}] Hz: order {max_o} needs at least {}",
                lines.len(),
                max_o + 1
            ),
        ));
    }
    let dt = 1.0 / (2.0 * hi);
    let omega_dt: Vec<f64> = lines.iter().map(|&k| 2.0 * PI * freqs_hz[k] * dt).collect();
    let band_curves: Vec<Vec<Complex64>> = curves
        .iter()
        .map(|c| lines.iter().map(|&k| c[k]).collect())
        .collect();
    if band_curves
        .iter()
        .flatten()
        .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return Err(invalid("FRFs", "a value in the band is not finite".into()));
    }
    let refs: Vec<&[Complex64]> = band_curves.iter().map(Vec::as_slice).collect();
    let band_freqs: Vec<f64> = lines.iter().map(|&k| freqs_hz[k]).collect();
    let sums = match grid_indices(&band_freqs, hi) {
        Some((grid, k_max)) if 2 * k_max > 2 * max_o => sums_fft(&refs, &grid, k_max, max_o),
        _ => sums(&refs, &omega_dt, max_o),
    };
    let orders: Vec<usize> = (min_o..=max_o).step_by(step).collect();
    let Some(reduced) = reduce(&sums, &orders) else {
        return Err(invalid(
            "band",
            "the normal equations are singular (too few distinct lines?)".into(),
        ));
    };
    let out: Vec<OrderPoles> = reduced
        .cumulative
        .par_iter()
        .map(|(n, gram)| OrderPoles {
            order: *n,
            poles: poles_at_order(&reduced.t, gram, *n, dt, [lo, hi]),
        })
        .collect();
    Ok(out)
}

/// The reduced normal matrices of every order at once.
///
/// With R_N = L Lᵀ (Cholesky at the highest order N), the leading block of L is the Cholesky
/// factor of every lower order's R_n, and forward substitution makes the leading (n+1) × (n+1)
/// block of W_o = L⁻¹ S_o,N equal to L_n⁻¹ S_o,n. So Σ_o S_o,nᵀ R_n⁻¹ S_o,n = Σ_{i ≤ n} P_i
/// restricted to indices ≤ n, with P_i = Σ_o w_o,i w_o,iᵀ (w_o,i = row i of W_o): one
/// triangular solve and N + 1 Gram products serve all orders.
struct Reduced {
    /// Σ_{i ≤ n} P_i for each needed n, as full (N+1)² matrices (leading blocks used).
    cumulative: Vec<(usize, Mat<f64>)>,
    t: Vec<f64>,
}

fn reduce(s: &Sums, orders: &[usize]) -> Option<Reduced> {
    let nmax = s.t.len() - 1;
    let np1 = nmax + 1;
    let r = Mat::from_fn(np1, np1, |j, l| s.r[j.abs_diff(l)]);
    let chol = r.llt(Side::Lower).ok()?;
    let compressed = compress(&s.s);
    let gen_s = compressed.as_ref().unwrap_or(&s.s);
    let no = gen_s.len();
    // All S_o side by side: S_o,jl = s_o(l − j).
    let mut w = Mat::from_fn(np1, no * np1, |j, c| {
        let (o, l) = (c / np1, c % np1);
        gen_s[o][nmax + l - j]
    });
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        chol.L(),
        w.as_mut(),
        faer::Par::rayon(0),
    );
    // P_i for every row i, in parallel (small sequential products: no nested threading).
    let p: Vec<Mat<f64>> = (0..np1)
        .into_par_iter()
        .map(|i| {
            let rows = Mat::from_fn(no, np1, |o, l| w[(i, o * np1 + l)]);
            let mut pi = Mat::<f64>::zeros(np1, np1);
            faer::linalg::matmul::matmul(
                pi.as_mut(),
                faer::Accum::Replace,
                rows.transpose(),
                rows.as_ref(),
                1.0,
                faer::Par::Seq,
            );
            pi
        })
        .collect();
    let mut acc = Mat::<f64>::zeros(np1, np1);
    let mut cumulative = Vec::with_capacity(orders.len());
    let mut next = orders.iter().copied().peekable();
    for (i, pi) in p.iter().enumerate() {
        acc += pi;
        while next.peek() == Some(&i) {
            cumulative.push((i, acc.clone()));
            next.next();
        }
    }
    Some(Reduced {
        cumulative,
        t: s.t.clone(),
    })
}

/// The sums s_o enter Σ_o S_oᵀ R⁻¹ S_o only through the Gram matrix C = Σ_o s_o s_oᵀ (the
/// expression is a quadratic form in s_o), so when there are more curves than lags (2N + 1)
/// they are replaced by the eigenvectors of C scaled by √(eigenvalue): exact, and the work
/// then scales with min(N_o, 2N + 1) instead of N_o. `None` when no compression helps.
fn compress(s: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let (no, len) = (s.len(), s.first()?.len());
    if no <= len {
        return None;
    }
    let data = Mat::from_fn(no, len, |o, q| s[o][q]);
    let c = data.transpose() * &data;
    let evd = c.self_adjoint_eigen(Side::Lower).ok()?;
    let (u, lam) = (evd.U(), evd.S().column_vector());
    let top = (0..len).map(|k| lam[k]).fold(0.0, f64::max);
    Some(
        (0..len)
            .filter(|&k| lam[k] > 1e-15 * top)
            .map(|k| (0..len).map(|q| lam[k].sqrt() * u[(q, k)]).collect())
            .collect(),
    )
}

/// Physical poles of the order-n model from its reduced normal matrix Σ_{i ≤ n} P_i (empty if
/// the equations are singular).
fn poles_at_order(t: &[f64], gram: &Mat<f64>, n: usize, dt: f64, band: [f64; 2]) -> Vec<Complex64> {
    let np1 = n + 1;
    let m = Mat::from_fn(np1, np1, |j, l| t[j.abs_diff(l)] - gram[(j, l)]);
    // a_n = 1: M[0..n, 0..n] a' = −M[0..n, n].
    let lhs = m.submatrix(0, 0, n, n).to_owned();
    let rhs = Mat::from_fn(n, 1, |j, _| -m[(j, n)]);
    let a = lhs.partial_piv_lu().solve(&rhs);
    if (0..n).any(|j| !a[(j, 0)].is_finite()) {
        return vec![];
    }
    // Companion matrix of x^n + Σ_{j<n} a_j x^j.
    let comp = Mat::from_fn(n, n, |i, j| {
        if i == 0 {
            -a[(n - 1 - j, 0)]
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let Some(roots) = eigenvalues_seq(&balance(comp)) else {
        return vec![];
    };
    let (lo, hi) = (2.0 * PI * band[0], 2.0 * PI * band[1]);
    let mut poles: Vec<Complex64> = roots
        .into_iter()
        .map(|x| -x.ln() / dt)
        .filter(|p| p.im > 0.0 && p.re < 0.0 && p.norm() >= lo && p.norm() <= hi)
        .collect();
    poles.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    poles
}

/// Diagonal similarity scaling by powers of two that makes row and column norms comparable
/// (Parlett–Reinsch balancing, as LAPACK's dgebal): the eigenvalues are unchanged, the QR
/// iteration converges faster and more accurately on companion matrices.
fn balance(mut a: Mat<f64>) -> Mat<f64> {
    let n = a.nrows();
    for _ in 0..20 {
        let mut done = true;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&j| j != i).map(|j| a[(j, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&j| j != i).map(|j| a[(i, j)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / 2.0 {
                cc *= 2.0;
                rr /= 2.0;
                f *= 2.0;
            }
            while cc >= rr * 2.0 {
                cc /= 2.0;
                rr *= 2.0;
                f /= 2.0;
            }
            if (cc + rr) < 0.95 * (c + r) {
                done = false;
                for j in 0..n {
                    a[(i, j)] /= f;
                    a[(j, i)] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
    a
}

/// Eigenvalues of a small real matrix without threads (the orders already run in parallel).
fn eigenvalues_seq(a: &Mat<f64>) -> Option<Vec<Complex64>> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{ComputeEigenvectors, evd_real, evd_scratch};
    let n = a.nrows();
    let par = faer::Par::Seq;
    let (mut re, mut im) = (
        faer::diag::Diag::<f64>::zeros(n),
        faer::diag::Diag::<f64>::zeros(n),
    );
    let mut mem = MemBuffer::new(evd_scratch::<f64>(
        n,
        ComputeEigenvectors::No,
        ComputeEigenvectors::No,
        par,
        Default::default(),
    ));
    evd_real(
        a.as_ref(),
        re.as_mut(),
        im.as_mut(),
        None,
        None,
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    Some((0..n).map(|k| Complex64::new(re[k], im[k])).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two exact modes, no noise: an over-specified model (order 16; a continuous-time FRF is
    /// not exactly rational in Ω, so the minimal order 4 is biased by 0.1 %) has poles within
    /// 1e-5 of the truth.
    /// Compressing many curves into the eigenvectors of their Gram matrix leaves the reduced
    /// normal matrices unchanged.
    #[test]
    fn compression_is_exact() {
        let n_max = 4;
        let s: Vec<Vec<f64>> = (0..20)
            .map(|o| {
                (0..2 * n_max + 1)
                    .map(|q| ((o * 7 + q * 3) as f64).sin() + 0.1 * o as f64)
                    .collect()
            })
            .collect();
        let sums = Sums {
            r: (0..=n_max)
                .map(|m| if m == 0 { 10.0 } else { 1.0 / (1.0 + m as f64) })
                .collect(),
            t: vec![100.0; n_max + 1],
            s: s.clone(),
        };
        let full = reduce(&sums, &[4]).unwrap();
        assert!(compress(&s).is_some_and(|c| c.len() <= 2 * n_max + 1));
        // Reference without compression: Σ_o W_oᵀ W_o computed directly at order 4.
        let np1 = n_max + 1;
        let r = Mat::from_fn(np1, np1, |j, l| sums.r[j.abs_diff(l)]);
        let rinv = r
            .llt(Side::Lower)
            .unwrap()
            .solve(Mat::<f64>::identity(np1, np1));
        let mut g = Mat::<f64>::zeros(np1, np1);
        for so in &s {
            let sm = Mat::from_fn(np1, np1, |j, l| so[n_max + l - j]);
            g += sm.transpose() * &rinv * &sm;
        }
        let got = &full.cumulative[0].1;
        for j in 0..np1 {
            for l in 0..np1 {
                assert!(
                    (got[(j, l)] - g[(j, l)]).abs() < 1e-9 * g[(j, l)].abs().max(1.0),
                    "{j} {l}: {} vs {}",
                    got[(j, l)],
                    g[(j, l)]
                );
            }
        }
    }

    /// The FFT route gives the direct sums.
    #[test]
    fn fft_sums_equal_direct_sums() {
        let freqs: Vec<f64> = (3..=200).map(|k| k as f64 * 0.5).collect();
        let h: Vec<Complex64> = freqs
            .iter()
            .map(|f| Complex64::new(f.sin(), (0.3 * f).cos()))
            .collect();
        let hi = 100.0;
        let omega_dt: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f / (2.0 * hi)).collect();
        let (grid, k_max) = grid_indices(&freqs, hi).unwrap();
        let (a, b) = (
            sums(&[&h], &omega_dt, 12),
            sums_fft(&[&h], &grid, k_max, 12),
        );
        for (x, y) in
            a.r.iter()
                .chain(&a.t)
                .chain(&a.s[0])
                .zip(b.r.iter().chain(&b.t).chain(&b.s[0]))
        {
            assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn exact_poles_from_noise_free_frfs() {
        let poles = [
            Complex64::new(-0.5, 2.0 * PI * 10.0),
            Complex64::new(-2.0, 2.0 * PI * 23.0),
        ];
        let freqs: Vec<f64> = (0..=400).map(|k| k as f64 * 0.1).collect();
        let curves: Vec<Vec<Complex64>> = (0..3)
            .map(|o| {
                freqs
                    .iter()
                    .map(|f| {
                        let s = Complex64::new(0.0, 2.0 * PI * f);
                        poles
                            .iter()
                            .enumerate()
                            .map(|(r, p)| {
                                let a = Complex64::new(0.0, 1.0 + o as f64 + r as f64);
                                a / (s - p) + a.conj() / (s - p.conj())
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let refs: Vec<&[Complex64]> = curves.iter().map(Vec::as_slice).collect();
        let out = lscf(
            &freqs,
            &refs,
            &LscfSettings {
                band_hz: [0.0, 40.0],
                min_order: 16,
                max_order: 16,
                step: 2,
            },
        )
        .unwrap();
        for q in &poles {
            let p = out[0]
                .poles
                .iter()
                .min_by(|a, b| (*a - q).norm().total_cmp(&(*b - q).norm()))
                .unwrap();
            assert!(
                (p - q).norm() / q.norm() < 1e-5,
                "{p} vs {q}: {:?}",
                out[0].poles
            );
        }
    }
}
