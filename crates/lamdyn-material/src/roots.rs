//! Roots of complex polynomials of low degree (Aberth–Ehrlich iteration with Newton polishing).

use num_complex::Complex64;

/// All roots of the polynomial with coefficients `coeffs` (highest degree first, leading
/// coefficient non-zero), by the Aberth–Ehrlich simultaneous iteration [Aberth 1973].
///
/// # Panics
/// If fewer than two coefficients are given or the leading one is zero (programming errors).
pub fn polynomial_roots(coeffs: &[Complex64]) -> Vec<Complex64> {
    assert!(
        coeffs.len() >= 2,
        "expected a polynomial of degree >= 1, got {} coefficients",
        coeffs.len()
    );
    assert!(
        coeffs[0].norm() > 0.0,
        "expected a non-zero leading coefficient"
    );
    let n = coeffs.len() - 1;
    let lead = coeffs[0];
    let monic: Vec<Complex64> = coeffs.iter().map(|c| c / lead).collect();
    // Start on a circle of the Cauchy bound radius, rotated off the axes.
    let radius = 1.0 + monic[1..].iter().map(|c| c.norm()).fold(0.0, f64::max);
    let mut z: Vec<Complex64> = (0..n)
        .map(|k| {
            Complex64::from_polar(
                0.5 * radius,
                0.4 + 2.0 * std::f64::consts::PI * k as f64 / n as f64,
            )
        })
        .collect();
    for _ in 0..500 {
        let mut max_step: f64 = 0.0;
        for i in 0..n {
            let (p, dp) = eval(&monic, z[i]);
            if p.norm() == 0.0 {
                continue;
            }
            let ratio = p / dp;
            let repulsion: Complex64 = (0..n)
                .filter(|&j| j != i)
                .map(|j| 1.0 / (z[i] - z[j]))
                .sum();
            let step = ratio / (1.0 - ratio * repulsion);
            z[i] -= step;
            max_step = max_step.max(step.norm() / z[i].norm().max(f64::MIN_POSITIVE));
        }
        if max_step < 1e-15 {
            break;
        }
    }
    // Two Newton steps on the original polynomial remove the last rounding of the iteration.
    for zi in &mut z {
        for _ in 0..2 {
            let (p, dp) = eval(&monic, *zi);
            if dp.norm() > 0.0 {
                *zi -= p / dp;
            }
        }
    }
    z
}

/// p(z) and p'(z) by Horner's scheme.
fn eval(coeffs: &[Complex64], z: Complex64) -> (Complex64, Complex64) {
    let mut p = Complex64::new(0.0, 0.0);
    let mut dp = Complex64::new(0.0, 0.0);
    for c in coeffs {
        dp = dp * z + p;
        p = p * z + c;
    }
    (p, dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_with_known_roots() {
        let r = [
            Complex64::new(2.0, 0.1),
            Complex64::new(-3.0, 0.0),
            Complex64::new(0.5, -7.0),
        ];
        // (z - r0)(z - r1)(z - r2)
        let c = [
            Complex64::new(1.0, 0.0),
            -(r[0] + r[1] + r[2]),
            r[0] * r[1] + r[0] * r[2] + r[1] * r[2],
            -r[0] * r[1] * r[2],
        ];
        let found = polynomial_roots(&c);
        for want in r {
            let best = found
                .iter()
                .map(|z| (z - want).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(best < 1e-13 * want.norm(), "root {want} missed by {best}");
        }
    }
}
