//! Poles by the least-squares complex frequency-domain estimator: LSCF, the z-domain rational
//! fraction polynomial with a common denominator (the paper's RFP-Z) [Guillaume et al. 2003;
//! Verboven 2002, eq. 5.26], and its multi-reference form pLSCF (PolyMAX) [Peeters et al. 2004;
//! Guillaume et al. 2003, "A poly-reference implementation of the LSCF estimator"].
//!
//! The curves come grouped by output: output o = 1..N_o holds the row H_o(ω) of N_i reference
//! curves (N_i = 1: LSCF). The model is a right matrix-fraction description
//!
//!   H_o(ω_k) ≈ B_o(Ω_k) A(Ω_k)⁻¹,  Ω_k = e^{−iω_kΔt}, Δt = 1/(2 f_max),
//!
//! with real polynomial coefficients of order n: B_o is 1 × N_i, A is N_i × N_i and monic
//! (A_n = I, the "lower right matrix" constraint of PolyMAX). Linearised with unit weights, the
//! normal equations eliminate each B_o:
//!
//!   M = Σ_o (T_o − S_oᵀ R⁻¹ S_o),   M α = 0 with α_n = I (least squares),
//!
//! where, with unknowns ordered reference-major ((a, j): row a of α_j), R_jl = r(l − j),
//! S_o[j, (b, l)] = s_ob(l − j), T[(a, j), (b, l)] = t_ab(l − j) are block Toeplitz matrices of
//! the lag sums
//!
//!   r(m) = Re Σ_k Ω_k^m,  s_ob(m) = −Re Σ_k H_ob,k Ω_k^m,  t_ab(m) = Re Σ_o Σ_k H̄_oa,k H_ob,k Ω_k^m.
//!
//! The sums are computed once for the highest order; a lower order uses their leading blocks
//! (the basis is nested), so a whole stabilization diagram costs one pass over the data, and one
//! triangular solve plus one Gram product per row serve the reduced matrices of all orders
//! (see `Reduced`). When the lines sit on a grid f_k = kΔf (the usual case),
//! Ω_k^m = e^{−2πi mk/(2K)} with K = f_max/Δf and the sums for all lags are one FFT of length 2K
//! per sequence (as in OpenModal and sdypy-EMA), or per two sequences, since only their real
//! parts are needed (`LagSums::sums`); otherwise they are summed directly.
//!
//! The poles are the roots x_r of det A (the block companion matrix, `companion`), mapped by
//! λ_r = −ln(x_r)/Δt; the physical ones (Im λ > 0, Re λ < 0, |λ|/2π in the band) are kept.
//! **Mode vectors** for the stability diagram: with v_r the right null vector of A(x_r), the
//! numerators give ψ_o,r = B_o(x_r) v_r ∝ the residue shape of the pole over the outputs (near
//! x_r, H A v = B v and H ≈ ψ lᵀ/(x − x_r)), with B_o's coefficients θ_o = −R⁻¹ S_o α from the
//! eliminated equations.

use crate::companion::MatrixPolynomial;
use crate::error::{EmaError, check_curves, invalid};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use num_complex::Complex64;
use rayon::prelude::*;
use serde::Serialize;
use std::borrow::Cow;
use std::f64::consts::PI;

/// The poles found at one model order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrderPoles {
    /// Model order n (denominator degree).
    pub order: usize,
    /// Physical poles λ (rad/s), increasing frequency.
    pub poles: Vec<Complex64>,
    /// Mode vector ψ of each pole over the outputs (module docs); empty unless asked for.
    #[serde(skip)]
    pub vectors: Vec<Vec<Complex64>>,
    /// Every root x_r of det A in the Ω domain: both of each conjugate pair, the real ones and
    /// the computational ones (the model's whole denominator, [`crate::context`]).
    #[serde(skip)]
    pub roots: Vec<Complex64>,
}

/// The sampling interval Δt = 1/(2 f_hi) of the z-domain model over the band [f_lo, f_hi]
/// (module docs), s.
pub fn sample_interval(band_hz: [f64; 2]) -> f64 {
    1.0 / (2.0 * band_hz[1])
}

/// Natural frequency (Hz) of a pole: |λ|/2π.
pub fn pole_freq_hz(p: Complex64) -> f64 {
    p.norm() / (2.0 * PI)
}

/// Viscous damping ratio of a pole: −Re λ/|λ|.
pub fn pole_damping(p: Complex64) -> f64 {
    -p.re / p.norm()
}

/// The pole λ = ω_n(−ζ + i√(1 − ζ²)), ω_n = 2π `freq_hz`, of natural frequency `freq_hz` and
/// damping ratio `damping` (the inverse of [`pole_freq_hz`] and [`pole_damping`]; at ζ ≥ 1
/// on the negative real axis).
pub fn pole_at(freq_hz: f64, damping: f64) -> Complex64 {
    let w = 2.0 * PI * freq_hz;
    Complex64::new(-damping * w, w * (1.0 - damping * damping).max(0.0).sqrt())
}

/// Whether the half-power bands of two poles overlap: |f₁ − f₂| < ζ₁f₁ + ζ₂f₂, with f = |λ|/2π
/// and ζf = −Re λ/2π (the half-power half-width).
pub fn half_power_bands_overlap(a: Complex64, b: Complex64) -> bool {
    let half_width = |p: Complex64| -p.re / (2.0 * PI);
    (b.norm() - a.norm()).abs() / (2.0 * PI) < half_width(a) + half_width(b)
}

/// Whether two poles lie within the larger of their half-power half-widths of each other:
/// |f₁ − f₂| ≤ max(ζ₁f₁, ζ₂f₂), with f = |λ|/2π and ζf = −Re λ/2π. A close pair, nearer than
/// [`half_power_bands_overlap`] asks.
pub(crate) fn within_a_half_width(a: Complex64, b: Complex64) -> bool {
    (b.norm() - a.norm()).abs() <= (-a.re).max(-b.re)
}

/// The lag sums of the block Toeplitz matrices for orders up to `n_max` (module docs); `t` and
/// `s` hold lags m = −n_max..=n_max at index m + n_max.
struct Sums {
    /// Highest order N.
    n_max: usize,
    /// References per output, N_i.
    refs: usize,
    /// r(m) for m = 0..=n_max only (r is even).
    r: Vec<f64>,
    /// t_ab(m) summed over the outputs, at index a·N_i + b.
    t: Vec<Vec<f64>>,
    /// s_ob(m) per curve, at index o·N_i + b.
    s: Vec<Vec<f64>>,
}

impl Sums {
    /// Outputs N_o.
    fn outputs(&self) -> usize {
        self.s.len() / self.refs
    }
}

/// How the lag sums L(m) = Re Σ_k y_k Ω_k^m, m = −N..=N, of a sequence y over the band's lines
/// are computed.
enum LagSums {
    /// Lines on a grid k·Δf up to K = f_max/Δf: one FFT of length 2K.
    Fft {
        fft: std::sync::Arc<dyn rustfft::Fft<f64>>,
        grid: Vec<usize>,
    },
    /// Any lines: Ω_k^m for m = 0..=N, row-major by line.
    Direct { powers: Vec<Complex64> },
}

impl LagSums {
    fn new(band_freqs: &[f64], hi: f64, omega_dt: &[f64], n_max: usize) -> Self {
        match grid_indices(band_freqs, hi) {
            Some((grid, k_max)) if k_max > n_max => Self::Fft {
                fft: rustfft::FftPlanner::<f64>::new().plan_fft_forward(2 * k_max),
                grid,
            },
            _ => Self::Direct {
                powers: omega_dt
                    .iter()
                    .flat_map(|w| {
                        (0..=n_max).map(move |m| Complex64::from_polar(1.0, -w * m as f64))
                    })
                    .collect(),
            },
        }
    }

    /// L(m) for m = −n_max..=n_max of `first` and, where given, of `second` (each the
    /// sequence's value at the band's line k); `buffers` holds the FFT's work between calls.
    ///
    /// By the FFT one transform serves both. On the grid Ω_k^m = W^{g_k m} (W = e^{−2πi/2K},
    /// g_k the line's grid index), so L(m) = Re Σ_k y_k W^{g_k m} is the transform of the
    /// Hermitian sequence z with z_g = y_k/2 and z_{2K−g} = ȳ_k/2 at each line, whose
    /// transform is real: z₁ + i z₂ transforms to L₁ + i L₂.
    fn sums(
        &self,
        first: &dyn Fn(usize) -> Complex64,
        second: Option<&dyn Fn(usize) -> Complex64>,
        n_max: usize,
        buffers: &mut FftBuffers,
    ) -> (Vec<f64>, Option<Vec<f64>>) {
        match self {
            Self::Fft { fft, grid } => {
                let len = fft.len();
                let x = &mut buffers.data;
                x.clear();
                x.resize(len, Complex64::new(0.0, 0.0));
                for (k, &g) in grid.iter().enumerate() {
                    let (a, b) = (first(k), second.map_or(Complex64::default(), |s| s(k)));
                    // z₁ + i z₂ at g and at 2K − g.
                    x[g] += 0.5 * Complex64::new(a.re - b.im, a.im + b.re);
                    x[(len - g) % len] += 0.5 * Complex64::new(a.re + b.im, b.re - a.im);
                }
                let scratch = &mut buffers.scratch;
                scratch.resize(fft.get_inplace_scratch_len(), Complex64::new(0.0, 0.0));
                fft.process_with_scratch(x, scratch);
                let at = |i: usize| {
                    let m = i as isize - n_max as isize;
                    x[m.rem_euclid(len as isize) as usize]
                };
                let lags = 0..=2 * n_max;
                let second_sums = second.map(|_| lags.clone().map(|i| at(i).im).collect());
                (lags.map(|i| at(i).re).collect(), second_sums)
            }
            Self::Direct { powers } => {
                let direct = |y: &dyn Fn(usize) -> Complex64| {
                    let mut out = vec![0.0; 2 * n_max + 1];
                    for k in 0..powers.len() / (n_max + 1) {
                        let v = y(k);
                        for m in 0..=n_max {
                            // y Ω^m and y Ω^{−m} = y conj(Ω^m).
                            let p = powers[k * (n_max + 1) + m];
                            out[n_max + m] += (v * p).re;
                            if m > 0 {
                                out[n_max - m] += (v * p.conj()).re;
                            }
                        }
                    }
                    out
                };
                (direct(first), second.map(direct))
            }
        }
    }
}

/// One thread's FFT input and scratch, reused from one lag sum to the next: each is as long as
/// the FFT, and fresh pages for every sum cost more than reuse (docs/ema.md, "Whole process").
#[derive(Default)]
struct FftBuffers {
    data: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

/// All lag sums of the curves (band lines only, grouped by output with `refs` curves each):
/// those of 1 (r), of each curve negated (s) and of each pair of references' products (t), two
/// sequences per transform ([`LagSums::sums`]).
///
/// t_ab is linear in the products H̄_oa,k H_ob,k, so the outputs are summed line by line before
/// one transform per pair (a ≤ b): N_i(N_i + 1)/2 transforms for t, not N_o times as many.
fn lag_sums(curves: &[&[Complex64]], refs: usize, how: &LagSums, n_max: usize) -> Sums {
    let rows: Vec<&[&[Complex64]]> = curves.chunks(refs).collect();
    let pairs: Vec<(usize, usize)> = reference_pairs(refs).collect();
    let mut series = vec![Series::One];
    series.extend((0..curves.len()).map(Series::Curve));
    series.extend(pairs.iter().map(|&(a, b)| Series::Pair(a, b)));
    let rows = rows.as_slice();
    let value = |series: Series| {
        move |k: usize| match series {
            Series::One => Complex64::new(1.0, 0.0),
            Series::Curve(c) => -curves[c][k],
            Series::Pair(a, b) => rows.iter().map(|row| row[a][k].conj() * row[b][k]).sum(),
        }
    };
    let mut all: Vec<Vec<f64>> = series
        .par_chunks(2)
        .map_init(FftBuffers::default, |buffers, two| {
            let first = value(two[0]);
            let second = two.get(1).map(|&s| value(s));
            let second = second.as_ref().map(|f| f as &dyn Fn(usize) -> Complex64);
            let (a, b) = how.sums(&first, second, n_max, buffers);
            std::iter::once(a).chain(b).collect::<Vec<_>>()
        })
        .flatten_iter()
        .collect();
    let pair_sums = all.split_off(1 + curves.len());
    let s = all.split_off(1);
    let r = all.swap_remove(0)[n_max..].to_vec();
    let mut t = vec![Vec::new(); refs * refs];
    for ((a, b), tab) in pairs.into_iter().zip(pair_sums) {
        // t_ba(m) = t_ab(−m).
        t[b * refs + a] = tab.iter().rev().copied().collect();
        t[a * refs + b] = tab;
    }
    Sums {
        n_max,
        refs,
        r,
        t,
        s,
    }
}

/// A sequence over the band's lines whose lag sums [`lag_sums`] takes.
#[derive(Debug, Clone, Copy)]
enum Series {
    /// 1 at every line (r).
    One,
    /// Curve c negated (s).
    Curve(usize),
    /// Σ_o H̄_oa,k H_ob,k over the outputs (t_ab).
    Pair(usize, usize),
}

/// The pairs (a, b), a ≤ b, of `refs` references, a-major.
fn reference_pairs(refs: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..refs).flat_map(move |a| (a..refs).map(move |b| (a, b)))
}

/// The curves' values on the band's `lines`: in place where the lines follow one another
/// ([`contiguous_range`]), else gathered.
///
/// # Errors
/// [`EmaError::Invalid`] where a value is not finite.
fn band_values<'a>(
    curves: &[&'a [Complex64]],
    lines: &[usize],
) -> Result<Vec<Cow<'a, [Complex64]>>, EmaError> {
    let values: Vec<Cow<'a, [Complex64]>> = match contiguous_range(lines) {
        Some(range) => curves
            .iter()
            .map(|c| Cow::Borrowed(&c[range.clone()]))
            .collect(),
        None => curves
            .iter()
            .map(|c| Cow::Owned(lines.iter().map(|&k| c[k]).collect()))
            .collect(),
    };
    let finite = |v: &Complex64| v.re.is_finite() && v.im.is_finite();
    if !values.iter().all(|c| c.iter().all(finite)) {
        return Err(invalid("FRFs", "a value in the band is not finite".into()));
    }
    Ok(values)
}

/// The range `lines` covers when its indices follow one another (a band of an increasing axis):
/// the curves' values there are used in place.
fn contiguous_range(lines: &[usize]) -> Option<std::ops::Range<usize>> {
    let (&first, &last) = (lines.first()?, lines.last()?);
    (last - first + 1 == lines.len()).then_some(first..last + 1)
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
    /// References N_i: the curves come grouped by output, N_i per output. 1 is LSCF; more is
    /// the multi-reference pLSCF (PolyMAX).
    pub references: usize,
    /// Compute each pole's mode vector over the outputs (for the diagram's vector criterion).
    pub mode_vectors: bool,
}

impl LscfSettings {
    /// Single-reference LSCF over `band_hz` at orders `min..=max` step `step`, with mode vectors.
    pub fn new(band_hz: [f64; 2], (min_order, max_order, step): (usize, usize, usize)) -> Self {
        Self {
            band_hz,
            min_order,
            max_order,
            step,
            references: 1,
            mode_vectors: true,
        }
    }
}

/// Poles at every order of `settings` from the FRF curves `curves` sampled at `freqs_hz`
/// (grouped by output, `settings.references` curves each).
///
/// # Errors
/// [`EmaError::Invalid`] for an empty or reversed band, a band with fewer lines than the highest
/// order needs (n + 1), curves of the wrong length or count, non-finite values, or orders out of
/// range.
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
    let refs = settings.references.max(1);
    if curves.len() % refs != 0 {
        return Err(invalid(
            "references",
            format!(
                "{} curves cannot be grouped into outputs of {refs} references",
                curves.len()
            ),
        ));
    }
    check_curves(freqs_hz, curves)?;
    let lines = crate::band::lines(freqs_hz, [lo, hi]);
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
    let dt = sample_interval([lo, hi]);
    let band_freqs: Vec<f64> = lines.iter().map(|&k| freqs_hz[k]).collect();
    let omega_dt: Vec<f64> = band_freqs.iter().map(|f| 2.0 * PI * f * dt).collect();
    let values = band_values(curves, &lines)?;
    let band_curves: Vec<&[Complex64]> = values.iter().map(AsRef::as_ref).collect();
    let how = LagSums::new(&band_freqs, hi, &omega_dt, max_o);
    let sums = lag_sums(&band_curves, refs, &how, max_o);
    let orders: Vec<usize> = (min_o..=max_o).step_by(step).collect();
    let Some(reduced) = reduce(&sums, &orders) else {
        return Err(invalid(
            "band",
            "the normal equations are singular (too few distinct lines?)".into(),
        ));
    };
    let model = |n: usize, gram: &Mat<f64>| {
        let poly = denominator(&sums, gram, n)?;
        Some(OrderModel {
            sums: &sums,
            l: &reduced.l,
            poly,
            n,
        })
    };
    let out: Vec<OrderPoles> = reduced
        .cumulative
        .par_iter()
        .map(|(n, gram)| {
            let (poles, vectors, roots) = model(*n, gram)
                .map(|m| m.poles(dt, [lo, hi], settings.mode_vectors))
                .unwrap_or_default();
            OrderPoles {
                order: *n,
                poles,
                vectors,
                roots,
            }
        })
        .collect();
    Ok(out)
}

/// The reduced normal matrices of every order at once.
///
/// With R_N = L Lᵀ (Cholesky at the highest order N), the leading block of L is the Cholesky
/// factor of every lower order's R_n, and forward substitution makes the leading (n+1)-row
/// blocks of W_o = L⁻¹ S_o,N equal to L_n⁻¹ S_o,n. So Σ_o S_o,nᵀ R_n⁻¹ S_o,n = Σ_{i ≤ n} P_i
/// restricted to lags ≤ n, with P_i = Σ_o w_o,i w_o,iᵀ (w_o,i = row i of W_o): one
/// triangular solve and N + 1 Gram products serve all orders.
struct Reduced {
    /// Σ_{i ≤ n} P_i for each needed n, as full (N_i(N+1))² matrices indexed (a, j) → a(N+1) + j
    /// (leading blocks used).
    cumulative: Vec<(usize, Mat<f64>)>,
    /// The Cholesky factor L of R_N.
    l: Mat<f64>,
}

fn reduce(s: &Sums, orders: &[usize]) -> Option<Reduced> {
    let (nmax, ni) = (s.n_max, s.refs);
    let np1 = nmax + 1;
    let lags = 2 * nmax + 1;
    let r = Mat::from_fn(np1, np1, |j, l| s.r[j.abs_diff(l)]);
    let chol = r.llt(Side::Lower).ok()?;
    // One vector per output: its references' s_ob one after the other.
    let rows: Vec<Vec<f64>> = s.s.chunks(ni).map(|c| c.concat()).collect();
    let gen_s = compress(&rows).unwrap_or(rows);
    let no = gen_s.len();
    let width = ni * np1;
    // All S_o side by side: column (o, b, l) holds s_ob(l − j).
    let mut w = Mat::from_fn(np1, no * width, |j, c| {
        let (o, q) = (c / width, c % width);
        let (b, l) = (q / np1, q % np1);
        gen_s[o][b * lags + nmax + l - j]
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
            let rows = Mat::from_fn(no, width, |o, q| w[(i, o * width + q)]);
            let mut pi = Mat::<f64>::zeros(width, width);
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
    let mut acc = Mat::<f64>::zeros(width, width);
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
        l: chol.L().to_owned(),
    })
}

/// The sums s_o enter Σ_o S_oᵀ R⁻¹ S_o only through the Gram matrix C = Σ_o s_o s_oᵀ (the
/// expression is a quadratic form in s_o), so when there are more outputs than entries in s_o
/// (N_i(2N + 1)) they are replaced by the eigenvectors of C scaled by √(eigenvalue): exact, and
/// the work then scales with min(N_o, N_i(2N + 1)) instead of N_o. `None` when no compression
/// helps.
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

/// The monic denominator A of order n from its reduced normal matrix Σ_{i ≤ n} P_i: the
/// least-squares solution of M α = 0 with α_n = I (`None` if the equations are singular).
fn denominator(s: &Sums, gram: &Mat<f64>, n: usize) -> Option<MatrixPolynomial> {
    let (ni, big, np1) = (s.refs, s.n_max + 1, n + 1);
    let m = Mat::from_fn(ni * np1, ni * np1, |i, j| {
        let (a, p) = (i / np1, i % np1);
        let (b, q) = (j / np1, j % np1);
        s.t[a * ni + b][s.n_max + q - p] - gram[(a * big + p, b * big + q)]
    });
    let free: Vec<usize> = (0..ni)
        .flat_map(|a| (0..n).map(move |p| a * np1 + p))
        .collect();
    let lhs = Mat::from_fn(free.len(), free.len(), |i, j| m[(free[i], free[j])]);
    let rhs = Mat::from_fn(free.len(), ni, |i, b| -m[(free[i], b * np1 + n)]);
    let x = lhs.partial_piv_lu().solve(&rhs);
    let coeffs: Vec<Vec<f64>> = (0..n)
        .map(|l| {
            (0..ni * ni)
                .map(|ab| x[((ab / ni) * n + l, ab % ni)])
                .collect()
        })
        .collect();
    coeffs
        .iter()
        .flatten()
        .all(|v| v.is_finite())
        .then_some(MatrixPolynomial { size: ni, coeffs })
}

/// The model of one order: its denominator and what the numerators need.
struct OrderModel<'a> {
    sums: &'a Sums,
    l: &'a Mat<f64>,
    poly: MatrixPolynomial,
    n: usize,
}

impl OrderModel<'_> {
    /// Physical poles in `band` (Hz), increasing frequency, their mode vectors if `vectors`,
    /// and every root of the denominator ([`OrderPoles::roots`]).
    fn poles(
        &self,
        dt: f64,
        band: [f64; 2],
        vectors: bool,
    ) -> (Vec<Complex64>, Vec<Vec<Complex64>>, Vec<Complex64>) {
        let Some(roots) = self.poly.roots() else {
            return (vec![], vec![], vec![]);
        };
        let (lo, hi) = (2.0 * PI * band[0], 2.0 * PI * band[1]);
        let mut kept: Vec<(Complex64, Complex64)> = roots
            .iter()
            .copied()
            .map(|x| (-x.ln() / dt, x))
            .filter(|(p, _)| p.im > 0.0 && p.re < 0.0 && p.norm() >= lo && p.norm() <= hi)
            .collect();
        kept.sort_by(|a, b| a.0.norm().total_cmp(&b.0.norm()));
        let vecs = if vectors {
            let xs: Vec<Complex64> = kept.iter().map(|(_, x)| *x).collect();
            self.mode_vectors(&xs)
        } else {
            vec![]
        };
        (kept.into_iter().map(|(p, _)| p).collect(), vecs, roots)
    }

    /// The mode vectors ψ_o(x_r) = B_o(x_r) v_r of the roots `xs` over every output at once.
    ///
    /// With θ_o = −R_n⁻¹ S_o,n α, ψ_o = −y_rᵀ S_o,n q_r where y_r = R_n⁻¹ [1, x_r, …, x_rⁿ]ᵀ and
    /// q_r = α v_r. As S_o,n[j, (b, l)] = s_ob(l − j), this is −Σ_b Σ_m s_ob(m) c_rb(m) with the
    /// cross-correlation c_rb(m) = Σ_j y_r,j q_r,(b, j+m), |m| ≤ n: one product of the lag
    /// sums (outputs × lags) with the correlations (lags × roots) serves every output and root.
    fn mode_vectors(&self, xs: &[Complex64]) -> Vec<Vec<Complex64>> {
        let (s, n) = (self.sums, self.n);
        let (ni, nmax, no, np) = (s.refs, s.n_max, s.outputs(), xs.len());
        let lags = 2 * n + 1;
        // y_r for every root: real and imaginary parts as 2 np right-hand sides.
        let mut y = Mat::from_fn(n + 1, 2 * np, |j, c| {
            let p = xs[c / 2].powu(j as u32);
            if c % 2 == 0 { p.re } else { p.im }
        });
        let ln = self.l.submatrix(0, 0, n + 1, n + 1);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            ln,
            y.as_mut(),
            faer::Par::Seq,
        );
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            ln.transpose(),
            y.as_mut(),
            faer::Par::Seq,
        );
        // Correlations c_rb(m) (rows b·lags + m + n), real and imaginary parts side by side.
        let mut corr = Mat::<f64>::zeros(ni * lags, 2 * np);
        for (r, &x) in xs.iter().enumerate() {
            let v = self.poly.null_vector(x);
            let yr: Vec<Complex64> = (0..=n)
                .map(|j| Complex64::new(y[(j, 2 * r)], y[(j, 2 * r + 1)]))
                .collect();
            for b in 0..ni {
                let q: Vec<Complex64> = (0..=n)
                    .map(|l| {
                        (0..ni)
                            .map(|c| {
                                let alpha = if l == n {
                                    if b == c { 1.0 } else { 0.0 }
                                } else {
                                    self.poly.coeffs[l][b * ni + c]
                                };
                                v[c] * alpha
                            })
                            .sum()
                    })
                    .collect();
                for j in 0..=n {
                    for l in 0..=n {
                        let c = yr[j] * q[l];
                        let row = b * lags + n + l - j;
                        corr[(row, 2 * r)] += c.re;
                        corr[(row, 2 * r + 1)] += c.im;
                    }
                }
            }
        }
        // Lag sums at |m| ≤ n, every output.
        let sums = Mat::from_fn(no, ni * lags, |o, col| {
            let (b, m) = (col / lags, col % lags);
            s.s[o * ni + b][nmax - n + m]
        });
        let psi = sums * &corr;
        (0..np)
            .map(|r| {
                (0..no)
                    .map(|o| -Complex64::new(psi[(o, 2 * r)], psi[(o, 2 * r + 1)]))
                    .collect()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Compressing many outputs into the eigenvectors of their Gram matrix leaves the reduced
    /// normal matrices unchanged (two references: Σ_o S_oᵀ R⁻¹ S_o computed directly).
    #[test]
    fn compression_is_exact() {
        let (n_max, ni, no): (usize, usize, usize) = (4, 2, 20);
        let lags = 2 * n_max + 1;
        let s: Vec<Vec<f64>> = (0..no * ni)
            .map(|c| {
                (0..lags)
                    .map(|q| ((c * 7 + q * 3) as f64).sin() + 0.1 * c as f64)
                    .collect()
            })
            .collect();
        let r: Vec<f64> = (0..lags)
            .map(|i| {
                let m = i.abs_diff(n_max);
                if m == 0 { 10.0 } else { 1.0 / (1.0 + m as f64) }
            })
            .collect();
        let sums = Sums {
            n_max,
            refs: ni,
            r: r[n_max..].to_vec(),
            t: vec![vec![100.0; lags]; ni * ni],
            s: s.clone(),
        };
        let rows: Vec<Vec<f64>> = s.chunks(ni).map(|c| c.concat()).collect();
        assert!(compress(&rows).is_some_and(|c| c.len() <= ni * lags));
        let full = reduce(&sums, &[4]).unwrap();
        let np1 = n_max + 1;
        let rm = Mat::from_fn(np1, np1, |j, l| r[n_max + j.abs_diff(l)]);
        let rinv = rm
            .llt(Side::Lower)
            .unwrap()
            .solve(Mat::<f64>::identity(np1, np1));
        let mut g = Mat::<f64>::zeros(ni * np1, ni * np1);
        for o in 0..no {
            let sm = Mat::from_fn(np1, ni * np1, |j, c| {
                let (b, l) = (c / np1, c % np1);
                s[o * ni + b][n_max + l - j]
            });
            g += sm.transpose() * &rinv * &sm;
        }
        let got = &full.cumulative[0].1;
        for j in 0..ni * np1 {
            for l in 0..ni * np1 {
                assert!(
                    (got[(j, l)] - g[(j, l)]).abs() < 1e-9 * g[(j, l)].abs().max(1.0),
                    "{j} {l}: {} vs {}",
                    got[(j, l)],
                    g[(j, l)]
                );
            }
        }
    }

    /// The FFT route gives the direct sums, for every lag and every pair of references.
    #[test]
    fn fft_sums_equal_direct_sums() {
        let freqs: Vec<f64> = (3..=200).map(|k| k as f64 * 0.5).collect();
        let curve = |o: f64| -> Vec<Complex64> {
            freqs
                .iter()
                .map(|f| Complex64::new((f + o).sin(), (0.3 * f * o).cos()))
                .collect()
        };
        let (h0, h1) = (curve(1.0), curve(2.0));
        let hi = 100.0;
        let omega_dt: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f / (2.0 * hi)).collect();
        let fft = LagSums::new(&freqs, hi, &omega_dt, 12);
        assert!(matches!(fft, LagSums::Fft { .. }));
        let direct = LagSums::Direct {
            powers: omega_dt
                .iter()
                .flat_map(|w| (0..=12).map(move |m| Complex64::from_polar(1.0, -w * m as f64)))
                .collect(),
        };
        let flat = |x: &Sums| -> Vec<f64> {
            x.r.iter()
                .chain(x.t.iter().flatten())
                .chain(x.s.iter().flatten())
                .copied()
                .collect()
        };
        // Two references: six sequences, three transforms; one curve: three sequences, the
        // last transformed alone.
        let two = [h0.as_slice(), h1.as_slice()];
        for (curves, refs) in [(&two[..], 2), (&two[..1], 1)] {
            let (a, b) = (
                lag_sums(curves, refs, &direct, 12),
                lag_sums(curves, refs, &fft, 12),
            );
            assert_eq!(flat(&a).len(), flat(&b).len());
            for (x, y) in flat(&a).iter().zip(&flat(&b)) {
                assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()), "{x} vs {y}");
            }
        }
    }

    /// With three outputs of two references each, t_ab(m) and s_ob(m) are the module docs'
    /// sums written out term by term: Re Σ_o Σ_k H̄_oa,k H_ob,k Ω_k^m and −Re Σ_k H_ob,k Ω_k^m.
    #[test]
    fn sums_over_outputs_follow_their_definition() {
        let freqs: Vec<f64> = (1..=300).map(|k| k as f64 * 0.25).collect();
        let hi = 75.0;
        let omega_dt: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f / (2.0 * hi)).collect();
        let curve = |c: f64| -> Vec<Complex64> {
            let value = |f: f64| Complex64::new((0.7 * f + c).sin(), (0.2 * f * c).cos() + c);
            freqs.iter().map(|&f| value(f)).collect()
        };
        let owned: Vec<Vec<Complex64>> = (0..6).map(|c| curve(c as f64)).collect();
        let curves: Vec<&[Complex64]> = owned.iter().map(|c| c.as_slice()).collect();
        let n_max = 8;
        let sums = lag_sums(
            &curves,
            2,
            &LagSums::new(&freqs, hi, &omega_dt, n_max),
            n_max,
        );
        let lag = |y: &dyn Fn(usize) -> Complex64, m: i64| -> f64 {
            let terms = omega_dt.iter().enumerate();
            terms
                .map(|(k, w)| (y(k) * Complex64::from_polar(1.0, -w * m as f64)).re)
                .sum()
        };
        let close = |x: f64, y: f64| (x - y).abs() < 1e-9 * (1.0 + y.abs());
        for m in -(n_max as i64)..=n_max as i64 {
            let at = (m + n_max as i64) as usize;
            for (a, b) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                let product = |k: usize| -> Complex64 {
                    (0..3)
                        .map(|o| curves[2 * o + a][k].conj() * curves[2 * o + b][k])
                        .sum()
                };
                let expected = lag(&product, m);
                assert!(close(sums.t[2 * a + b][at], expected), "t_{a}{b}({m})");
            }
            for (c, h) in curves.iter().enumerate() {
                assert!(close(sums.s[c][at], lag(&|k| -h[k], m)), "s_{c}({m})");
            }
        }
    }

    /// Two exact modes, no noise: an over-specified model (order 16; a continuous-time FRF is
    /// not exactly rational in Ω, so the minimal order 4 is biased by 0.1 %) has poles within
    /// 1e-5 of the truth and mode vectors parallel to the residues.
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
        let out = lscf(&freqs, &refs, &LscfSettings::new([0.0, 40.0], (16, 16, 2))).unwrap();
        for (r, q) in poles.iter().enumerate() {
            let k = (0..out[0].poles.len())
                .min_by(|&a, &b| {
                    (out[0].poles[a] - q)
                        .norm()
                        .total_cmp(&(out[0].poles[b] - q).norm())
                })
                .unwrap();
            let p = out[0].poles[k];
            assert!(
                (p - q).norm() / q.norm() < 1e-5,
                "{p} vs {q}: {:?}",
                out[0].poles
            );
            // The mode vector is parallel to the residues over the outputs.
            let residues: Vec<Complex64> = (0..3)
                .map(|o| Complex64::new(0.0, 1.0 + o as f64 + r as f64))
                .collect();
            let m = crate::shapes::mac(&out[0].vectors[k], &residues);
            assert!(m > 1.0 - 1e-8, "MAC {m}");
        }
    }
}
