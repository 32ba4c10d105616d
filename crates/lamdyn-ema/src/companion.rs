//! Roots of a monic real matrix polynomial A(x) = I xⁿ + Σ_{l<n} α_l x^l (N_i × N_i blocks) and
//! its null vector at a root: the last step of LSCF (N_i = 1) and PolyMAX (N_i > 1).
//!
//! The roots are the eigenvalues of the block companion matrix [Gohberg, Lancaster & Rodman,
//! *Matrix Polynomials*, 1982, §1.1]
//!
//! ```text
//!     C = | −α_{n−1} −α_{n−2} … −α_0 |      C [x^{n−1}v; …; x v; v] = x [x^{n−1}v; …; v]
//!         |    I        0     …   0  |      ⇔  A(x) v = 0,
//!         |    0        I     …   0  |
//! ```
//!
//! computed after Parlett–Reinsch balancing (as LAPACK's dgebal). With N_i = 1 the companion
//! matrix is already upper Hessenberg (balancing keeps it so), and its eigenvalues come from
//! the Francis double-shift QR iteration directly on it [Francis 1961; the EISPACK `hqr`
//! routine, Wilkinson & Reinsch, *Handbook for Automatic Computation II*, 1971, II/14]: this
//! skips the Hessenberg reduction a general eigensolver starts with (half the time of a
//! stabilization diagram on many FRFs). Block companions (N_i > 1), and the rare companion on
//! which the iteration does not converge, go to faer's real eigensolver without threads (the
//! model orders already run in parallel). The right null vector v (A(x) v = 0) at a root x is
//! found by one step of inverse iteration on A(x) (x is a root to machine precision, so one step
//! converges).

use faer::Mat;
use faer::linalg::solvers::Solve;
use num_complex::Complex64;

/// The coefficients α_0..α_{n−1} (each N_i × N_i, row-major) of a monic matrix polynomial.
pub(crate) struct MatrixPolynomial {
    /// Block size N_i.
    pub size: usize,
    /// α_l for l = 0..n; α_n = I is implied.
    pub coeffs: Vec<Vec<f64>>,
}

impl MatrixPolynomial {
    fn degree(&self) -> usize {
        self.coeffs.len()
    }

    /// The roots of det A(x): eigenvalues of the balanced block companion matrix (module docs).
    pub fn roots(&self) -> Option<Vec<Complex64>> {
        let (m, n) = (self.size, self.degree());
        let comp = Mat::from_fn(n * m, n * m, |i, j| {
            let (bi, a) = (i / m, i % m);
            let (bj, b) = (j / m, j % m);
            if bi == 0 {
                -self.coeffs[n - 1 - bj][a * m + b]
            } else if bi == bj + 1 && a == b {
                1.0
            } else {
                0.0
            }
        });
        let balanced = balance(comp);
        if m == 1 {
            if let Some(roots) = hessenberg_eigenvalues(&balanced) {
                return Some(roots);
            }
        }
        eigenvalues_seq(&balanced)
    }

    /// A(x) as a complex N_i × N_i matrix.
    pub fn at(&self, x: Complex64) -> Mat<faer::c64> {
        let m = self.size;
        Mat::from_fn(m, m, |a, b| {
            let mut acc = Complex64::new(if a == b { 1.0 } else { 0.0 }, 0.0);
            for c in self.coeffs.iter().rev() {
                acc = acc * x + c[a * m + b];
            }
            faer::c64::new(acc.re, acc.im)
        })
    }

    /// The right null vector v of A(x) (A(x) v = 0) at a root x, scaled to unit 2-norm.
    pub fn null_vector(&self, x: Complex64) -> Vec<Complex64> {
        if self.size == 1 {
            return vec![Complex64::new(1.0, 0.0)];
        }
        inverse_iteration(&self.at(x))
    }
}

/// One step of inverse iteration on a nearly singular matrix: the solution of a x = 1 (all
/// ones), normalised; the diagonal is shifted by 1e-14 ‖a‖ so an exactly singular pivot cannot
/// give infinities.
fn inverse_iteration(a: &Mat<faer::c64>) -> Vec<Complex64> {
    let m = a.nrows();
    let norm = a.norm_l2().max(f64::MIN_POSITIVE);
    let shifted = Mat::from_fn(m, m, |i, j| {
        a[(i, j)]
            + if i == j {
                faer::c64::new(1e-14 * norm, 0.0)
            } else {
                faer::c64::new(0.0, 0.0)
            }
    });
    let rhs = Mat::from_fn(m, 1, |_, _| faer::c64::new(1.0, 0.0));
    let v = shifted.partial_piv_lu().solve(&rhs);
    let scale: f64 = (0..m).map(|i| v[(i, 0)].norm_sqr()).sum::<f64>().sqrt();
    (0..m)
        .map(|i| Complex64::new(v[(i, 0)].re / scale, v[(i, 0)].im / scale))
        .collect()
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

/// Eigenvalues of an upper Hessenberg matrix by the Francis double-shift QR iteration with
/// deflation (EISPACK `hqr`; module docs), `None` if an eigenvalue takes more than 60
/// iterations. Only the active block rows l..=nn and columns are updated (no Schur vectors).
fn hessenberg_eigenvalues(h: &Mat<f64>) -> Option<Vec<Complex64>> {
    let n = h.nrows();
    let mut a: Vec<f64> = (0..n * n).map(|k| h[(k / n, k % n)]).collect();
    let at = |i: usize, j: usize| i * n + j;
    let norm: f64 = (0..n)
        .flat_map(|i| (i.saturating_sub(1)..n).map(move |j| (i, j)))
        .map(|(i, j)| a[at(i, j)].abs())
        .sum();
    let mut roots = vec![Complex64::new(0.0, 0.0); n];
    // Accumulated exceptional shifts.
    let mut t = 0.0;
    let mut nn = n as isize - 1;
    while nn >= 0 {
        let mut its = 0;
        loop {
            let u = nn as usize;
            // A negligible subdiagonal element splits the matrix at l.
            let mut l = u;
            while l >= 1 {
                let mut s = a[at(l - 1, l - 1)].abs() + a[at(l, l)].abs();
                if s == 0.0 {
                    s = norm;
                }
                if a[at(l, l - 1)].abs() <= f64::EPSILON * s {
                    a[at(l, l - 1)] = 0.0;
                    break;
                }
                l -= 1;
            }
            let mut x = a[at(u, u)];
            if l == u {
                roots[u] = Complex64::new(x + t, 0.0);
                nn -= 1;
            } else {
                let mut y = a[at(u - 1, u - 1)];
                let mut w = a[at(u, u - 1)] * a[at(u - 1, u)];
                if l == u - 1 {
                    // A 2 × 2 block: its two roots.
                    let p = 0.5 * (y - x);
                    let q = p * p + w;
                    let z = q.abs().sqrt();
                    x += t;
                    if q >= 0.0 {
                        let z = p + z.copysign(p);
                        let second = if z != 0.0 { x - w / z } else { x + z };
                        roots[u - 1] = Complex64::new(x + z, 0.0);
                        roots[u] = Complex64::new(second, 0.0);
                    } else {
                        roots[u - 1] = Complex64::new(x + p, -z);
                        roots[u] = Complex64::new(x + p, z);
                    }
                    nn -= 2;
                } else {
                    if its == 60 {
                        return None;
                    }
                    if its == 10 || its == 20 {
                        // Exceptional shift.
                        t += x;
                        for i in 0..=u {
                            a[at(i, i)] -= x;
                        }
                        let s = a[at(u, u - 1)].abs() + a[at(u - 1, u - 2)].abs();
                        x = 0.75 * s;
                        y = x;
                        w = -0.4375 * s * s;
                    }
                    its += 1;
                    francis_step(&mut a, n, l, u, x, y, w);
                }
            }
            if nn < 1 || l as isize >= nn - 1 {
                break;
            }
        }
    }
    Some(roots)
}

/// One Francis double-shift QR step on rows/columns l..=u of the Hessenberg matrix `a`
/// (row-major, n × n), with the shifts given by x, y, w (sum x + y and product xy − w of the
/// shifts' trailing 2 × 2 block): starts where two consecutive subdiagonal elements are small
/// and chases the bulge down with 3 × 3 Householder reflections.
fn francis_step(a: &mut [f64], n: usize, l: usize, u: usize, x: f64, y: f64, w: f64) {
    let at = |i: usize, j: usize| i * n + j;
    let (mut p, mut q, mut r);
    let mut m = u - 2;
    loop {
        let z = a[at(m, m)];
        let (rr, ss) = (x - z, y - z);
        p = (rr * ss - w) / a[at(m + 1, m)] + a[at(m, m + 1)];
        q = a[at(m + 1, m + 1)] - z - rr - ss;
        r = a[at(m + 2, m + 1)];
        let s = p.abs() + q.abs() + r.abs();
        p /= s;
        q /= s;
        r /= s;
        if m == l {
            break;
        }
        let uu = a[at(m, m - 1)].abs() * (q.abs() + r.abs());
        let vv = p.abs() * (a[at(m - 1, m - 1)].abs() + z.abs() + a[at(m + 1, m + 1)].abs());
        if uu <= f64::EPSILON * vv {
            break;
        }
        m -= 1;
    }
    for i in m + 2..=u {
        a[at(i, i - 2)] = 0.0;
        if i != m + 2 {
            a[at(i, i - 3)] = 0.0;
        }
    }
    let mut xk = 0.0;
    for k in m..u {
        if k != m {
            p = a[at(k, k - 1)];
            q = a[at(k + 1, k - 1)];
            r = if k != u - 1 { a[at(k + 2, k - 1)] } else { 0.0 };
            xk = p.abs() + q.abs() + r.abs();
            if xk != 0.0 {
                p /= xk;
                q /= xk;
                r /= xk;
            }
        }
        let s = (p * p + q * q + r * r).sqrt().copysign(p);
        if s == 0.0 {
            continue;
        }
        if k == m {
            if l != m {
                a[at(k, k - 1)] = -a[at(k, k - 1)];
            }
        } else {
            a[at(k, k - 1)] = -s * xk;
        }
        p += s;
        let (hx, hy, hz) = (p / s, q / s, r / s);
        q /= p;
        r /= p;
        for j in k..=u {
            let mut v = a[at(k, j)] + q * a[at(k + 1, j)];
            if k != u - 1 {
                v += r * a[at(k + 2, j)];
                a[at(k + 2, j)] -= v * hz;
            }
            a[at(k + 1, j)] -= v * hy;
            a[at(k, j)] -= v * hx;
        }
        for i in l..=u.min(k + 3) {
            let mut v = hx * a[at(i, k)] + hy * a[at(i, k + 1)];
            if k != u - 1 {
                v += hz * a[at(i, k + 2)];
                a[at(i, k + 2)] -= v * r;
            }
            a[at(i, k + 1)] -= v * q;
            a[at(i, k)] -= v;
        }
    }
}

/// Eigenvalues of a small real matrix without threads.
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

    /// The QR iteration on Hessenberg matrices gives faer's eigenvalues: random upper
    /// Hessenberg matrices of sizes 1..40 and companion matrices of 30 known roots.
    #[test]
    fn hessenberg_qr_agrees_with_faer() {
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let sorted = |mut v: Vec<Complex64>| {
            v.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
            v
        };
        for n in 1..40 {
            let h = Mat::from_fn(n, n, |i, j| if i <= j + 1 { rand() } else { 0.0 });
            let ours = sorted(hessenberg_eigenvalues(&h).unwrap());
            let theirs = sorted(eigenvalues_seq(&h).unwrap());
            let scale = h.norm_l2();
            for (a, b) in ours.iter().zip(&theirs) {
                assert!((a - b).norm() < 1e-10 * scale, "n = {n}: {a} vs {b}");
            }
        }
        // x^30 polynomial with roots 0.97 e^{±iθ_k} (LSCF-like: near the unit circle).
        let roots: Vec<Complex64> = (0..15)
            .flat_map(|k| {
                let r = Complex64::from_polar(0.97 + 0.001 * k as f64, 0.1 + 0.2 * k as f64);
                [r, r.conj()]
            })
            .collect();
        let mut coeffs = vec![Complex64::new(1.0, 0.0)];
        for r in &roots {
            let mut next = vec![Complex64::new(0.0, 0.0); coeffs.len() + 1];
            for (i, c) in coeffs.iter().enumerate() {
                next[i + 1] += c;
                next[i] -= c * r;
            }
            coeffs = next;
        }
        let poly = MatrixPolynomial {
            size: 1,
            coeffs: coeffs[..30].iter().map(|c| vec![c.re]).collect(),
        };
        let found = poly.roots().unwrap();
        for r in &roots {
            let d = found
                .iter()
                .map(|f| (f - r).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-8, "{r}: nearest {d}");
        }
    }

    /// A(x) = I x² + α_1 x + α_0 built from known roots: (x − 2)(x − 3) on the diagonal and
    /// (x + 1)(x − 0.5) coupled by a rotation Q: A = Q diag(p1, p2) Qᵀ. Its roots are the four
    /// scalar roots, and the null vector at x = 2 is the first column of Q.
    #[test]
    fn roots_and_null_vectors_of_a_known_matrix_polynomial() {
        let (c, s) = (0.6_f64, 0.8_f64);
        let q = [[c, -s], [s, c]];
        // p1 = x² − 5x + 6, p2 = x² − 0.5x − 0.5.
        let d1 = [-5.0, -0.5];
        let d0 = [6.0, -0.5];
        let rot = |d: [f64; 2]| {
            let mut out = vec![0.0; 4];
            for a in 0..2 {
                for b in 0..2 {
                    out[a * 2 + b] = (0..2).map(|k| q[a][k] * d[k] * q[b][k]).sum();
                }
            }
            out
        };
        let poly = MatrixPolynomial {
            size: 2,
            coeffs: vec![rot(d0), rot(d1)],
        };
        let mut r: Vec<f64> = poly.roots().unwrap().iter().map(|z| z.re).collect();
        r.sort_by(f64::total_cmp);
        for (got, want) in r.iter().zip([-0.5, 1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{r:?}");
        }
        let w = poly.null_vector(Complex64::new(2.0, 0.0));
        // Parallel to (c, s): |wᴴ q1| = 1.
        let dot = w[0].conj() * c + w[1].conj() * s;
        assert!((dot.norm() - 1.0).abs() < 1e-10, "{w:?}");
    }
}
