//! Each curve's noise level, estimated from the curve alone, line to line.
//!
//! A curve sampled finely enough to show its resonances is smooth from one line to the next:
//! the second difference d_k = H_{k−1} − 2H_k + H_{k+1} holds little of the FRF itself and
//! six times the variance of white noise in each of its real and imaginary parts. The median
//! of |d| over the lines is robust to the few lines where the FRF curves sharply (peaks
//! narrower than a few lines), so
//!
//!   σ̂ = median(|Re d_k|, |Im d_k|) / (0.6745 √6)
//!
//! (0.6745: the median of |x| for a standard normal x [Donoho & Johnstone 1994]). It errs
//! high by the FRF's own curvature, the more the quieter the curve; on noise-free curves σ̂ is
//! that curvature alone, small but not zero.

use num_complex::Complex64;

/// The fewest consecutive line triples an estimate is made from.
pub const MIN_TRIPLES: usize = 8;

/// σ̂² (module docs) of `curve` over the consecutive line triples of `lines` (indices into the
/// curve, in increasing order); None with fewer than [`MIN_TRIPLES`] triples or where σ̂² is
/// not finite.
pub fn line_noise_variance(curve: &[Complex64], lines: &[usize]) -> Option<f64> {
    // |x| as its bits: for floats without sign the integers' order is the numbers' (NaN last,
    // as f64::total_cmp), and integers select faster.
    let mut magnitudes: Vec<u64> = lines
        .windows(3)
        .filter(|w| w[1] == w[0] + 1 && w[2] == w[1] + 1)
        .flat_map(|w| {
            let d = curve[w[0]] - 2.0 * curve[w[1]] + curve[w[2]];
            [d.re.abs().to_bits(), d.im.abs().to_bits()]
        })
        .collect();
    if magnitudes.len() < 2 * MIN_TRIPLES {
        return None;
    }
    let mid = magnitudes.len() / 2;
    let (_, median, _) = magnitudes.select_nth_unstable(mid);
    let sigma = f64::from_bits(*median) / 0.674_489_75;
    let variance = sigma * sigma / 6.0;
    variance.is_finite().then_some(variance)
}

/// Each curve's σ̂² ([`line_noise_variance`]) over the same lines, estimated once for every
/// step that weighs the curves by their noise (the refinement's check, the second-shape test).
#[derive(Debug, Clone, PartialEq)]
pub struct CurveNoise {
    variances: Vec<Option<f64>>,
}

impl CurveNoise {
    /// The estimates of `curves` over `lines` (indices into each curve, increasing), the curves
    /// in parallel.
    pub fn of(curves: &[&[Complex64]], lines: &[usize]) -> Self {
        use rayon::prelude::*;
        Self {
            variances: curves
                .par_iter()
                .map(|c| line_noise_variance(c, lines))
                .collect(),
        }
    }

    /// Curve `o`'s σ̂²; None without an estimate (or past the curves).
    pub fn variance(&self, o: usize) -> Option<f64> {
        self.variances.get(o).copied().flatten()
    }

    /// Weights that make every curve's noise alike: √(mean σ̂²)/σ̂ of each curve, the mean over
    /// the curves, so that every weighted curve's noise variance is about the mean σ̂². σ̂² is
    /// floored at 1e-12 of the largest (a curve of zeros or of exact values does not take an
    /// unbounded weight). All ones where any curve has no estimate or every σ̂² is zero.
    pub fn weights(&self) -> Vec<f64> {
        let Some(floored) = self.floored_variances() else {
            return vec![1.0; self.variances.len()];
        };
        let mean = floored.iter().sum::<f64>() / floored.len() as f64;
        floored.iter().map(|v| (mean / v).sqrt()).collect()
    }

    /// The noise variance of each part (real, imaginary) of every curve weighted by
    /// [`Self::weights`]: the mean σ̂²; None where the weights are all ones for want of
    /// estimates.
    pub fn weighted_variance(&self) -> Option<f64> {
        let floored = self.floored_variances()?;
        Some(floored.iter().sum::<f64>() / floored.len() as f64)
    }

    /// Every curve's σ̂² floored at 1e-12 of the largest; None where a curve has no estimate
    /// or every σ̂² is zero.
    fn floored_variances(&self) -> Option<Vec<f64>> {
        let variances = self
            .variances
            .iter()
            .copied()
            .collect::<Option<Vec<f64>>>()?;
        let largest = variances.iter().copied().fold(0.0, f64::max);
        (largest > 0.0).then(|| variances.iter().map(|v| v.max(1e-12 * largest)).collect())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use lamdyn_fit::synthetic::Normal;
    use std::f64::consts::PI;

    /// Standard complex normal numbers (each part of unit variance), seeded: the project's
    /// generator ([`lamdyn_fit::synthetic::Normal`]).
    pub(crate) fn gaussian_sequence(seed: u64) -> impl FnMut() -> Complex64 {
        let mut normal = Normal::new(seed);
        move || Complex64::new(normal.sample(), normal.sample())
    }

    /// A two-mode accelerance on 0.1 Hz lines (0.1–250 Hz) plus complex white noise of standard
    /// deviation `sigma` in each part.
    fn noisy_curve(sigma: f64, zeta: f64, seed: u64) -> Vec<Complex64> {
        let mut noise = gaussian_sequence(seed);
        (1..=2500)
            .map(|k| {
                let w = 2.0 * PI * 0.1 * f64::from(k);
                let mode = |f: f64| {
                    let wr = 2.0 * PI * f;
                    -w * w / Complex64::new(wr * wr - w * w, 2.0 * zeta * wr * w)
                };
                mode(40.0) + 0.5 * mode(130.0) + sigma * noise()
            })
            .collect()
    }

    #[test]
    fn the_noise_of_a_damped_curve_is_found() {
        let lines: Vec<usize> = (0..2500).collect();
        // 2 % damping: the peaks span 16 and 52 lines. The median of the 5000 overlapping
        // second differences scatters by 2.1 % (1σ, 200 seeds); the FRF's own curvature adds a
        // bias that grows as the noise falls (measured: +1.8, +2.9, +12.5 % at σ = 0.1, 0.01,
        // 0.001 of the curve's level).
        for (sigma, bias) in [(0.1, 0.05), (1e-2, 0.08), (1e-3, 0.15)] {
            let got = line_noise_variance(&noisy_curve(sigma, 0.02, 7), &lines).unwrap();
            let ratio = got.sqrt() / sigma;
            assert!(
                ratio > 0.95 && ratio < 1.0 + bias,
                "σ {sigma}: ratio {ratio}"
            );
        }
    }

    #[test]
    fn sharp_peaks_do_not_carry_the_estimate() {
        // 0.1 % damping: each peak is narrower than a line, and its lines' second differences
        // are up to thousands of σ; they shift the median by 7.4 %.
        let lines: Vec<usize> = (0..2500).collect();
        let got = line_noise_variance(&noisy_curve(1e-2, 0.001, 3), &lines).unwrap();
        let ratio = got.sqrt() / 1e-2;
        assert!(ratio > 0.95 && ratio < 1.1, "ratio {ratio}");
    }

    #[test]
    fn weights_equalise_the_curves_noise() {
        // Noise where σ̂ is the noise's, not the curve's curvature (at 0.001 of the level it is
        // 12.5 % high: the_noise_of_a_damped_curve_is_found).
        let (quiet, loud) = (noisy_curve(1e-2, 0.02, 1), noisy_curve(4e-2, 0.02, 2));
        let lines: Vec<usize> = (0..2500).collect();
        let w = CurveNoise::of(&[&quiet, &loud], &lines).weights();
        assert!((w[0] / w[1] / 4.0 - 1.0).abs() < 0.08, "{w:?}");
        // Scaling a curve scales its weight inversely.
        let scaled: Vec<Complex64> = loud.iter().map(|h| h * 1000.0).collect();
        let ws = CurveNoise::of(&[&quiet, &scaled], &lines).weights();
        assert!((ws[0] / ws[1] / (w[0] / w[1]) / 1000.0 - 1.0).abs() < 1e-9);
        // Weighted, each curve's noise variance per part is the mean σ̂²: (1e-4 + 16e-4) / 2.
        let noise = CurveNoise::of(&[&quiet, &loud], &lines);
        let v = noise.weighted_variance().unwrap();
        assert!((v / 8.5e-4 - 1.0).abs() < 0.1, "{v}");
        for (o, w) in w.iter().enumerate() {
            let weighted = noise.variance(o).unwrap() * w * w;
            assert!((weighted / v - 1.0).abs() < 1e-12, "{weighted} against {v}");
        }
    }

    #[test]
    fn too_few_lines_or_a_zero_curve_leave_the_weights_alike() {
        let curve = noisy_curve(1e-3, 0.02, 1);
        let gappy: Vec<usize> = (0..2500).step_by(2).collect();
        assert_eq!(line_noise_variance(&curve, &gappy), None);
        assert_eq!(
            CurveNoise::of(&[&curve, &curve], &gappy).weights(),
            vec![1.0, 1.0]
        );
        let zeros = vec![Complex64::new(0.0, 0.0); 2500];
        let lines: Vec<usize> = (0..2500).collect();
        assert_eq!(
            CurveNoise::of(&[&zeros, &zeros], &lines).weights(),
            vec![1.0, 1.0]
        );
        let w = CurveNoise::of(&[&curve, &zeros], &lines).weights();
        assert!(w.iter().all(|x| x.is_finite() && *x > 0.0), "{w:?}");
    }
}
