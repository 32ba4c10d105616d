//! The residue problem of given poles on given lines, solved and differentiated with respect
//! to the poles: variable projection [Golub & Pereyra 1973].
//!
//! With the poles fixed, every curve is linear in its residues and residual terms (the model of
//! [`crate::lsfd`]): B ≈ A(λ) X, with A the real basis (real and imaginary part of each line as
//! two rows) shared by all curves and B the curves as columns. The projected residual
//!
//!   R(λ) = P⊥ B,   P⊥ = I − A A⁺,
//!
//! depends on the poles alone. Its derivative with respect to a pole parameter u_j is
//! [Golub & Pereyra 1973, eq. (4.12); Kaufman 1975 keeps the first term only]
//!
//!   ∂R/∂u_j = −P⊥ D_j X − (A⁺)ᵀ D_jᵀ R,   D_j = ∂A/∂u_j,
//!
//! with D_j nonzero only in the two columns of u_j's pole. With the columns scaled by their
//! norms S for conditioning and the QR A S⁻¹ = Q R̃ ([`crate::thin_qr`]), A⁺ = S⁻¹ R̃⁻¹ Q₁ᵀ and
//! (A⁺)ᵀ = Q₁ R̃⁻ᵀ S⁻¹. The Gauss–Newton steps need only JᵀJ and Jᵀr, and the two terms of
//! ∂R/∂u_j are orthogonal (one outside the basis's span, one inside), so both come from small
//! matrices ([`Projection::normal_equations`]): the Jacobian itself (rows × curves per
//! parameter) is never formed. It is exact where finite differences are not.
//!
//! The pole parameters are u = (ln σ, ω_d) for λ = −σ + iω_d (σ > 0 keeps the pole stable):
//! ∂λ/∂ln σ = −σ, ∂λ/∂ω_d = i.

use crate::error::{EmaError, invalid};
use crate::thin_qr::ThinQr;
use faer::linalg::solvers::SolveLstsq;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par};
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The measured side of the residue problem: the lines (ω), the curves' quantity, and the
/// curves' values as real rows (re, im per line), one column per curve.
pub(crate) struct LineSamples {
    omega: Vec<f64>,
    quantity: Quantity,
    data: Mat<f64>,
    /// Columns beside the poles' and the residual terms' that do not depend on the poles (real
    /// rows as `data`'s): none unless [`Self::set_fixed`] gives them.
    fixed: Mat<f64>,
}

impl LineSamples {
    /// The samples of `curves` (values of `quantity` at `freqs_hz`) at `lines` (positive
    /// frequencies; the curves' lengths already checked).
    ///
    /// # Errors
    /// [`EmaError::Invalid`] for a value that is not finite.
    pub(crate) fn new(
        freqs_hz: &[f64],
        curves: &[&[Complex64]],
        quantity: Quantity,
        lines: &[usize],
    ) -> Result<Self, EmaError> {
        let omega: Vec<f64> = lines.iter().map(|&k| 2.0 * PI * freqs_hz[k]).collect();
        let data = Mat::from_fn(2 * lines.len(), curves.len(), |row, o| {
            let h = curves[o][lines[row / 2]];
            if row % 2 == 0 { h.re } else { h.im }
        });
        if !data.is_all_finite() {
            return Err(invalid("FRFs", "a value in the band is not finite".into()));
        }
        let fixed = Mat::zeros(data.nrows(), 0);
        Ok(Self {
            omega,
            quantity,
            data,
            fixed,
        })
    }

    /// Sets the columns `fixed` (real rows as the samples', one column per
    /// function of the line) beside the poles' and the residual terms' in every basis: their
    /// coefficients are unknowns as the residues are, their columns do not move with the poles.
    ///
    /// # Panics
    /// When `fixed` has not one row per sample row (a caller's bug).
    pub(crate) fn set_fixed(&mut self, fixed: Mat<f64>) {
        assert_eq!(fixed.nrows(), self.rows(), "fixed columns' rows");
        self.fixed = fixed;
    }

    /// The unknowns per curve with `poles` poles: two per pole, the two residual terms and
    /// one per fixed column.
    pub(crate) fn unknowns(&self, poles: usize) -> usize {
        2 * poles + 2 + self.fixed.ncols()
    }

    /// ω of each line, rad/s.
    pub(crate) fn omega(&self) -> &[f64] {
        &self.omega
    }

    /// The two basis columns of each of `poles` (module docs), as real rows: fixed columns
    /// ([`Self::set_fixed`]) for poles held where they are.
    pub(crate) fn pole_columns(&self, poles: &[Complex64]) -> Mat<f64> {
        self.basis(poles).subcols(0, 2 * poles.len()).to_owned()
    }

    /// Rows per curve: two per line.
    pub(crate) fn rows(&self) -> usize {
        self.data.nrows()
    }

    /// The number of curves.
    pub(crate) fn curves(&self) -> usize {
        self.data.ncols()
    }

    /// Writes the complex column value `v` of line `i` into rows 2i, 2i + 1 of column `c`.
    pub(crate) fn put(a: &mut Mat<f64>, i: usize, c: usize, v: Complex64) {
        a[(2 * i, c)] = v.re;
        a[(2 * i + 1, c)] = v.im;
    }

    /// The basis A for `poles` (unscaled): per pole the columns (iω)^k [1/(iω − λ) + 1/(iω − λ*)]
    /// and (iω)^k i[1/(iω − λ) − 1/(iω − λ*)], then the lower residual's −(iω)^k/ω² and the upper
    /// residual's (iω)^k, then the fixed columns ([`Self::set_fixed`]).
    fn basis(&self, poles: &[Complex64]) -> Mat<f64> {
        let n = 2 * poles.len();
        let mut a = Mat::zeros(self.rows(), self.unknowns(poles.len()));
        a.subcols_mut(n + 2, self.fixed.ncols())
            .copy_from(&self.fixed);
        let mut line = LineBasis::new(poles, self.quantity, 0.0);
        for (i, &w) in self.omega.iter().enumerate() {
            line.set(poles, self.quantity, w);
            for (r, &(a1, a2)) in line.fractions.iter().enumerate() {
                Self::put(&mut a, i, 2 * r, line.factor * (a1 + a2));
                Self::put(
                    &mut a,
                    i,
                    2 * r + 1,
                    line.factor * Complex64::i() * (a1 - a2),
                );
            }
            Self::put(&mut a, i, n, line.factor * line.lower);
            Self::put(&mut a, i, n + 1, line.factor);
        }
        a
    }

    /// The base columns of pole `p`'s two parameters ([`ColumnMap`]) in the two columns of `d`
    /// (rows × 2): the derivatives of its two basis columns with respect to λ (∂λ/∂u = 1,
    /// ∂λ*/∂u = 1), (iω)^k [1/(iω − λ)² + 1/(iω − λ*)²] and (iω)^k i[1/(iω − λ)² −
    /// 1/(iω − λ*)²]. The parameter ln σ (∂λ/∂u = Re λ) has Re λ times them, ω_d (∂λ/∂u = i)
    /// their [`ColumnMap::TURNED`].
    fn write_base_derivatives(&self, p: Complex64, d: &mut Mat<f64>) {
        for (i, &w) in self.omega.iter().enumerate() {
            let f = quantity_factor(w, self.quantity);
            let s = Complex64::new(0.0, w);
            let (a1, a2) = (1.0 / (s - p), 1.0 / (s - p.conj()));
            let (d1, d2) = (f * a1 * a1, f * a2 * a2);
            Self::put(d, i, 0, d1 + d2);
            Self::put(d, i, 1, Complex64::i() * (d1 - d2));
        }
    }

    /// The basis for `poles` with each column scaled to unit norm, and the norms; None without
    /// more rows than columns.
    fn scaled_basis(&self, poles: &[Complex64]) -> Option<(Mat<f64>, Vec<f64>)> {
        if self.rows() <= self.unknowns(poles.len()) {
            return None;
        }
        let mut a = self.basis(poles);
        let scale = unit_columns(&mut a);
        Some((a, scale))
    }

    /// The block's least-squares problem for `poles` reduced to min(rows, unknowns) rows: the
    /// triangle R of the QR of the basis and the first rows of Qᵀ B ([`solve_by_blocks`]). The
    /// basis is factorised with its columns scaled to unit norm and R scaled back.
    fn triangle(&self, poles: &[Complex64]) -> (Mat<f64>, Mat<f64>) {
        let mut a = self.basis(poles);
        let scale = unit_columns(&mut a);
        let qr = ThinQr::of(a);
        let mut r = qr.r();
        for (c, s) in scale.iter().enumerate() {
            r.col_mut(c).iter_mut().for_each(|v| *v *= s);
        }
        let mut qtb = self.data.clone();
        qr.apply_transpose_q(&mut qtb);
        let rows = r.nrows();
        (r, qtb.subrows(0, rows).to_owned())
    }

    /// The model of `poles` fitted to these samples (residues, residual terms and fixed
    /// columns), kept to be held beside some of the poles ([`HeldModel::rest_removed`]); None
    /// where the residue problem fails.
    pub(crate) fn held_model(&self, poles: &[Complex64]) -> Option<HeldModel<'_>> {
        let (basis, scale) = self.scaled_basis(poles)?;
        let projection = self.project_on(poles, basis.clone(), scale)?;
        Some(HeldModel {
            samples: self,
            poles: poles.len(),
            basis,
            coefficients: projection.unknowns,
        })
    }

    /// The residue problem solved for `poles` (module docs); None where it is singular or not
    /// finite. Needs more rows than unknowns (2 poles + 2). The residual P⊥B = Q [0; (QᵀB)₂],
    /// the part of B outside the basis's span, is kept in Q's coordinates, [0; (QᵀB)₂]: its
    /// norms and its products with other vectors in Q's coordinates are those of P⊥B, and Q is
    /// never applied.
    pub(crate) fn project(&self, poles: &[Complex64]) -> Option<Projection> {
        let (a, scale) = self.scaled_basis(poles)?;
        self.project_on(poles, a, scale)
    }

    /// [`Self::project`] on the basis `a` of `poles` already scaled by the column norms
    /// `scale` ([`Self::scaled_basis`]).
    fn project_on(&self, poles: &[Complex64], a: Mat<f64>, scale: Vec<f64>) -> Option<Projection> {
        let qr = ThinQr::of(a);
        let r = qr.r();
        let n = r.nrows();
        let mut residual_in_q = self.data.clone();
        qr.apply_transpose_q(&mut residual_in_q);
        let mut unknowns = residual_in_q.subrows(0, n).to_owned();
        solve_upper_triangular_in_place(r.as_ref(), unknowns.as_mut(), Par::Seq);
        if !unknowns.is_all_finite() {
            return None;
        }
        residual_in_q.subrows_mut(0, n).fill(0.0);
        Some(Projection {
            poles: poles.to_vec(),
            qr,
            scale,
            unknowns,
            residual_in_q,
        })
    }
}

/// A model of poles fitted to [`LineSamples`] ([`LineSamples::held_model`]): its basis and
/// coefficients on the samples' lines.
pub(crate) struct HeldModel<'a> {
    samples: &'a LineSamples,
    /// How many poles the model holds (their columns come first in the basis).
    poles: usize,
    /// The basis with its columns scaled to unit norm, A S⁻¹, rows × unknowns.
    basis: Mat<f64>,
    /// The scaled unknowns S X, unknowns × curves: (A S⁻¹)(S X) = A X is the model.
    coefficients: Mat<f64>,
}

impl HeldModel<'_> {
    /// The samples of the lines `lines` (indices into the samples' lines) less the model
    /// without the columns of the poles `group` (indices into its poles): what those poles and
    /// two new residual terms must explain there while every other pole's residues, the residual
    /// terms and the fixed columns keep their fitted values. No fixed columns.
    pub(crate) fn rest_removed(&self, group: &[usize], lines: &[usize]) -> LineSamples {
        let held: Vec<usize> = (0..self.basis.ncols())
            .filter(|&c| c >= 2 * self.poles || !group.contains(&(c / 2)))
            .collect();
        let data = Mat::from_fn(2 * lines.len(), self.samples.curves(), |row, o| {
            let r = 2 * lines[row / 2] + row % 2;
            let model: f64 = held
                .iter()
                .map(|&c| self.basis[(r, c)] * self.coefficients[(c, o)])
                .sum();
            self.samples.data[(r, o)] - model
        });
        LineSamples {
            omega: lines.iter().map(|&i| self.samples.omega[i]).collect(),
            quantity: self.samples.quantity,
            data,
            fixed: Mat::zeros(2 * lines.len(), 0),
        }
    }
}

/// Lines per block of [`solve_by_blocks`]: 4096 rows of a few dozen columns stay in cache.
const BLOCK_LINES: usize = 2048;

/// The unknowns of the residue problem for `poles` (one column per curve, the order of
/// [`Projection::unknown`]) fitted to `curves` (values of `quantity` at `freqs_hz`, lengths
/// already checked) at `lines`; None where it is singular, not finite or has no more rows than
/// unknowns. By a QR of each block of lines, in parallel, then one of their stacked triangles
/// with the columns scaled to unit norm (TSQR [Demmel et al. 2012]): the least-squares solution
/// of one QR of every row, without the band's whole basis in memory.
///
/// # Errors
/// [`EmaError::Invalid`] for a value that is not finite.
pub(crate) fn solve_by_blocks(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    lines: &[usize],
    poles: &[Complex64],
) -> Result<Option<Mat<f64>>, EmaError> {
    use rayon::prelude::*;
    let n = 2 * poles.len() + 2;
    if 2 * lines.len() <= n {
        return Ok(None);
    }
    let blocks: Vec<(Mat<f64>, Mat<f64>)> = lines
        .par_chunks(BLOCK_LINES)
        .map(|block| LineSamples::new(freqs_hz, curves, quantity, block).map(|s| s.triangle(poles)))
        .collect::<Result<_, _>>()?;
    let rows: usize = blocks.iter().map(|(r, _)| r.nrows()).sum();
    let (mut r, mut qtb) = (Mat::zeros(rows, n), Mat::zeros(rows, curves.len()));
    let mut at = 0;
    for (rb, tb) in &blocks {
        r.subrows_mut(at, rb.nrows()).copy_from(rb);
        qtb.subrows_mut(at, tb.nrows()).copy_from(tb);
        at += rb.nrows();
    }
    let scale = unit_columns(&mut r);
    let mut x = r.qr().solve_lstsq(&qtb);
    for (c, s) in scale.iter().enumerate() {
        x.row_mut(c).iter_mut().for_each(|v| *v /= s);
    }
    Ok(x.is_all_finite().then_some(x))
}

/// Scales each column of `a` to unit norm (for the QR's conditioning: the span is what
/// counts); returns the norms.
pub(crate) fn unit_columns(a: &mut Mat<f64>) -> Vec<f64> {
    let scale: Vec<f64> = (0..a.ncols())
        .map(|c| a.col(c).squared_norm_l2().sqrt().max(f64::MIN_POSITIVE))
        .collect();
    for (c, s) in scale.iter().enumerate() {
        a.col_mut(c).iter_mut().for_each(|v| *v /= s);
    }
    scale
}

/// How a parameter's two derivative columns follow from its pair's two base columns [A, B]:
/// D_u = [A, B] T_u, `t[c][d]` the weight of base column c in column d. A complex coefficient
/// e of a pole's columns enters them as e/(iω − λ) and e*/(iω − λ*) (their real part and i
/// times their difference, [`LineSamples::put`]); replacing e by i·e turns [A, B] into
/// [B, −A]. So a pole's ∂/∂ln σ (∂λ = Re λ) is Re λ [A, B] and its ∂/∂ω_d (∂λ = i) is [B, −A],
/// [A, B] the derivatives with respect to λ; a complex coefficient's real part is [A, B], its
/// imaginary part [B, −A]. Only the base columns need the projection (P⊥ commutes with T):
/// half the columns a Jacobian of both parameters would take.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColumnMap {
    t: [[f64; 2]; 2],
}

impl ColumnMap {
    /// The first parameter of a pair: its base columns times `scale`.
    pub(crate) fn scaled(scale: f64) -> Self {
        Self {
            t: [[scale, 0.0], [0.0, scale]],
        }
    }

    /// The second parameter of a pair: [B, −A].
    pub(crate) const TURNED: Self = Self {
        t: [[0.0, -1.0], [1.0, 0.0]],
    };

    /// The maps of the parameters (ln σ, ω_d) of each of `poles` in turn.
    pub(crate) fn of_poles(poles: &[Complex64]) -> Vec<Self> {
        poles
            .iter()
            .flat_map(|p| [Self::scaled(p.re), Self::TURNED])
            .collect()
    }
}

/// The Gram matrix of the parameters' columns E_u = base · T_u ([`ColumnMap`]; 2 × 2 block
/// T_uᵀ G_q(u)q(v) T_v at rows 2u, columns 2v) from `base_gram`, that of the base columns
/// (pair q at 2q, 2q + 1; parameter u's pair at u − u mod 2).
pub(crate) fn expanded_gram(base_gram: &Mat<f64>, maps: &[ColumnMap]) -> Mat<f64> {
    Mat::from_fn(2 * maps.len(), 2 * maps.len(), |i, j| {
        let (a, c) = (i / 2, i % 2);
        let (b, d) = (j / 2, j % 2);
        let (pa, pb) = (a - a % 2, b - b % 2);
        let mut v = 0.0;
        for x in 0..2 {
            for y in 0..2 {
                v += maps[a].t[x][c] * base_gram[(pa + x, pb + y)] * maps[b].t[y][d];
            }
        }
        v
    })
}

/// E_uᵀ r (rows 2u, 2u + 1, one column per column of r) from `base_products`, the base
/// columns' baseᵀ r ([`expanded_gram`]'s layout).
pub(crate) fn expanded_products(base_products: &Mat<f64>, maps: &[ColumnMap]) -> Mat<f64> {
    Mat::from_fn(2 * maps.len(), base_products.ncols(), |i, o| {
        let (a, d) = (i / 2, i % 2);
        let pair = a - a % 2;
        (0..2)
            .map(|c| maps[a].t[c][d] * base_products[(pair + c, o)])
            .sum()
    })
}

/// What every curve's synthesis at one line shares ([`crate::lsfd::ModalFit::line_basis`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LineBasis {
    /// (iω)^k of the quantity.
    pub(crate) factor: Complex64,
    /// The lower residual's −1/ω² (0 at 0 Hz).
    pub(crate) lower: f64,
    /// 1/(iω − λ_r) and 1/(iω − λ_r*) of each pole.
    pub(crate) fractions: Vec<(Complex64, Complex64)>,
}

impl LineBasis {
    /// The basis of `poles` for curves of `quantity` at ω = `w` rad/s: the model's terms of
    /// the module docs before their coefficients.
    pub(crate) fn new(poles: &[Complex64], quantity: Quantity, w: f64) -> Self {
        let mut line = Self {
            factor: Complex64::default(),
            lower: 0.0,
            fractions: Vec::with_capacity(poles.len()),
        };
        line.set(poles, quantity, w);
        line
    }

    /// Makes this the basis of [`Self::new`] at ω = `w`, in its own storage (loops over lines
    /// reuse one).
    pub(crate) fn set(&mut self, poles: &[Complex64], quantity: Quantity, w: f64) {
        let s = Complex64::new(0.0, w);
        self.factor = quantity_factor(w, quantity);
        self.lower = if w > 0.0 { -1.0 / (w * w) } else { 0.0 };
        self.fractions.clear();
        self.fractions.extend(
            poles
                .iter()
                .map(|p| (reciprocal(s - p), reciprocal(s - p.conj()))),
        );
    }
}

/// 1/z by one division: z*/|z|².
fn reciprocal(z: Complex64) -> Complex64 {
    let r = 1.0 / z.norm_sqr();
    Complex64::new(z.re * r, -z.im * r)
}

/// (iω)^k of the quantity: receptance 1, mobility iω, accelerance (iω)².
fn quantity_factor(w: f64, q: Quantity) -> Complex64 {
    let s = Complex64::new(0.0, w);
    match q {
        Quantity::Receptance => Complex64::new(1.0, 0.0),
        Quantity::Mobility => s,
        Quantity::Accelerance => s * s,
    }
}

/// The residue problem of [`LineSamples::project`] solved at given poles.
pub(crate) struct Projection {
    poles: Vec<Complex64>,
    /// The QR of the scaled basis (its triangular factor is R̃).
    qr: ThinQr,
    /// Column norms S of the basis.
    scale: Vec<f64>,
    /// The scaled unknowns X̃ = S X, one column per curve.
    unknowns: Mat<f64>,
    /// Qᵀ P⊥ B = [0; (QᵀB)₂]: the residual in Q's coordinates.
    residual_in_q: Mat<f64>,
}

impl Projection {
    /// Unknown `c` of curve `o` (basis order: re, im of each pole's residue, then the lower
    /// and upper residuals).
    pub(crate) fn unknown(&self, c: usize, o: usize) -> f64 {
        self.unknowns[(c, o)] / self.scale[c]
    }

    /// The residual sum of squares over every curve.
    pub(crate) fn cost(&self) -> f64 {
        self.residual_in_q.squared_norm_l2()
    }

    /// Curve `o`'s residual sum of squares.
    pub(crate) fn curve_cost(&self, o: usize) -> f64 {
        self.residual_in_q.col(o).squared_norm_l2()
    }

    /// The Gauss–Newton normal equations of the projected residual with respect to the pole
    /// parameters (ln σ, ω_d of each pole in turn), curve by curve, without forming the
    /// Jacobian (module docs: J_j = −(P⊥ D_j X + Q Z_j) with Z_j = R̃⁻ᵀ S⁻¹ D_jᵀ R). The two
    /// terms are orthogonal (P⊥ Q = 0) and P⊥ R = R, so for curve o
    ///
    ///   (JᵀJ)_ab = x_aᵀ E_aᵀ P⊥ E_b x_b + z_aᵀ z_b,   (Jᵀr)_a = −x_aᵀ E_aᵀ r,
    ///
    /// with E_j the two nonzero columns of D_j, x_j their two unknowns and z_j curve o's column
    /// of Z_j. EᵀP⊥E is the Gram matrix of the last rows of QᵀE (P⊥E in Q's coordinates)
    /// rather than EᵀE − (Q₁ᵀE)ᵀ(Q₁ᵀE), which cancels where a derivative lies near the basis's
    /// span; Eᵀr = (QᵀE)ᵀ(Qᵀr) is taken in Q's coordinates too, where r lies in the last rows.
    pub(crate) fn normal_equations(&self, samples: &LineSamples) -> NormalEquations {
        let r = self.qr.r();
        let (n, p, curves) = (r.nrows(), 2 * self.poles.len(), self.residual_in_q.ncols());
        let mut perp = Mat::<f64>::zeros(samples.rows(), p);
        let mut d = Mat::<f64>::zeros(samples.rows(), 2);
        for (k, pole) in self.poles.iter().enumerate() {
            samples.write_base_derivatives(*pole, &mut d);
            perp.subcols_mut(2 * k, 2).copy_from(&d);
        }
        self.qr.apply_transpose_q(&mut perp);
        perp.subrows_mut(0, n).fill(0.0);
        let maps = ColumnMap::of_poles(&self.poles);
        let etr = expanded_products(&(perp.transpose() * &self.residual_in_q), &maps);
        let m = expanded_gram(&(perp.transpose() * &perp), &maps);
        let mut z = Mat::<f64>::zeros(n, p * curves);
        for j in 0..p {
            for o in 0..curves {
                for c in 0..2 {
                    let col = 2 * (j / 2) + c;
                    z[(col, j * curves + o)] = etr[(2 * j + c, o)] / self.scale[col];
                }
            }
        }
        solve_lower_triangular_in_place(r.transpose(), z.as_mut(), Par::Seq);
        let x = |j: usize, o: usize| [0, 1].map(|c| self.unknown(2 * (j / 2) + c, o));
        let per_curve = (0..curves)
            .map(|o| {
                Mat::from_fn(p, p, |a, b| {
                    let (xa, xb) = (x(a, o), x(b, o));
                    let mut v = z.col(a * curves + o).transpose() * z.col(b * curves + o);
                    for (c, xac) in xa.iter().enumerate() {
                        for (d, xbd) in xb.iter().enumerate() {
                            v += xac * m[(2 * a + c, 2 * b + d)] * xbd;
                        }
                    }
                    v
                })
            })
            .collect();
        let gradient = Mat::from_fn(p, 1, |a, _| {
            (0..curves)
                .map(|o| {
                    let xa = x(a, o);
                    -(xa[0] * etr[(2 * a, o)] + xa[1] * etr[(2 * a + 1, o)])
                })
                .sum()
        });
        NormalEquations {
            per_curve,
            gradient,
        }
    }
}

/// The Gauss–Newton normal equations of [`Projection::normal_equations`].
pub(crate) struct NormalEquations {
    /// JᵀJ of each curve's residuals (parameters × parameters).
    pub(crate) per_curve: Vec<Mat<f64>>,
    /// Jᵀr over every curve (one column).
    pub(crate) gradient: Mat<f64>,
}

impl NormalEquations {
    /// JᵀJ over every curve, each curve's weighted by `weights[o]`.
    pub(crate) fn weighted(&self, weights: impl Fn(usize) -> f64) -> Mat<f64> {
        let p = self.gradient.nrows();
        let mut sum = Mat::<f64>::zeros(p, p);
        for (o, m) in self.per_curve.iter().enumerate() {
            sum += m * faer::Scale(weights(o));
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl LineSamples {
        /// The derivatives of pole `p`'s two basis columns with respect to a parameter with
        /// ∂λ/∂u = `c` (∂λ*/∂u = c*), written out apart from
        /// [`LineSamples::write_base_derivatives`] and [`ColumnMap`] to check them: (iω)^k [c/(iω − λ)² +
        /// c*/(iω − λ*)²] and (iω)^k i[c/(iω − λ)² − c*/(iω − λ*)²], as an (rows × 2) matrix.
        fn basis_derivative(&self, p: Complex64, c: Complex64) -> Mat<f64> {
            let mut d = Mat::zeros(self.rows(), 2);
            for (i, &w) in self.omega.iter().enumerate() {
                let f = quantity_factor(w, self.quantity);
                let s = Complex64::new(0.0, w);
                let (a1, a2) = (1.0 / (s - p), 1.0 / (s - p.conj()));
                let (d1, d2) = (c * a1 * a1, c.conj() * a2 * a2);
                Self::put(&mut d, i, 0, f * (d1 + d2));
                Self::put(&mut d, i, 1, f * Complex64::i() * (d1 - d2));
            }
            d
        }
    }

    impl Projection {
        /// ∂λ/∂u_j of parameter `j`: −σ = Re λ for ln σ (even j), i for ω_d (odd j).
        fn parameter_derivative(&self, j: usize) -> Complex64 {
            if j % 2 == 0 {
                Complex64::new(self.poles[j / 2].re, 0.0)
            } else {
                Complex64::i()
            }
        }

        /// The residual P⊥B in the samples' coordinates: Q times the one kept in Q's.
        fn residual(&self) -> Mat<f64> {
            let mut residual = self.residual_in_q.clone();
            self.qr.apply_q(&mut residual);
            residual
        }

        /// The residuals curve after curve (rows 2i, 2i + 1: line i's real and imaginary
        /// part), as one column.
        fn residual_vector(&self) -> Mat<f64> {
            let residual = self.residual();
            let rows = residual.nrows();
            Mat::from_fn(rows * residual.ncols(), 1, |i, _| {
                residual[(i % rows, i / rows)]
            })
        }

        /// The Jacobian of [`Self::residual_vector`], formed column by column (module docs):
        /// −(P⊥ D_j X + Q R̃⁻ᵀ S⁻¹ D_jᵀ R).
        fn jacobian(&self, samples: &LineSamples) -> Mat<f64> {
            let residual = self.residual();
            let (rows, curves) = (residual.nrows(), residual.ncols());
            let r = self.qr.r();
            let mut jac = Mat::<f64>::zeros(rows * curves, 2 * self.poles.len());
            for j in 0..2 * self.poles.len() {
                let k = j / 2;
                let d = samples.basis_derivative(self.poles[k], self.parameter_derivative(j));
                let x = Mat::from_fn(2, curves, |m, o| self.unknown(2 * k + m, o));
                let v = &d * &x;
                let mut w = Mat::<f64>::zeros(r.nrows(), curves);
                let dtr = d.transpose() * &residual;
                for m in 0..2 {
                    for o in 0..curves {
                        w[(2 * k + m, o)] = dtr[(m, o)] / self.scale[2 * k + m];
                    }
                }
                solve_lower_triangular_in_place(r.transpose(), w.as_mut(), Par::Seq);
                let mut q = Mat::<f64>::zeros(rows, r.nrows());
                q.subrows_mut(0, r.nrows())
                    .copy_from(Mat::<f64>::identity(r.nrows(), r.nrows()));
                self.qr.apply_q(&mut q);
                let qtv = q.transpose() * &v;
                let col = &q * (&w - &qtv) + &v;
                for o in 0..curves {
                    for i in 0..rows {
                        jac[(o * rows + i, j)] = -col[(i, o)];
                    }
                }
            }
            jac
        }
    }

    /// The pole of frequency `f` (Hz) and damping ratio `z`.
    fn pole(f: f64, z: f64) -> Complex64 {
        Complex64::new(-z * 2.0 * PI * f, 2.0 * PI * f)
    }

    /// `n` accelerance curves of `poles` at `freqs` (residue 1 + r + o + 0.3 r i of pole r in
    /// curve o) with a deterministic disturbance of amplitude `noise` on every line.
    fn accelerances(
        freqs: &[f64],
        poles: &[Complex64],
        n: usize,
        noise: f64,
    ) -> Vec<Vec<Complex64>> {
        (0..n)
            .map(|o| {
                freqs
                    .iter()
                    .enumerate()
                    .map(|(k, &f)| {
                        let s = Complex64::new(0.0, 2.0 * PI * f);
                        let h: Complex64 = poles
                            .iter()
                            .enumerate()
                            .map(|(r, &p)| {
                                let a = Complex64::new(1.0 + (r + o) as f64, 0.3 * r as f64);
                                a / (s - p) + a.conj() / (s - p.conj())
                            })
                            .sum();
                        let k = k as f64;
                        s * s * h + noise * Complex64::new((1.7 * k).sin(), k.cos())
                    })
                    .collect()
            })
            .collect()
    }

    /// Three poles over 5000 lines (three blocks, the last a short one): the blocks' stacked
    /// triangles give the unknowns of one QR of every row.
    #[test]
    fn blocks_solve_as_one_factorisation() {
        let freqs: Vec<f64> = (1..=5000).map(|k| 0.02 * f64::from(k)).collect();
        let poles = [pole(20.0, 0.01), pole(21.0, 0.02), pole(70.0, 0.005)];
        let curves = accelerances(&freqs, &poles, 3, 1e-2);
        let refs: Vec<&[Complex64]> = curves.iter().map(|c| c.as_slice()).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        let samples = LineSamples::new(&freqs, &refs, Quantity::Accelerance, &lines).unwrap();
        let one = samples.project(&poles).unwrap();
        let blocks = solve_by_blocks(&freqs, &refs, Quantity::Accelerance, &lines, &poles)
            .unwrap()
            .unwrap();
        // Each unknown's difference as a part of the curve it fits (its column's norm times
        // the difference, against the curve's norm): the lower residual is ~1e-5 of its
        // column here, so a relative test of the value itself would measure conditioning.
        for o in 0..refs.len() {
            let curve = samples.data.col(o).norm_l2();
            for c in 0..blocks.nrows() {
                let (a, b) = (one.unknown(c, o), blocks[(c, o)]);
                let part = (a - b).abs() * one.scale[c] / curve;
                assert!(part <= 1e-12, "{c}, {o}: {a} {b} ({part:e} of the curve)");
            }
        }
    }

    /// Two close modes and one far, two curves, 1 % noise: the analytic Jacobian matches
    /// central differences of the residuals within their own truncation error.
    #[test]
    fn the_jacobian_matches_central_differences() {
        let freqs: Vec<f64> = (1..=400).map(|k| 0.25 * f64::from(k)).collect();
        let truth = [pole(40.0, 0.02), pole(41.5, 0.03), pole(80.0, 0.01)];
        let curves = accelerances(&freqs, &truth, 2, 1e-3);
        let refs: Vec<&[Complex64]> = curves.iter().map(|c| c.as_slice()).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        let samples = LineSamples::new(&freqs, &refs, Quantity::Accelerance, &lines).unwrap();
        let start: Vec<Complex64> = truth
            .iter()
            .map(|p| p * Complex64::new(1.01, 0.002))
            .collect();
        let at = samples.project(&start).unwrap();
        let analytic = at.jacobian(&samples);
        let u: Vec<f64> = start.iter().flat_map(|p| [(-p.re).ln(), p.im]).collect();
        let poles_of = |u: &[f64]| -> Vec<Complex64> {
            u.chunks(2)
                .map(|c| Complex64::new(-c[0].exp(), c[1]))
                .collect()
        };
        for j in 0..u.len() {
            let h = 1e-6 * u[j].abs().max(1.0);
            let (mut up, mut um) = (u.clone(), u.clone());
            up[j] += h;
            um[j] -= h;
            let rp = samples.project(&poles_of(&up)).unwrap().residual_vector();
            let rm = samples.project(&poles_of(&um)).unwrap().residual_vector();
            let numeric = (&rp - &rm) * faer::Scale(0.5 / h);
            let norm = numeric.norm_l2();
            let diff = (numeric.col(0) - analytic.col(j)).norm_l2();
            assert!(
                diff < 1e-6 * norm,
                "parameter {j}: {diff:e} against {norm:e}"
            );
        }
    }

    /// The normal equations without the Jacobian equal JᵀJ and Jᵀr of the explicit Jacobian
    /// (itself checked against central differences above), curve by curve.
    #[test]
    fn normal_equations_match_the_explicit_jacobian() {
        let freqs: Vec<f64> = (1..=400).map(|k| 0.25 * f64::from(k)).collect();
        let truth = [pole(40.0, 0.02), pole(41.5, 0.03), pole(80.0, 0.01)];
        let curves = accelerances(&freqs, &truth, 3, 1e-3);
        let refs: Vec<&[Complex64]> = curves.iter().map(|c| c.as_slice()).collect();
        let lines: Vec<usize> = (0..freqs.len()).collect();
        let samples = LineSamples::new(&freqs, &refs, Quantity::Accelerance, &lines).unwrap();
        let start: Vec<Complex64> = truth
            .iter()
            .map(|p| p * Complex64::new(0.99, -0.003))
            .collect();
        let at = samples.project(&start).unwrap();
        let jac = at.jacobian(&samples);
        let normal = at.normal_equations(&samples);
        let rows = samples.rows();
        for o in 0..refs.len() {
            let block = jac.subrows(o * rows, rows);
            let want = block.transpose() * block;
            let diff = (&normal.per_curve[o] - &want).norm_l2();
            assert!(diff < 1e-10 * want.norm_l2(), "curve {o}: {diff:e}");
        }
        let want = jac.transpose() * at.residual_vector();
        let diff = (&normal.gradient - &want).norm_l2();
        assert!(diff < 1e-10 * want.norm_l2(), "gradient: {diff:e}");
    }
}
