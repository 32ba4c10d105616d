//! Householder QR of tall, thin real matrices: the residue problems' bases (thousands of rows,
//! ten or so columns), factorised once per pole trial.
//!
//! **Why not faer's.** faer 0.24's `Mat::qr` is slower on such blocks than this
//! column-by-column kernel (its recursive blocking and generic inner loops do not pay below a
//! few dozen columns), and faster from a few dozen columns on: benches/thin_qr.rs, results in
//! bench-results/2026-12-01-vm-2cpu/thin_qr.md. Everything else (products, triangular solves,
//! the check's wide QR of the LSCF roots) stays faer's.
//!
//! **Algorithm** [Golub & Van Loan 2013, alg. 5.2.1]: for each column j, the reflector
//! H_j = I − τ_j v_j v_jᵀ (v_j = 1 at row j, zero above) that maps the column's rows j.. onto
//! β e_j, |β| = their norm, sign opposite to the diagonal's (no cancellation), applied to the
//! later columns; A = H_0 ⋯ H_{n−1} [R; 0] = Q [R; 0]. The norms are plain sums of squares:
//! the callers scale their columns to unit norm, far from over- and underflow.

use faer::Mat;

/// Rows × columns × reflectors from which [`ThinQr::apply_transpose_q`] and [`ThinQr::apply_q`]
/// share the columns out over threads (each column's work is then a few milliseconds' share).
const PARALLEL_WORK: usize = 1 << 21;

/// The QR factorisation A = Q [R; 0] of a real rows × cols matrix, Q held as its min(rows, cols)
/// Householder reflectors ([`Self::apply_transpose_q`], [`Self::apply_q`]); R is
/// min(rows, cols) × cols (a trapezoid where rows < cols).
#[derive(Debug, Clone)]
pub struct ThinQr {
    rows: usize,
    cols: usize,
    /// Column-major: R on and above the diagonal, the reflectors' v below it (v_j = 1 at row j,
    /// not stored).
    packed: Vec<f64>,
    /// τ_j of each reflector (0 where the column's rows below the diagonal are zero).
    tau: Vec<f64>,
}

impl ThinQr {
    /// The QR of `a` (columns of moderate scale, module docs).
    pub fn new(a: &Mat<f64>) -> Self {
        let (rows, cols) = a.shape();
        let mut packed = Vec::with_capacity(rows * cols);
        for j in 0..cols {
            packed.extend_from_slice(a.col_as_slice(j));
        }
        let mut tau = vec![0.0; rows.min(cols)];
        for j in 0..tau.len() {
            let (done, later) = packed.split_at_mut((j + 1) * rows);
            let column = &mut done[j * rows + j..];
            tau[j] = make_reflector(column);
            let v = &column[1..];
            for c in later.chunks_exact_mut(rows) {
                reflect(tau[j], v, &mut c[j..]);
            }
        }
        Self {
            rows,
            cols,
            packed,
            tau,
        }
    }

    /// R's rows: min(rows, cols), the number of reflectors.
    pub fn r_rows(&self) -> usize {
        self.tau.len()
    }

    /// The triangular factor R (min(rows, cols) × cols).
    pub fn r(&self) -> Mat<f64> {
        Mat::from_fn(self.tau.len(), self.cols, |i, j| {
            if i <= j {
                self.packed[j * self.rows + i]
            } else {
                0.0
            }
        })
    }

    /// Replaces `b` (rows × any) by Qᵀ b.
    ///
    /// # Panics
    /// When `b` has not the factorised matrix's rows (a caller's bug).
    pub fn apply_transpose_q(&self, b: &mut Mat<f64>) {
        self.apply(b, 0..self.tau.len());
    }

    /// Replaces `b` (rows × any) by Q b.
    ///
    /// # Panics
    /// As [`Self::apply_transpose_q`].
    pub fn apply_q(&self, b: &mut Mat<f64>) {
        self.apply(b, (0..self.tau.len()).rev());
    }

    /// Applies the reflectors in `order` (each its own transpose) to every column of `b`, the
    /// columns in parallel where the work is large ([`PARALLEL_WORK`]).
    fn apply(&self, b: &mut Mat<f64>, order: impl Iterator<Item = usize> + Clone + Send + Sync) {
        use rayon::prelude::*;
        assert_eq!(b.nrows(), self.rows, "rows of the matrix Q is applied to");
        let one = |column: &mut [f64]| {
            for j in order.clone() {
                let v = &self.packed[j * self.rows + j + 1..(j + 1) * self.rows];
                reflect(self.tau[j], v, &mut column[j..]);
            }
        };
        if b.ncols() > 1 && self.rows * b.ncols() * self.tau.len() >= PARALLEL_WORK {
            b.par_col_iter_mut().for_each(|c| {
                let column = c
                    .try_as_col_major_mut()
                    .expect("a Mat's columns are contiguous");
                one(column.as_slice_mut());
            });
        } else {
            for c in 0..b.ncols() {
                one(b.col_as_slice_mut(c));
            }
        }
    }
}

/// Turns `x` (a column's rows from the diagonal down) into β (first) and the reflector's v
/// below it; returns τ = (β − α)/β, 0 where x's rows below the first are zero (the column is
/// left as it is).
fn make_reflector(x: &mut [f64]) -> f64 {
    let alpha = x[0];
    let below = dot(&x[1..], &x[1..]);
    if below == 0.0 {
        return 0.0;
    }
    let norm = (alpha * alpha + below).sqrt();
    let beta = if alpha > 0.0 { -norm } else { norm };
    let scale = 1.0 / (alpha - beta);
    x[1..].iter_mut().for_each(|v| *v *= scale);
    x[0] = beta;
    (beta - alpha) / beta
}

/// y ← (I − τ v vᵀ) y for the reflector whose v is 1 at y's first row and `v` below it.
fn reflect(tau: f64, v: &[f64], y: &mut [f64]) {
    if tau == 0.0 {
        return;
    }
    let (head, tail) = y.split_at_mut(1);
    let w = tau * (head[0] + dot(v, tail));
    head[0] -= w;
    tail.iter_mut().zip(v).for_each(|(t, vi)| *t -= w * vi);
}

/// xᵀy with eight partial sums (vectorised by the compiler).
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let (xs, ys) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = xs
        .remainder()
        .iter()
        .zip(ys.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xs.zip(ys) {
        for k in 0..8 {
            acc[k] += a[k] * b[k];
        }
    }
    acc.iter().sum::<f64>() + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic rows × cols matrix with columns of very different directions.
    fn sample(rows: usize, cols: usize) -> Mat<f64> {
        Mat::from_fn(rows, cols, |i, j| {
            let (x, k) = (i as f64 / rows as f64, (j + 1) as f64);
            (k * 3.1 * x).sin() + 0.3 * (x * x * k).cos() + if i == j { 1e-3 } else { 0.0 }
        })
    }

    /// Q [R; 0] rebuilds A, QᵀQ = I, and R agrees with faer's QR up to the rows' signs.
    #[test]
    fn factors_rebuild_the_matrix_and_agree_with_faer() {
        for (rows, cols) in [(37, 5), (300, 12), (1000, 1), (9, 9), (4, 7)] {
            let a = sample(rows, cols);
            let qr = ThinQr::new(&a);
            let mut rebuilt = Mat::<f64>::zeros(rows, cols);
            rebuilt.subrows_mut(0, qr.r_rows()).copy_from(qr.r());
            qr.apply_q(&mut rebuilt);
            let err = (&rebuilt - &a).norm_l2() / a.norm_l2();
            assert!(err < 1e-14, "{rows} x {cols}: |QR - A|/|A| = {err:e}");
            let mut q = Mat::<f64>::identity(rows, rows);
            qr.apply_transpose_q(&mut q);
            let ortho = (q.transpose() * &q - Mat::<f64>::identity(rows, rows)).norm_l2();
            assert!(ortho < 1e-13, "{rows} x {cols}: |QᵀQ - I| = {ortho:e}");
            let theirs = a.qr().thin_R().to_owned();
            let ours = qr.r();
            for i in 0..qr.r_rows() {
                let sign = (ours[(i, i)] * theirs[(i, i)]).signum();
                for j in i..cols {
                    let d = (ours[(i, j)] - sign * theirs[(i, j)]).abs();
                    assert!(d < 1e-12 * a.norm_l2(), "R[{i}, {j}]: {d:e}");
                }
            }
        }
    }

    /// A zero column leaves a zero on R's diagonal and Q orthogonal (the caller's solve then
    /// reports the singular problem).
    #[test]
    fn a_zero_column_gives_a_zero_pivot() {
        let mut a = sample(50, 4);
        a.col_mut(2).fill(0.0);
        let qr = ThinQr::new(&a);
        assert_eq!(qr.r()[(2, 2)], 0.0);
        let mut q = Mat::<f64>::identity(50, 50);
        qr.apply_q(&mut q);
        let ortho = (q.transpose() * &q - Mat::<f64>::identity(50, 50)).norm_l2();
        assert!(ortho < 1e-13, "{ortho:e}");
    }
}
