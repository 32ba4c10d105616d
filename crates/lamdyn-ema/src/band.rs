//! The lines of a band, edges included with a relative slack of [`EDGE_SLACK`]: a frequency
//! axis computed from a printed time step (0.4999999999999526 Hz for 0.5 Hz) must select the
//! same lines as the exact one, since one line more or less at an edge moves a pole near it.
//! And the pseudo-modes that stand for the modes above a band in the refinement's models
//! (`pseudo_modes_above`).

use num_complex::Complex64;
use std::f64::consts::PI;

/// Relative slack at the band's edges.
pub const EDGE_SLACK: f64 = 1e-9;

/// Indices of the lines f_k with lo(1 − ε) ≤ f_k ≤ hi(1 + ε), ε = [`EDGE_SLACK`].
pub fn lines(freqs_hz: &[f64], [lo, hi]: [f64; 2]) -> Vec<usize> {
    let (lo, hi) = (lo * (1.0 - EDGE_SLACK), hi * (1.0 + EDGE_SLACK));
    (0..freqs_hz.len())
        .filter(|&k| freqs_hz[k] >= lo && freqs_hz[k] <= hi)
        .collect()
}

/// [`lines`] without the 0 Hz line (or any non-positive one).
pub fn positive_lines(freqs_hz: &[f64], band_hz: [f64; 2]) -> Vec<usize> {
    let mut out = lines(freqs_hz, band_hz);
    out.retain(|&k| freqs_hz[k] > 0.0);
    out
}

/// The spacing of the first two of `lines` (Hz), 0 with fewer: the line spacing of a uniform
/// frequency axis.
pub fn line_spacing(freqs_hz: &[f64], lines: &[usize]) -> f64 {
    match lines {
        [a, b, ..] => (freqs_hz[*b] - freqs_hz[*a]).abs(),
        _ => 0.0,
    }
}

/// The multiples of the band's upper edge at which [`pseudo_modes_above`] puts its poles.
const PSEUDO_RATIOS: [f64; 4] = [1.1, 1.3, 1.7, 2.3];

/// The damping ratio of the pseudo-modes ([`PSEUDO_RATIOS`]).
const PSEUDO_DAMPING: f64 = 0.1;

/// The poles (rad/s) of the pseudo-modes above a band whose upper edge is `upper_hz`: at
/// [`PSEUDO_RATIOS`] times it, with damping [`PSEUDO_DAMPING`]. Held fixed with free residues
/// in a refinement's model, they stand for the modes above the band, knowing nothing of the
/// part: the tails of damped modes just above it, which the upper residual alone does not
/// follow and a free pole would otherwise leave its column to take (docs/ema.md, "Damped
/// poles").
pub(crate) fn pseudo_modes_above(upper_hz: f64) -> Vec<Complex64> {
    PSEUDO_RATIOS
        .iter()
        .map(|r| {
            let w = 2.0 * PI * r * upper_hz;
            let z = PSEUDO_DAMPING;
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rounded_axis_selects_the_exact_axis_lines() {
        let exact: Vec<f64> = (0..2000).map(|k| 0.5 * f64::from(k)).collect();
        let rounded: Vec<f64> = (0..2000)
            .map(|k| f64::from(k) * (25_600.0 * (1.0 - 9.5e-14)) / 51_200.0)
            .collect();
        assert!(rounded[120] < 60.0);
        assert_eq!(lines(&exact, [60.0, 500.0]), lines(&rounded, [60.0, 500.0]));
        assert_eq!(lines(&exact, [60.0, 500.0]).len(), 881);
        // A line a hundredth of a line outside stays out.
        assert_eq!(lines(&exact, [60.005, 499.995]).len(), 879);
    }
}
