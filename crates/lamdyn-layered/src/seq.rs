//! Sequential (`Par::Seq`) products and eigenvalues for the layered model.
//!
//! faer's operators (`&a * &b`, `.eigenvalues()`) use its global parallelism, by default every
//! rayon thread, and a parallel kernel may split its sums by the thread count: the layered
//! inverse then changed at 1e-6 in G between 1 and 2 threads. These helpers fix
//! the order of every sum, so the results are the same bits on any thread count; the
//! parallelism lamdyn wants is across independent solves (rayon), not inside one.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{ComputeEigenvectors, evd_cplx, evd_scratch};
use faer::sparse::SparseColMat;
use faer::{Accum, Mat, MatRef, Par, c64};
use num_complex::Complex64;

/// A B, dense.
pub fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

/// A X with A sparse.
pub fn sparse_mul(a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), x.ncols());
    faer::sparse::linalg::matmul::sparse_dense_matmul(
        out.as_mut(),
        Accum::Replace,
        a.as_ref(),
        x,
        1.0,
        Par::Seq,
    );
    out
}

/// Eigenvalues of a square complex matrix (faer's complex EVD, without vectors), increasing
/// real part; empty if the QR iteration does not converge.
pub fn eigenvalues(z: MatRef<'_, c64>) -> Vec<Complex64> {
    let n = z.nrows();
    let mut s = faer::diag::Diag::<c64>::zeros(n);
    let req = evd_scratch::<c64>(
        n,
        ComputeEigenvectors::No,
        ComputeEigenvectors::No,
        Par::Seq,
        Default::default(),
    );
    let mut mem = MemBuffer::new(req);
    let ok = evd_cplx(
        z,
        s.as_mut(),
        None,
        None,
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
    if ok.is_err() {
        return Vec::new();
    }
    let mut out: Vec<Complex64> = (0..n).map(|i| Complex64::new(s[i].re, s[i].im)).collect();
    out.sort_by(|a, b| a.re.total_cmp(&b.re));
    out
}
