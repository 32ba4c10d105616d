//! Cubic spline interpolation with not-a-knot ends and linear extrapolation, for the per-mode
//! law (ln E' and ln η against ln f between the modal frequencies).
//!
//! With knots x₀ < … < x_{n−1}, values y_i, widths h_i = x_{i+1} − x_i and second derivatives
//! M_i, the spline on [x_i, x_{i+1}] with t = x − x_i is [de Boor, *A Practical Guide to
//! Splines*, ch. IV]
//!
//! s(x) = y_i + b_i t + M_i t²/2 + (M_{i+1} − M_i) t³/(6 h_i),
//! b_i = (y_{i+1} − y_i)/h_i − h_i (2 M_i + M_{i+1})/6,
//!
//! where continuity of s' at the interior knots gives
//!
//! h_{i−1} M_{i−1} + 2 (h_{i−1} + h_i) M_i + h_i M_{i+1}
//!     = 6 [(y_{i+1} − y_i)/h_i − (y_i − y_{i−1})/h_{i−1}],   i = 1 … n−2,
//!
//! and not-a-knot ends (s''' continuous at x₁ and x_{n−2}) close the system:
//! h₁ M₀ − (h₀ + h₁) M₁ + h₀ M₂ = 0 and its mirror. Not-a-knot reproduces cubics exactly
//! and has O(h⁴) error for smooth data; a natural spline (M₀ = M_{n−1} = 0) would force a
//! straight end segment and O(h²) error there. Fewer than four knots: the interpolating
//! polynomial (constant, line, parabola). Outside [x₀, x_{n−1}] the spline continues as the
//! tangent line at the end knot, so that the per-mode law stays tame at the band edges.

use faer::Mat;
use faer::prelude::Solve;

/// An interpolating cubic spline (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Spline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl Spline {
    /// The spline through (x_i, y_i).
    ///
    /// # Panics
    /// If `x` is empty, not strictly increasing, or not as long as `y` (callers pass the
    /// validated, sorted anchor frequencies).
    pub fn new(x: &[f64], y: &[f64]) -> Self {
        assert!(
            !x.is_empty() && x.len() == y.len() && x.windows(2).all(|w| w[1] > w[0]),
            "spline knots must be non-empty, increasing and match the values"
        );
        let m = match x.len() {
            0..=2 => vec![0.0; x.len()],
            3 => vec![parabola_curvature(x, y); 3],
            _ => not_a_knot_curvatures(x, y),
        };
        Self {
            x: x.to_vec(),
            y: y.to_vec(),
            m,
        }
    }

    /// s(x), with tangent-line extrapolation.
    pub fn eval(&self, x: f64) -> f64 {
        let n = self.x.len();
        if n == 1 {
            return self.y[0];
        }
        if x <= self.x[0] {
            return self.y[0] + self.slope_at_start() * (x - self.x[0]);
        }
        if x >= self.x[n - 1] {
            return self.y[n - 1] + self.slope_at_end() * (x - self.x[n - 1]);
        }
        let i = (self.x.partition_point(|k| *k <= x) - 1).min(n - 2);
        let (h, t) = (self.x[i + 1] - self.x[i], x - self.x[i]);
        self.y[i]
            + self.b(i) * t
            + self.m[i] * t * t / 2.0
            + (self.m[i + 1] - self.m[i]) * t * t * t / (6.0 * h)
    }

    /// b_i, the slope at the left end of interval i.
    fn b(&self, i: usize) -> f64 {
        let h = self.x[i + 1] - self.x[i];
        (self.y[i + 1] - self.y[i]) / h - h * (2.0 * self.m[i] + self.m[i + 1]) / 6.0
    }

    fn slope_at_start(&self) -> f64 {
        self.b(0)
    }

    fn slope_at_end(&self) -> f64 {
        let n = self.x.len();
        let h = self.x[n - 1] - self.x[n - 2];
        (self.y[n - 1] - self.y[n - 2]) / h + h * (self.m[n - 2] + 2.0 * self.m[n - 1]) / 6.0
    }
}

/// The constant second derivative of the parabola through three points (twice its leading
/// coefficient, the second divided difference).
fn parabola_curvature(x: &[f64], y: &[f64]) -> f64 {
    let d01 = (y[1] - y[0]) / (x[1] - x[0]);
    let d12 = (y[2] - y[1]) / (x[2] - x[1]);
    2.0 * (d12 - d01) / (x[2] - x[0])
}

/// Second derivatives of the not-a-knot spline (n ≥ 4), by a dense LU solve (n is the number
/// of modes in the band, a few dozen at most).
fn not_a_knot_curvatures(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let h: Vec<f64> = (0..n - 1).map(|i| x[i + 1] - x[i]).collect();
    let mut a = Mat::<f64>::zeros(n, n);
    let mut rhs = Mat::<f64>::zeros(n, 1);
    a[(0, 0)] = h[1];
    a[(0, 1)] = -(h[0] + h[1]);
    a[(0, 2)] = h[0];
    for i in 1..n - 1 {
        a[(i, i - 1)] = h[i - 1];
        a[(i, i)] = 2.0 * (h[i - 1] + h[i]);
        a[(i, i + 1)] = h[i];
        rhs[(i, 0)] = 6.0 * ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1]);
    }
    a[(n - 1, n - 3)] = h[n - 2];
    a[(n - 1, n - 2)] = -(h[n - 3] + h[n - 2]);
    a[(n - 1, n - 1)] = h[n - 3];
    let m = a.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| m[(i, 0)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Not-a-knot splines reproduce cubics exactly (on uneven knots); fewer knots reproduce
    /// their polynomial degree; outside the knots the tangent line continues.
    #[test]
    fn reproduces_polynomials_and_extrapolates_linearly() {
        let cubic = |x: f64| 1.0 - 2.0 * x + 0.5 * x * x + 0.3 * x * x * x;
        let x = [0.0, 0.4, 1.1, 1.5, 2.6, 3.0];
        let y: Vec<f64> = x.iter().map(|&v| cubic(v)).collect();
        let s = Spline::new(&x, &y);
        for k in 0..=60 {
            let v = 0.05 * k as f64;
            assert!(
                (s.eval(v) - cubic(v)).abs() < 1e-12,
                "at {v}: {} vs {}",
                s.eval(v),
                cubic(v)
            );
        }
        let slope_end = -2.0 + 3.0 + 0.9 * 9.0;
        assert!((s.eval(4.0) - (cubic(3.0) + slope_end)).abs() < 1e-11);
        let q = |x: f64| 2.0 - x + 0.7 * x * x;
        let x3 = [1.0, 1.5, 3.0];
        let s3 = Spline::new(&x3, &x3.map(q));
        assert!((s3.eval(2.2) - q(2.2)).abs() < 1e-13);
        let s2 = Spline::new(&[1.0, 3.0], &[5.0, 9.0]);
        assert!((s2.eval(2.0) - 7.0).abs() < 1e-14 && (s2.eval(4.0) - 11.0).abs() < 1e-14);
        assert_eq!(Spline::new(&[2.0], &[3.0]).eval(7.0), 3.0);
    }

    /// O(h⁴) convergence on a smooth function: halving the spacing divides the error by ~16.
    #[test]
    fn fourth_order_on_smooth_data() {
        let err = |n: usize| {
            let x: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
            let y: Vec<f64> = x.iter().map(|v| v.exp().sin()).collect();
            let s = Spline::new(&x, &y);
            (0..=400)
                .map(|k| k as f64 / 400.0)
                .map(|v| (s.eval(v) - v.exp().sin()).abs())
                .fold(0.0, f64::max)
        };
        let ratio = err(11) / err(21);
        assert!((10.0..24.0).contains(&ratio), "error ratio {ratio}");
    }
}
