//! The lines of a band, edges included with a relative slack of [`EDGE_SLACK`]: a frequency
//! axis computed from a printed time step (0.4999999999999526 Hz for 0.5 Hz) must select the
//! same lines as the exact one, since one line more or less at an edge moves a pole near it.

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
