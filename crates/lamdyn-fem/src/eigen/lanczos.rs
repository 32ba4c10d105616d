//! Thick-restart block shift-invert Lanczos for the generalized symmetric problem K φ = λ M φ.
//!
//! With S = (K − σM)⁻¹ the operator S M is self-adjoint in the M inner product, and
//! S M φ = θ φ with θ = 1/(λ − σ): the eigenvalues nearest σ become the largest θ. The basis V
//! is built b columns at a time (one multi-right-hand-side solve per block, which reads the
//! Cholesky factor once for all b columns) and kept M-orthonormal by full reorthogonalization
//! (classical Gram–Schmidt, twice [Daniel, Gragg, Kaufman & Stewart 1976]) against V and any
//! locked vectors X. After m columns
//!
//! S M V_m = V_m T_m + Q R E_mᵀ,     (Q: next block, R: b×b, E_m: last b columns)
//!
//! and the Ritz pairs (θ_i, V_m y_i) of T_m have residual ‖S M x_i − θ_i x_i‖_M = ‖R y_i[last b]‖.
//! A thick restart [Wu & Simon 2000; Stewart 2001] keeps the p best Ritz vectors and the block
//! Q; T becomes diag(θ) bordered by R Y[last b, 0..p], and the iteration continues. Symbols:
//! V = `v`, M V = `mv`, T = `t`, θ = `theta`.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

/// The operator of a shift-invert eigenproblem.
pub trait ShiftInvert {
    /// Dimension n.
    fn dim(&self) -> usize;
    /// y ← M x (any number of columns).
    fn mass(&self, x: MatRef<'_, f64>, y: MatMut<'_, f64>);
    /// x ← (K − σM)⁻¹ x in place (any number of columns up to the block size).
    fn solve(&self, x: MatMut<'_, f64>);
}

/// Settings of [`lanczos`].
#[derive(Debug, Clone, Copy)]
pub struct LanczosParams {
    /// Number of largest θ wanted.
    pub wanted: usize,
    /// Basis size m (rounded up to a multiple of the block size; at least wanted + block).
    pub subspace: usize,
    /// Block size b (1: classical Lanczos).
    pub block: usize,
    /// Convergence when the Ritz residual ≤ tolerance·|θ|.
    pub tolerance: f64,
    /// Restarts allowed.
    pub max_restarts: usize,
    /// Seed of the start block.
    pub seed: u64,
    /// Parallelism of the dense products.
    pub par: Par,
}

/// What [`lanczos`] found.
#[derive(Debug, Clone)]
pub struct LanczosOutput {
    /// The largest θ, descending (converged or not: see `converged`).
    pub theta: Vec<f64>,
    /// Their Ritz vectors, M-orthonormal, n × wanted.
    pub vectors: Mat<f64>,
    /// Ritz residual estimates ‖R y_i‖ / |θ_i|.
    pub residuals: Vec<f64>,
    /// Restarts used.
    pub restarts: usize,
    /// Columns to which S M was applied.
    pub applications: usize,
    /// How many of `wanted` (leading) converged.
    pub converged: usize,
}

/// Deterministic pseudo-random numbers in [−1, 1) (SplitMix64), n × cols.
pub(crate) fn random_block(n: usize, cols: usize, seed: u64) -> Mat<f64> {
    let mut state = seed
        .wrapping_mul(0x2545_F491_4F6C_DD1D)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    Mat::from_fn(n, cols, |_, _| {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    })
}

/// M-orthogonalizes the columns of `w` against `basis` (with `m_basis` = M·basis), twice;
/// returns the summed coefficients (basis.ncols() × w.ncols()).
fn orthogonalize(
    w: &mut Mat<f64>,
    basis: MatRef<'_, f64>,
    m_basis: MatRef<'_, f64>,
    par: Par,
) -> Mat<f64> {
    let k = basis.ncols();
    let mut total = Mat::zeros(k, w.ncols());
    if k == 0 {
        return total;
    }
    for _ in 0..2 {
        let mut h = Mat::zeros(k, w.ncols());
        matmul(
            h.as_mut(),
            Accum::Replace,
            m_basis.transpose(),
            w.as_ref(),
            1.0,
            par,
        );
        matmul(w.as_mut(), Accum::Add, basis, h.as_ref(), -1.0, par);
        total += &h;
    }
    total
}

/// The working state: the basis and its M-image.
struct Basis {
    v: Mat<f64>,
    mv: Mat<f64>,
}

/// What a new block must be M-orthogonal to: the first `prior` columns of the basis and the
/// locked vectors.
struct Against<'a> {
    op: &'a dyn ShiftInvert,
    v: MatRef<'a, f64>,
    mv: MatRef<'a, f64>,
    locked: MatRef<'a, f64>,
    m_locked: MatRef<'a, f64>,
    par: Par,
}

impl Against<'_> {
    /// A random direction (from `seed`) M-orthogonal to everything here and to `extra`.
    fn fresh_direction(
        &self,
        seed: &mut u64,
        extra: MatRef<'_, f64>,
        m_extra: MatRef<'_, f64>,
    ) -> Mat<f64> {
        *seed = seed.wrapping_add(0x51_7CC1_B727_220A);
        let mut x = random_block(self.v.nrows(), 1, *seed);
        orthogonalize(&mut x, self.locked, self.m_locked, self.par);
        orthogonalize(&mut x, self.v, self.mv, self.par);
        orthogonalize(&mut x, extra, m_extra, self.par);
        x
    }
}

/// M-orthonormalizes the block `w` in place: w = Q R with Qᵀ M Q = I, by Cholesky QR applied
/// twice (CholQR2 [Fukaya et al. 2014]) in the M inner product, which needs one product with M
/// for the whole block (M Q = (M W) R⁻¹). When the Gram matrix is not numerically positive
/// definite (a rank-deficient block), falls back to column-by-column Gram–Schmidt, replacing
/// dependent columns by fresh directions M-orthogonal to everything, with zeros in R.
fn block_orthonormalize(
    w: &mut Mat<f64>,
    against: &Against<'_>,
    seed: &mut u64,
) -> (Mat<f64>, Mat<f64>) {
    let (n, b) = (w.nrows(), w.ncols());
    let mut mw = Mat::zeros(n, b);
    against.op.mass(w.as_ref(), mw.as_mut());
    let mut r_total = Mat::<f64>::identity(b, b);
    for _ in 0..2 {
        let mut g = Mat::zeros(b, b);
        matmul(
            g.as_mut(),
            Accum::Replace,
            w.as_ref().transpose(),
            mw.as_ref(),
            1.0,
            against.par,
        );
        let g = Mat::from_fn(b, b, |i, j| 0.5 * (g[(i, j)] + g[(j, i)]));
        let scale = (0..b).map(|i| g[(i, i)]).fold(0.0, f64::max);
        let Ok(chol) = g.llt(Side::Lower) else {
            return gram_schmidt(w, against, seed);
        };
        let r = chol.L().transpose().to_owned();
        // Reject a nearly dependent block: its smallest pivot must not vanish against the largest.
        let min_pivot = (0..b).map(|i| r[(i, i)]).fold(f64::INFINITY, f64::min);
        if min_pivot.is_nan() || min_pivot <= 1e-7 * scale.sqrt() {
            return gram_schmidt(w, against, seed);
        }
        // W ← W R⁻¹, MW ← MW R⁻¹ (solve from the right with the upper triangle).
        let mut rinv = Mat::<f64>::identity(b, b);
        solve_upper_triangular_in_place(r.as_ref(), rinv.as_mut(), Par::Seq);
        let w_new = w.as_ref() * &rinv;
        let mw_new = mw.as_ref() * &rinv;
        *w = w_new;
        mw = mw_new;
        r_total = &r * &r_total;
    }
    (r_total, mw)
}

/// Column-by-column M-orthonormalization with deflation (see [`block_orthonormalize`]).
fn gram_schmidt(w: &mut Mat<f64>, against: &Against<'_>, seed: &mut u64) -> (Mat<f64>, Mat<f64>) {
    let (n, b) = (w.nrows(), w.ncols());
    let (op, par) = (against.op, against.par);
    let mut r = Mat::zeros(b, b);
    let mut mq = Mat::zeros(n, b);
    let norm_of = |x: MatRef<'_, f64>, mx: MatRef<'_, f64>| {
        (0..n)
            .map(|i| x[(i, 0)] * mx[(i, 0)])
            .sum::<f64>()
            .max(0.0)
            .sqrt()
    };
    for c in 0..b {
        let mut x = w.as_ref().subcols(c, 1).to_owned();
        let mut mx = Mat::zeros(n, 1);
        op.mass(x.as_ref(), mx.as_mut());
        let before = norm_of(x.as_ref(), mx.as_ref());
        let coef = orthogonalize(
            &mut x,
            w.as_ref().subcols(0, c),
            mq.as_ref().subcols(0, c),
            par,
        );
        for p in 0..c {
            r[(p, c)] = coef[(p, 0)];
        }
        op.mass(x.as_ref(), mx.as_mut());
        let mut norm = norm_of(x.as_ref(), mx.as_ref());
        if !norm.is_finite() || norm <= 1e-10 * before {
            // Deflation: a fresh direction, uncoupled (R[c][c] = 0).
            x = against.fresh_direction(seed, w.as_ref().subcols(0, c), mq.as_ref().subcols(0, c));
            op.mass(x.as_ref(), mx.as_mut());
            norm = norm_of(x.as_ref(), mx.as_ref()).max(f64::MIN_POSITIVE);
            r[(c, c)] = 0.0;
        } else {
            r[(c, c)] = norm;
        }
        w.as_mut().subcols_mut(c, 1).copy_from(x.as_ref() / norm);
        mq.as_mut().subcols_mut(c, 1).copy_from(mx.as_ref() / norm);
    }
    (r, mq)
}

/// Runs thick-restart block Lanczos on `op` for the `wanted` largest θ, keeping the basis
/// M-orthogonal to `locked` (with `m_locked` = M·locked). `on_restart(converged)` is called
/// after each Rayleigh–Ritz step.
pub fn lanczos(
    op: &dyn ShiftInvert,
    params: LanczosParams,
    locked: MatRef<'_, f64>,
    m_locked: MatRef<'_, f64>,
    on_restart: &mut dyn FnMut(usize),
) -> LanczosOutput {
    let n = op.dim();
    let b = params.block.max(1);
    let wanted = params.wanted;
    let par = params.par;
    // At most half the free dimension: S M has the rank of M (drilling dofs carry no mass), and a
    // basis near that rank would be exhausted.
    let room = (n.saturating_sub(locked.ncols()) / 2).saturating_sub(b) / b * b;
    let m = (params.subspace.max(wanted + b).div_ceil(b) * b)
        .min(room)
        .max(b);
    let mut basis = Basis {
        v: Mat::zeros(n, m + b),
        mv: Mat::zeros(n, m + b),
    };
    let mut t = Mat::<f64>::zeros(m + b, m + b);
    let mut seed = params.seed;
    let mut applications = 0;
    {
        let mut w = random_block(n, b, seed);
        orthogonalize(&mut w, locked, m_locked, par);
        let empty = Mat::<f64>::zeros(n, 0);
        let against = Against {
            op,
            v: empty.as_ref(),
            mv: empty.as_ref(),
            locked,
            m_locked,
            par,
        };
        let (_, mq) = block_orthonormalize(&mut w, &against, &mut seed);
        basis.v.as_mut().subcols_mut(0, b).copy_from(&w);
        basis.mv.as_mut().subcols_mut(0, b).copy_from(&mq);
    }
    let mut k = 0;
    let mut restarts = 0;
    loop {
        let mut j = k;
        while j + b <= m {
            let mut w = basis.mv.as_ref().subcols(j, b).to_owned();
            op.solve(w.as_mut());
            applications += b;
            let before: Vec<f64> = (0..b).map(|c| w.col(c).norm_l2()).collect();
            orthogonalize(&mut w, locked, m_locked, par);
            let h = orthogonalize(
                &mut w,
                basis.v.as_ref().subcols(0, j + b),
                basis.mv.as_ref().subcols(0, j + b),
                par,
            );
            t.as_mut().submatrix_mut(0, j, j + b, b).copy_from(&h);
            // Columns that lay in the span of the basis (an invariant subspace was found) carry
            // only rounding: replace them by fresh directions, uncoupled (zero column in R).
            let (r, mq) = {
                let against = Against {
                    op,
                    v: basis.v.as_ref().subcols(0, j + b),
                    mv: basis.mv.as_ref().subcols(0, j + b),
                    locked,
                    m_locked,
                    par,
                };
                let deflated: Vec<usize> = (0..b)
                    .filter(|&c| {
                        w.col(c).norm_l2().is_nan() || w.col(c).norm_l2() <= 1e-10 * before[c]
                    })
                    .collect();
                let none = Mat::<f64>::zeros(n, 0);
                for &c in &deflated {
                    let x = against.fresh_direction(&mut seed, none.as_ref(), none.as_ref());
                    w.col_mut(c).copy_from(x.col(0));
                }
                let (mut r, mq) = block_orthonormalize(&mut w, &against, &mut seed);
                for &c in &deflated {
                    r.col_mut(c).fill(0.0);
                }
                (r, mq)
            };
            t.as_mut().submatrix_mut(j + b, j, b, b).copy_from(&r);
            basis.v.as_mut().subcols_mut(j + b, b).copy_from(&w);
            basis.mv.as_mut().subcols_mut(j + b, b).copy_from(&mq);
            j += b;
        }
        // Rayleigh–Ritz on the symmetrised T_m (upper triangle from the orthogonalization).
        let tm = Mat::from_fn(m, m, |i, jj| if i <= jj { t[(i, jj)] } else { t[(jj, i)] });
        let eig = tm
            .self_adjoint_eigen(Side::Upper)
            .expect("eigen of a small symmetric matrix");
        let order: Vec<usize> = (0..m).rev().collect();
        let theta: Vec<f64> = order.iter().map(|&i| eig.S()[i]).collect();
        let y = Mat::from_fn(m, m, |r, c| eig.U()[(r, order[c])]);
        // Coupling of each Ritz vector to the next block: R · Y[last b rows, i].
        let r_last = t.as_ref().submatrix(m, m - b, b, b).to_owned();
        let mut coupling = Mat::zeros(b, m);
        matmul(
            coupling.as_mut(),
            Accum::Replace,
            r_last.as_ref(),
            y.as_ref().subrows(m - b, b),
            1.0,
            par,
        );
        let resid: Vec<f64> = (0..m)
            .map(|i| coupling.col(i).norm_l2() / theta[i].abs().max(f64::MIN_POSITIVE))
            .collect();
        let converged = resid
            .iter()
            .take(wanted)
            .take_while(|r| **r <= params.tolerance)
            .count();
        on_restart(converged);
        let done = converged >= wanted || restarts >= params.max_restarts;
        let keep = if done {
            wanted
        } else {
            // Keep about half the basis beyond the wanted, leaving whole blocks to fill.
            let p = (wanted + m) / 2;
            (m - (m - p).div_ceil(b) * b).max(wanted).min(m - b)
        };
        let mut vy = Mat::zeros(n, keep);
        matmul(
            vy.as_mut(),
            Accum::Replace,
            basis.v.as_ref().subcols(0, m),
            y.as_ref().subcols(0, keep),
            1.0,
            par,
        );
        if done {
            return LanczosOutput {
                theta: theta[..wanted].to_vec(),
                vectors: vy,
                residuals: resid[..wanted].to_vec(),
                restarts,
                applications,
                converged,
            };
        }
        let mut mvy = Mat::zeros(n, keep);
        matmul(
            mvy.as_mut(),
            Accum::Replace,
            basis.mv.as_ref().subcols(0, m),
            y.as_ref().subcols(0, keep),
            1.0,
            par,
        );
        let (next_v, next_mv) = (
            basis.v.as_ref().subcols(m, b).to_owned(),
            basis.mv.as_ref().subcols(m, b).to_owned(),
        );
        basis.v.as_mut().subcols_mut(0, keep).copy_from(&vy);
        basis.mv.as_mut().subcols_mut(0, keep).copy_from(&mvy);
        basis.v.as_mut().subcols_mut(keep, b).copy_from(&next_v);
        basis.mv.as_mut().subcols_mut(keep, b).copy_from(&next_mv);
        t.fill(0.0);
        for i in 0..keep {
            t[(i, i)] = theta[i];
            for a in 0..b {
                t[(keep + a, i)] = coupling[(a, i)];
                t[(i, keep + a)] = coupling[(a, i)];
            }
        }
        k = keep;
        restarts += 1;
    }
}
