//! Small sparse kernels the solver needs beyond faer: a parallel product with a symmetric
//! matrix stored in full, and dropping stored zeros.

use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{MatMut, MatRef};
use rayon::prelude::*;

/// y ← A x for a symmetric A stored in full (both triangles): row i of A is column i, so each
/// output row is an independent gather, computed in parallel over rows.
///
/// # Panics
/// If the shapes disagree (a programming error).
pub fn symmetric_matmul(
    a: SparseColMatRef<'_, usize, f64>,
    x: MatRef<'_, f64>,
    mut y: MatMut<'_, f64>,
) {
    let n = a.ncols();
    assert!(
        x.nrows() == n && y.nrows() == n && x.ncols() == y.ncols(),
        "expected matching shapes"
    );
    let (col_ptr, row_idx, val) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
    let b = x.ncols();
    // Row-major copy of x for contiguous gathers.
    let xr: Vec<f64> = (0..n)
        .flat_map(|i| (0..b).map(move |k| (i, k)))
        .map(|(i, k)| x[(i, k)])
        .collect();
    let mut out = vec![0.0; n * b];
    out.par_chunks_mut(b * 256)
        .enumerate()
        .for_each(|(chunk, rows)| {
            for (r, yi) in rows.chunks_mut(b).enumerate() {
                let i = chunk * 256 + r;
                for p in col_ptr[i]..col_ptr[i + 1] {
                    let (j, v) = (row_idx[p], val[p]);
                    let xj = &xr[j * b..j * b + b];
                    for k in 0..b {
                        yi[k] += v * xj[k];
                    }
                }
            }
        });
    for i in 0..n {
        for k in 0..b {
            y[(i, k)] = out[i * b + k];
        }
    }
}

/// The same matrix without its stored exact zeros.
pub fn drop_zeros(a: SparseColMatRef<'_, usize, f64>) -> SparseColMat<usize, f64> {
    let n = a.ncols();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    let mut val = Vec::new();
    col_ptr.push(0);
    for j in 0..n {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            if *v != 0.0 {
                row_idx.push(i);
                val.push(*v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    SparseColMat::new(
        SymbolicSparseColMat::new_checked(a.nrows(), n, col_ptr, None, row_idx),
        val,
    )
}
