//! Householder QR of tall, thin real matrices: the residue problems' bases (thousands of rows,
//! ten or so columns), factorised once per pole trial, and the check's fixed LSCF roots (a few
//! dozen columns).
//!
//! **Why not faer's.** faer 0.24's `Mat::qr` takes each reflector's norm by a scaled, pairwise
//! sum (safe from over- and underflow at any scale), which costs more than the rest of the
//! factorisation on such matrices; its generic blocking does not pay below a few dozen columns
//! either. The callers here scale their columns to unit norm, so plain sums of squares serve:
//! benches/thin_qr.rs, results in bench-results/. Everything else (products, triangular
//! solves, small QRs) stays faer's.
//!
//! **Algorithm** [Golub & Van Loan 2013, alg. 5.2.1 and § 5.2.3]: for each column j, the
//! reflector H_j = I − τ_j v_j v_jᵀ (v_j = 1 at row j, zero above) that maps the column's rows
//! j.. onto β e_j, |β| = their norm, sign opposite to the diagonal's (no cancellation);
//! A = H_0 ⋯ H_{n−1} [R; 0] = Q [R; 0]. The columns go in panels of 16: within a panel
//! each reflector updates the panel's later columns, and the panel's reflectors, in the compact
//! WY form H_j0 ⋯ H_j1 = I − V T Vᵀ [Schreiber & Van Loan 1989; LAPACK `dlarft`] with T upper
//! triangular, update the later columns at once by two matrix products (faer's),
//! C − V (Tᵀ (Vᵀ C)). Q and Qᵀ are applied panel after panel the same way.

use faer::linalg::matmul::matmul;
use faer::{Accum, ColMut, Mat, MatMut, MatRef, Par};
use std::cmp::Ordering;

/// Rows × columns × reflectors from which [`ThinQr::apply_transpose_q`] and [`ThinQr::apply_q`]
/// share their products out over threads (each share is then a few milliseconds' work).
const PARALLEL_WORK: usize = 1 << 21;

/// Columns per panel of the factorisation (module docs): the residue problems' bases fit in
/// one.
const PANEL: usize = 16;

/// The QR factorisation A = Q [R; 0] of a real rows × cols matrix, Q held as its min(rows, cols)
/// Householder reflectors in panels of the compact WY form ([`Self::apply_transpose_q`],
/// [`Self::apply_q`]); R is min(rows, cols) × cols (a trapezoid where rows < cols).
#[derive(Debug, Clone)]
pub struct ThinQr {
    /// R, min(rows, cols) × cols.
    r: Mat<f64>,
    /// The reflectors' vectors as columns, rows × min(rows, cols): 1 on the diagonal, 0 above.
    v: Mat<f64>,
    /// Each panel's first column and the upper triangular T of its reflectors' product
    /// I − V T Vᵀ (module docs).
    panels: Vec<(usize, Mat<f64>)>,
}

impl ThinQr {
    /// The QR of `a` (columns of moderate scale, module docs).
    pub fn new(a: &Mat<f64>) -> Self {
        Self::of(a.clone())
    }

    /// The QR of `a`, factorised in its own storage, which then holds V.
    pub fn of(mut a: Mat<f64>) -> Self {
        let (rows, cols) = a.shape();
        let k = rows.min(cols);
        let mut beta = vec![0.0; k];
        let mut panels = Vec::with_capacity(k.div_ceil(PANEL));
        for j0 in (0..k).step_by(PANEL) {
            let width = PANEL.min(k - j0);
            let (mut panel, later) = a
                .as_mut()
                .submatrix_mut(j0, j0, rows - j0, cols - j0)
                .split_at_col_mut(width);
            let tau = factorised_panel(panel.as_mut(), &mut beta[j0..j0 + width]);
            let r_in_panel = panel.as_ref().subrows(0, width).to_owned();
            zero_above_diagonal(panel.as_mut());
            let t = triangular_factor(panel.as_ref(), &tau);
            if later.ncols() > 0 {
                apply_block(panel.as_ref(), &t, true, later);
            }
            for j in 1..width {
                let above = r_in_panel.col(j).subrows(0, j);
                panel.as_mut().col_mut(j).subrows_mut(0, j).copy_from(above);
            }
            panels.push((j0, t));
        }
        let r = Mat::from_fn(k, cols, |i, j| match i.cmp(&j) {
            Ordering::Less => a[(i, j)],
            Ordering::Equal => beta[i],
            Ordering::Greater => 0.0,
        });
        a.truncate(rows, k);
        zero_above_diagonal(a.as_mut());
        Self { r, v: a, panels }
    }

    /// R's rows: min(rows, cols), the number of reflectors.
    pub fn r_rows(&self) -> usize {
        self.r.nrows()
    }

    /// The triangular factor R (min(rows, cols) × cols).
    pub fn r(&self) -> Mat<f64> {
        self.r.clone()
    }

    /// Replaces `b` (rows × any) by Qᵀ b.
    ///
    /// # Panics
    /// When `b` has not the factorised matrix's rows (a caller's bug).
    pub fn apply_transpose_q(&self, b: &mut Mat<f64>) {
        assert_eq!(
            b.nrows(),
            self.v.nrows(),
            "rows of the matrix Q is applied to"
        );
        for (j0, t) in &self.panels {
            self.apply_panel(*j0, t, true, b);
        }
    }

    /// Replaces `b` (rows × any) by Q b.
    ///
    /// # Panics
    /// As [`Self::apply_transpose_q`].
    pub fn apply_q(&self, b: &mut Mat<f64>) {
        assert_eq!(
            b.nrows(),
            self.v.nrows(),
            "rows of the matrix Q is applied to"
        );
        for (j0, t) in self.panels.iter().rev() {
            self.apply_panel(*j0, t, false, b);
        }
    }

    /// Applies the panel from column `j0` with T `t` (or its transpose) to `b`'s rows j0...
    fn apply_panel(&self, j0: usize, t: &Mat<f64>, transposed: bool, b: &mut Mat<f64>) {
        let rows = self.v.nrows() - j0;
        let v = self.v.as_ref().submatrix(j0, j0, rows, t.nrows());
        apply_block(v, t, transposed, b.as_mut().subrows_mut(j0, rows));
    }
}

/// Factorises the panel `a` (its columns from the diagonal's row down) column by column, each
/// reflector applied to the panel's later columns; each column then holds R's entries above the
/// diagonal and v_j from it down (1 on the diagonal). Writes β_j into `beta`, returns τ_j.
fn factorised_panel(mut a: MatMut<'_, f64>, beta: &mut [f64]) -> Vec<f64> {
    let (rows, width) = a.shape();
    let mut tau = vec![0.0; width];
    for j in 0..width {
        (beta[j], tau[j]) = make_reflector(a.as_mut().submatrix_mut(j, j, rows - j, 1).col_mut(0));
        if tau[j] != 0.0 && j + 1 < width {
            let (v, later) = a
                .as_mut()
                .submatrix_mut(j, j, rows - j, width - j)
                .split_at_col_mut(1);
            reflect(tau[j], v.as_ref(), later);
        }
    }
    tau
}

/// Zeroes the entries above the diagonal.
fn zero_above_diagonal(mut a: MatMut<'_, f64>) {
    for j in 1..a.ncols() {
        let above = j.min(a.nrows());
        a.as_mut().col_mut(j).subrows_mut(0, above).fill(0.0);
    }
}

/// Replaces `b` by Qᵀ b (`transposed`) or Q b for Q = I − V T Vᵀ, `v` unit lower trapezoidal
/// (module docs), the products in parallel where the work is large ([`PARALLEL_WORK`]).
fn apply_block(v: MatRef<'_, f64>, t: &Mat<f64>, transposed: bool, mut b: MatMut<'_, f64>) {
    let (rows, k) = v.shape();
    let par = if rows * b.ncols() * k >= PARALLEL_WORK {
        faer::get_global_parallelism()
    } else {
        Par::Seq
    };
    let mut vtb = Mat::<f64>::zeros(k, b.ncols());
    matmul(
        vtb.as_mut(),
        Accum::Replace,
        v.transpose(),
        b.as_ref(),
        1.0,
        par,
    );
    let w = if transposed {
        t.transpose() * &vtb
    } else {
        t * &vtb
    };
    matmul(b.as_mut(), Accum::Add, v, w.as_ref(), -1.0, par);
}

/// T of H_0 ⋯ H_{k−1} = I − V T Vᵀ for the reflectors' vectors `v` (columns, unit lower
/// trapezoidal) and their `tau` [LAPACK `dlarft`, forward, column-wise]: T_jj = τ_j and
/// T[..j, j] = −τ_j T[..j, ..j] V[:, ..j]ᵀ v_j, the products Vᵀv_j taken at once as VᵀV.
fn triangular_factor(v: MatRef<'_, f64>, tau: &[f64]) -> Mat<f64> {
    let k = tau.len();
    let gram = v.transpose() * v;
    let mut t = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        t[(j, j)] = tau[j];
        for i in 0..j {
            t[(i, j)] = (i..j).map(|l| t[(i, l)] * gram[(l, j)]).sum::<f64>() * -tau[j];
        }
    }
    t
}

/// Turns `x` (a column's rows from the diagonal down, α first) into the reflector's vector v
/// (1 first, in place of α) and returns β (R's diagonal) and τ = (β − α)/β; τ = 0 and β = α
/// where x's rows below the first are zero (v = e_0, H = I). `x` then holds v.
fn make_reflector(mut x: ColMut<'_, f64>) -> (f64, f64) {
    let n = x.nrows();
    let alpha = x[0];
    x[0] = 1.0;
    let below = x.as_ref().subrows(1, n - 1).squared_norm_l2();
    if below == 0.0 {
        return (alpha, 0.0);
    }
    let norm = (alpha * alpha + below).sqrt();
    let beta = if alpha > 0.0 { -norm } else { norm };
    let scale = 1.0 / (alpha - beta);
    x.as_mut()
        .subrows_mut(1, n - 1)
        .iter_mut()
        .for_each(|v| *v *= scale);
    (beta, (beta - alpha) / beta)
}

/// y ← (I − τ v vᵀ) y for the reflector's vector `v` (one column) and every column of `y`:
/// w = vᵀy, then y − τ v w.
fn reflect(tau: f64, v: MatRef<'_, f64>, mut y: MatMut<'_, f64>) {
    let mut w = Mat::<f64>::zeros(1, y.ncols());
    matmul(
        w.as_mut(),
        Accum::Replace,
        v.transpose(),
        y.as_ref(),
        1.0,
        Par::Seq,
    );
    matmul(y.as_mut(), Accum::Add, v, w.as_ref(), -tau, Par::Seq);
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
        let shapes = [
            (37, 5),
            (300, 12),
            (1000, 1),
            (9, 9),
            (4, 7),
            (600, 53),
            (40, 33),
            (20, 37),
        ];
        for (rows, cols) in shapes {
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
