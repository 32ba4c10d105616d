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
    let Some((s, _)) = complex_evd(z, false) else {
        return Vec::new();
    };
    let mut out: Vec<Complex64> = s.iter().map(|l| Complex64::new(l.re, l.im)).collect();
    out.sort_by(|a, b| a.re.total_cmp(&b.re));
    out
}

/// Eigenvalues and right eigenvectors (unit length) of a square complex matrix, by increasing
/// real part; empty if the QR iteration does not converge.
pub fn eigenpairs(z: MatRef<'_, c64>) -> Vec<(Complex64, Vec<Complex64>)> {
    let Some((s, Some(u))) = complex_evd(z, true) else {
        return Vec::new();
    };
    let mut out: Vec<(Complex64, Vec<Complex64>)> = s
        .iter()
        .enumerate()
        .map(|(j, l)| {
            let v = (0..u.nrows()).map(|i| Complex64::new(u[(i, j)].re, u[(i, j)].im));
            (Complex64::new(l.re, l.im), v.collect())
        })
        .collect();
    out.sort_by(|a, b| a.0.re.total_cmp(&b.0.re));
    out
}

/// faer's complex EVD of `z`, sequential: the eigenvalues and, with `vectors`, the right
/// eigenvectors; None if the QR iteration does not converge.
fn complex_evd(z: MatRef<'_, c64>, vectors: bool) -> Option<(Vec<c64>, Option<Mat<c64>>)> {
    let n = z.nrows();
    let mut s = faer::diag::Diag::<c64>::zeros(n);
    let mut u = vectors.then(|| Mat::<c64>::zeros(n, n));
    let right = if vectors {
        ComputeEigenvectors::Yes
    } else {
        ComputeEigenvectors::No
    };
    let req = evd_scratch::<c64>(
        n,
        ComputeEigenvectors::No,
        right,
        Par::Seq,
        Default::default(),
    );
    let mut mem = MemBuffer::new(req);
    evd_cplx(
        z,
        s.as_mut(),
        None,
        u.as_mut().map(|u| u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    Some(((0..n).map(|i| s[i]).collect(), u))
}

/// Eigenvalues (nondecreasing) and eigenvectors (the columns) of a real symmetric matrix,
/// its lower triangle read (faer's self-adjoint EVD); None if the iteration does not converge.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    let n = a.nrows();
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let req = faer::linalg::evd::self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    );
    let mut mem = MemBuffer::new(req);
    faer::linalg::evd::self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    Some(((0..n).map(|i| s[i]).collect(), u))
}
