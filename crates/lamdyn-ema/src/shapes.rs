//! Mode-shape indicators: MAC, MPC, MPD, complex-to-real conversion, CMIF.
//!
//! - MAC(a, b) = |aᴴb|² / ((aᴴa)(bᴴb)) [Allemang & Brown 1982].
//! - MPC = ((s_xx − s_yy)² + 4 s_xy²) / (s_xx + s_yy)² with s_xx = ReᵀRe, s_yy = ImᵀIm,
//!   s_xy = ReᵀIm: 1 for a vector whose components are collinear in the complex plane (a real
//!   mode), 0 for a circular one [Pappa et al. 1993].
//! - MPD: the amplitude-weighted mean angle (degrees) between each component and the principal
//!   direction θ₀ of the components in the complex plane (the major axis of [s_xx s_xy; s_xy
//!   s_yy]); 0 for a real mode.
//! - Real mode: the components rotated by −θ₀, real parts kept.
//! - CMIF: per line, the singular values of the responses × references FRF matrix, largest
//!   first [Shih et al. 1988]; with one reference, the 2-norm of the FRF column.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// `v` times the power of two that brings its largest magnitude into [1, 2): the indicators'
/// sums of fourth powers neither underflow nor overflow whatever the shapes' units (a residue
/// of 1e-108 squares twice to nothing), and a power of two changes no bit of a ratio.
fn unit_scaled(v: &[Complex64]) -> Vec<Complex64> {
    let scale = to_unit(v.iter().map(|z| z.norm()).fold(0.0, f64::max));
    v.iter().map(|z| z * scale).collect()
}

/// The power of two that brings `largest` into [1, 2); 1 for 0 or a value that is not finite.
/// Scaling by it is exact: no bit of a ratio, a pole or an angle changes.
pub(crate) fn to_unit(largest: f64) -> f64 {
    if largest == 0.0 || !largest.is_finite() {
        return 1.0;
    }
    2f64.powi(-(largest.log2().floor() as i32))
}

/// Modal assurance criterion.
pub fn mac(a: &[Complex64], b: &[Complex64]) -> f64 {
    let (a, b) = (&unit_scaled(a), &unit_scaled(b));
    let ab: Complex64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(Complex64::norm_sqr).sum();
    let bb: f64 = b.iter().map(Complex64::norm_sqr).sum();
    ab.norm_sqr() / (aa * bb).max(f64::MIN_POSITIVE)
}

/// (s_xx, s_yy, s_xy) of `v` at a unit scale ([`unit_scaled`]).
fn moments(v: &[Complex64]) -> (f64, f64, f64) {
    unit_scaled(v).iter().fold((0.0, 0.0, 0.0), |(a, b, c), z| {
        (a + z.re * z.re, b + z.im * z.im, c + z.re * z.im)
    })
}

/// Principal angle θ₀ of the components in the complex plane.
fn principal_angle(v: &[Complex64]) -> f64 {
    let (sxx, syy, sxy) = moments(v);
    0.5 * (2.0 * sxy).atan2(sxx - syy)
}

/// Modal phase collinearity.
pub fn mpc(v: &[Complex64]) -> f64 {
    let (sxx, syy, sxy) = moments(v);
    let d = (sxx + syy).powi(2);
    if d == 0.0 {
        0.0
    } else {
        ((sxx - syy).powi(2) + 4.0 * sxy * sxy) / d
    }
}

/// Mean phase deviation, degrees.
pub fn mpd(v: &[Complex64]) -> f64 {
    let t = principal_angle(v);
    let (mut num, mut den) = (0.0, 0.0);
    for z in v {
        let r = z * Complex64::from_polar(1.0, -t);
        // Angle to the line (either direction along it).
        let dev = r.im.atan2(r.re.abs()).abs();
        num += z.norm() * dev;
        den += z.norm();
    }
    if den == 0.0 {
        0.0
    } else {
        (num / den).to_degrees()
    }
}

/// The real mode closest to a complex one: rotated by −θ₀, real parts.
pub fn real_mode(v: &[Complex64]) -> Vec<f64> {
    let rot = Complex64::from_polar(1.0, -principal_angle(v));
    v.iter().map(|z| (z * rot).re).collect()
}

/// The indices of a row-major `rows` × `cols` matrix's entries in the row-major order of its
/// transpose (column by column of the original).
pub(crate) fn transposed_indices(rows: usize, cols: usize) -> impl Iterator<Item = usize> {
    (0..cols).flat_map(move |j| (0..rows).map(move |i| i * cols + j))
}

/// Participation factors of a mode ([`crate::identify::Mode::participation`]): the dominant
/// right singular vector of its residue matrix R (`nr` responses × `nf` references, `residues`
/// row-major), by power iteration on RᴴR, scaled to 1 at its largest entry.
pub(crate) fn participation(residues: &[Complex64], nr: usize, nf: usize) -> Vec<Complex64> {
    let res = |i: usize, j: usize| residues[i * nf + j];
    let mut g = vec![Complex64::new(0.0, 0.0); nf * nf];
    for a in 0..nf {
        for b in 0..nf {
            g[a * nf + b] = (0..nr).map(|i| res(i, a).conj() * res(i, b)).sum();
        }
    }
    let mut v = vec![Complex64::new(1.0, 0.0); nf];
    for _ in 0..100 {
        let w: Vec<Complex64> = (0..nf)
            .map(|a| (0..nf).map(|b| g[a * nf + b] * v[b]).sum())
            .collect();
        let norm = w.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
        if norm == 0.0 {
            break;
        }
        v = w.iter().map(|z| z / norm).collect();
    }
    let big = v
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or(Complex64::new(1.0, 0.0));
    v.iter().map(|z| z / big).collect()
}

/// CMIF values of one line: the min(n_resp, n_ref) singular values of the n_resp × n_ref matrix
/// `h` (row-major), largest first. The Gram matrix is taken on the smaller side: with one response
/// and nine references (a roving hammer) there is one singular value, not nine of which eight
/// are rounding.
pub fn cmif_line(h: &[Complex64], n_ref: usize) -> Vec<f64> {
    let n_resp = h.len() / n_ref.max(1);
    if n_ref == 1 || n_resp == 1 {
        return vec![h.iter().map(Complex64::norm_sqr).sum::<f64>().sqrt()];
    }
    if n_resp < n_ref {
        let transposed: Vec<Complex64> = transposed_indices(n_resp, n_ref).map(|k| h[k]).collect();
        return cmif_line(&transposed, n_resp);
    }
    let g = faer::Mat::<faer::c64>::from_fn(n_ref, n_ref, |a, b| {
        let s: Complex64 = (0..n_resp)
            .map(|i| h[i * n_ref + a].conj() * h[i * n_ref + b])
            .sum();
        faer::c64::new(s.re, s.im)
    });
    let mut ev: Vec<f64> = g
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .map(|v| v.into_iter().map(|x| x.max(0.0).sqrt()).collect())
        .unwrap_or_default();
    ev.sort_by(|a, b| b.total_cmp(a));
    ev
}

/// A CMIF peak.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CmifPeak {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// First singular value there.
    pub value: f64,
}

/// Local maxima of the first CMIF curve whose topographic prominence, as a ratio, is at least
/// `prominence`: for a peak σ_k the base on each side is the lowest value between it and the
/// nearest higher point on that side (or the band's end), and the peak is kept when
/// σ_k ≥ prominence · max(base_left, base_right) — the definition of
/// `scipy.signal.peak_prominences` taken on log σ. A ripple on a resonance's flank has a base just
/// below it and is dropped, however many local maxima noise puts there; a resonance's own base is
/// the trough to the next higher peak. A plateau counts once, at its first line.
pub fn cmif_peaks(freqs_hz: &[f64], first: &[f64], prominence: f64) -> Vec<CmifPeak> {
    let n = first.len();
    let left = bases(first.iter().copied());
    let mut right = bases(first.iter().rev().copied());
    right.reverse();
    (1..n.saturating_sub(1))
        .filter(|&k| first[k] > first[k - 1] && first[k] >= first[k + 1])
        .filter(|&k| first[k] >= prominence * left[k].max(right[k]))
        .map(|k| CmifPeak {
            freq_hz: freqs_hz[k],
            value: first[k],
        })
        .collect()
}

/// For each value v_k of `values`: the lowest value between it and the nearest earlier value
/// above it (or the start), v_k excluded; +∞ where there is none between. One pass with a
/// stack of the values not yet exceeded, each with the lowest value since the one below it.
fn bases(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut stack: Vec<(f64, f64)> = Vec::new();
    values
        .map(|v| {
            let mut low = f64::INFINITY;
            while let Some(&(top, since)) = stack.last() {
                if top > v || top.is_nan() || v.is_nan() {
                    break;
                }
                low = low.min(since);
                stack.pop();
            }
            stack.push((v, low.min(v)));
            low
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indicators_of_real_and_complex_vectors() {
        let real: Vec<Complex64> = [1.0, -2.0, 0.5]
            .iter()
            .map(|x| Complex64::from_polar(*x, 0.7))
            .collect();
        assert!((mpc(&real) - 1.0).abs() < 1e-12 && mpd(&real) < 1e-9);
        let r = real_mode(&real);
        assert!((r[1] / r[0] + 2.0).abs() < 1e-12);
        let circ = [Complex64::new(1.0, 0.0), Complex64::new(0.0, 1.0)];
        assert!(mpc(&circ) < 1e-12);
        assert!((mac(&real, &real) - 1.0).abs() < 1e-12);
        let other = [
            Complex64::new(1.0, 0.0),
            Complex64::new(0.5, 0.0),
            Complex64::new(0.0, 0.0),
        ];
        assert!(mac(&real, &other) < 1.0);
    }

    /// H = 3 u₁v₁ᴴ + 0.5 u₂v₂ᴴ with orthonormal u (two responses) and v (three references): the
    /// CMIF is [3, 0.5], two values and not three, for H and for Hᵀ (three responses, two
    /// references); a single response's one value is the row's norm.
    #[test]
    fn cmif_has_as_many_values_as_the_smaller_side() {
        let c = |re: f64, im: f64| Complex64::new(re, im);
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let u = [[c(1.0, 0.0), c(0.0, 0.0)], [c(0.0, 0.0), c(0.0, 1.0)]];
        let v = [
            [c(r, 0.0), c(0.0, r), c(0.0, 0.0)],
            [c(0.0, 0.0), c(0.0, 0.0), c(1.0, 0.0)],
        ];
        let h: Vec<Complex64> = (0..6)
            .map(|k| {
                let (i, j) = (k / 3, k % 3);
                3.0 * u[0][i] * v[0][j].conj() + 0.5 * u[1][i] * v[1][j].conj()
            })
            .collect();
        let transposed: Vec<Complex64> = (0..6).map(|k| h[(k % 2) * 3 + k / 2]).collect();
        for sigma in [cmif_line(&h, 3), cmif_line(&transposed, 2)] {
            assert_eq!(sigma.len(), 2);
            assert!((sigma[0] - 3.0).abs() < 1e-12 && (sigma[1] - 0.5).abs() < 1e-12);
        }
        let row = [c(3.0, 4.0), c(0.0, 12.0)];
        assert_eq!(cmif_line(&row, 2), vec![13.0]);
    }

    /// Two resonances (|1/(1 − (f/f_r)² + iη)|) with a 5 % ripple of period 2 Hz on them: the
    /// ripple's many local maxima go, the two resonances stay, the higher one's base being the
    /// edge of the band and the lower one's the trough between them.
    #[test]
    fn cmif_peaks_keep_resonances_and_drop_ripple() {
        let f: Vec<f64> = (0..4000).map(|k| 1.0 + 0.1 * f64::from(k)).collect();
        let sigma: Vec<f64> = f
            .iter()
            .map(|&f| {
                let r = |fr: f64, eta: f64| {
                    let x = 1.0 - (f / fr).powi(2);
                    1.0 / x.hypot(eta)
                };
                (r(100.0, 0.02) + 0.3 * r(250.0, 0.03))
                    * (1.0 + 0.05 * (std::f64::consts::PI * f).sin())
            })
            .collect();
        let maxima = (1..f.len() - 1)
            .filter(|&k| sigma[k] > sigma[k - 1] && sigma[k] >= sigma[k + 1])
            .count();
        assert!(maxima > 100, "{maxima}");
        let peaks = cmif_peaks(&f, &sigma, 2.0);
        let at: Vec<f64> = peaks.iter().map(|p| p.freq_hz).collect();
        assert_eq!(at.len(), 2, "{at:?}");
        assert!(
            (at[0] - 100.0).abs() < 0.5 && (at[1] - 250.0).abs() < 0.5,
            "{at:?}"
        );
        // A higher threshold than the weaker resonance's prominence keeps the stronger one.
        let lower = peaks[1].value / sigma[990..2490].iter().cloned().fold(f64::MAX, f64::min);
        assert_eq!(cmif_peaks(&f, &sigma, 1.01 * lower).len(), 1);
    }

    /// The one-pass bases equal their definition, scanned line by line from each value, on
    /// values with repeats, plateaus and a NaN.
    #[test]
    fn bases_equal_the_scan_of_their_definition() {
        let mut v: Vec<f64> = (0..500u64)
            .map(|k| ((k * 7919 % 101) as f64 / 10.0).floor())
            .collect();
        v[250] = f64::NAN;
        let by_scan = |k: usize| {
            (0..k)
                .rev()
                .take_while(|&j| v[j] <= v[k])
                .map(|j| v[j])
                .fold(f64::INFINITY, f64::min)
        };
        let fast = bases(v.iter().copied());
        for k in 0..v.len() {
            assert_eq!(fast[k].to_bits(), by_scan(k).to_bits(), "line {k}");
        }
    }
}
