//! FRFs of known modes for the unit tests: the modal model the identification fits.

use num_complex::Complex64;
use std::f64::consts::PI;

/// The pole of a mode at `f` Hz with damping ratio `z`, rad/s.
pub(crate) fn pole(f: f64, z: f64) -> Complex64 {
    let w = 2.0 * PI * f;
    Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
}

/// Accelerance of modes (f, ζ, shape over the curves) at the lines: the modal model of
/// the band's fit with A = φφ_p/(2iω_d), driving point p = curve 0.
pub(crate) fn accelerances(freqs: &[f64], modes: &[(f64, f64, Vec<f64>)]) -> Vec<Vec<Complex64>> {
    let curves = modes[0].2.len();
    let poles: Vec<(f64, f64)> = modes.iter().map(|(f, z, _)| (*f, *z)).collect();
    (0..curves)
        .map(|o| accelerance(freqs, &poles, |r| modes[r].2[o] * modes[r].2[0]))
        .collect()
}

/// One accelerance curve of modes (f, ζ) at the lines, mode r's residue φφ(r)/(2iω_d) with
/// φφ(r) = `shape_product(r)`.
pub(crate) fn accelerance(
    freqs: &[f64],
    modes: &[(f64, f64)],
    shape_product: impl Fn(usize) -> f64,
) -> Vec<Complex64> {
    freqs
        .iter()
        .map(|&f| {
            let s = Complex64::new(0.0, 2.0 * PI * f);
            modes
                .iter()
                .enumerate()
                .map(|(r, &(fr, z))| {
                    let p = pole(fr, z);
                    let a = shape_product(r) / Complex64::new(0.0, 2.0 * p.im);
                    s * s * (a / (s - p) + a.conj() / (s - p.conj()))
                })
                .sum()
        })
        .collect()
}
