//! The refined poles checked in the context of the LSCF model the stabilization diagram was read
//! from: a refined pole replaces the diagram's only where the measured curves say so.
//!
//! **Why.** The refinement ([`crate::lsfd::refine`]) fits the poles with real lower and upper
//! residual terms beside them (the maximum-likelihood estimate for white noise *if* that model
//! held). The modes outside the band and the damped modes' tails do not fit those terms, and a
//! damped pole, broad and flat, takes up the misfit where the diagram's pole is exact. The
//! diagram's pole has the opposite weakness: the linearised LSCF is biased by noise, which the
//! refinement removes. The measurements, and the alternatives measured worse, are in
//! docs/ema.md ("Damped poles").
//!
//! **The context.** The LSCF model of order n is H_o(Ω) = B_o(Ω) A(Ω)⁻¹ with Ω = e^{−iωΔt} and
//! real coefficients ([`crate::lscf`]); its partial fractions (module `denominator`) span the
//! functions the numerators B_o can make (for several references the residues per curve are
//! free, where PolyMAX ties them into rank-one matrices). The roots of the diagram's highest
//! order hold the modes outside the band, the band's edges and the noise (its computational
//! roots); with the roots fixed the model is linear in the residues and the direct term d_o
//! (real).
//!
//! **The check.** With the physical poles' own roots replaced by the poles (x = e^{−λΔt}), the
//! residual sum of squares J of that model (the fixed columns projected out once, the residues
//! eliminated: variable projection [Golub & Pereyra 1973]) is computed at the diagram's poles
//! and, pole by pole, with one refined pole in place of its diagram pole. The refined pole is
//! taken where J drops by more than the 99 % point of χ² with two degrees of freedom times the
//! residual variance (J/dof at the diagram's poles): more than moving one pole's two parameters
//! takes from noise alone. Close poles are coupled (one of a close pair moved alone can fit
//! worse), so neighbours whose half-power bands overlap and neither of which passed alone are
//! tried together, with the χ² point of four degrees of freedom. On noise-free curves the
//! diagram's poles already fit the context model, and the refinement's moves bring no
//! significant drop; with noise the linearised estimator's bias does.

pub use crate::denominator::LscfContext;
use crate::denominator::{pair_columns, root_columns, scaled_real_matrix};
use crate::error::EmaError;
use crate::lsfd::{ModalFit, RefineLines, lsfd, refinement_lines};
use crate::projection::apply_transpose_q;
use faer::Mat;
use faer::linalg::solvers::{Qr, SolveLstsq};
use lamdyn_frf::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The context model on the refinement's lines: the data with the fixed columns projected out.
/// With the QR F = Q R of the fixed columns F (rows × k), the projection is taken in Q's
/// coordinates: Qᵀ(I − Q₁Q₁ᵀ)X is Qᵀ X with its first k rows zeroed, so the problem of the free
/// columns is that of the last rows of Qᵀ P and Qᵀ B, and Q is applied as its Householder
/// reflections, never formed.
struct ContextProblem<'a> {
    context: &'a LscfContext,
    /// Ω_k of each line.
    omega: Vec<Complex64>,
    /// The QR of the fixed columns (direct term and fixed roots).
    fixed: Qr<f64>,
    /// The last rows − k rows of Qᵀ B: the data with the fixed columns projected out, in Q's
    /// coordinates, one column per curve.
    data: Mat<f64>,
}

impl<'a> ContextProblem<'a> {
    /// The problem on `lines` with the roots of `context` fixed but those of `poles`.
    fn new(
        freqs_hz: &[f64],
        curves: &[&[Complex64]],
        lines: &[usize],
        context: &'a LscfContext,
        poles: &[Complex64],
    ) -> Self {
        let omega = context.omega(freqs_hz, lines);
        let mut cols: Vec<Vec<Complex64>> = vec![vec![Complex64::new(1.0, 0.0); omega.len()]];
        cols.extend(root_columns(&omega, &context.fixed_roots(poles)));
        let rows = 2 * lines.len();
        let fixed = scaled_real_matrix(&cols, rows).qr();
        let b = Mat::from_fn(rows, curves.len(), |row, o| {
            let h = curves[o][lines[row / 2]];
            if row % 2 == 0 { h.re } else { h.im }
        });
        let data = projected_out(&fixed, b);
        Self {
            context,
            omega,
            fixed,
            data,
        }
    }

    /// The residual sum of squares with the physical poles `poles` (their residues fitted);
    /// None where it is not finite.
    fn cost(&self, poles: &[Complex64]) -> Option<f64> {
        let mut cols = Vec::with_capacity(2 * poles.len());
        for p in poles {
            let (g1, g2) = pair_columns(&self.omega, self.context.root(*p));
            cols.push(g1);
            cols.push(g2);
        }
        let p = projected_out(&self.fixed, scaled_real_matrix(&cols, 2 * self.omega.len()));
        let x = p.qr().solve_lstsq(&self.data);
        let r = &self.data - &p * &x;
        let j = r.squared_norm_l2();
        j.is_finite().then_some(j)
    }

    /// Degrees of freedom of the residuals with `poles` physical poles.
    fn dof(&self, poles: usize) -> usize {
        let per_curve = 2 * self.omega.len();
        let unknowns = self.fixed.thin_R().nrows() + 2 * poles;
        (self.data.ncols() * per_curve.saturating_sub(unknowns)).max(1)
    }
}

/// The last rows of Qᵀ `m` for the QR `fixed` (rows × k): `m` with the span of the fixed
/// columns projected out, in Q's coordinates ([`ContextProblem`]).
fn projected_out(fixed: &Qr<f64>, mut m: Mat<f64>) -> Mat<f64> {
    apply_transpose_q(fixed, &mut m);
    let k = fixed.thin_R().nrows();
    m.subrows(k, m.nrows() - k).to_owned()
}

/// The poles taken (module docs): each refined pole that lowers the context's sum of squares
/// significantly by itself; then, of each pair of neighbours whose half-power bands overlap
/// (|f₁ − f₂| < ζ₁f₁ + ζ₂f₂) and neither of which was taken alone, both refined poles where
/// together they do (coupled in the fit: one of a close pair moved alone can fit worse); the
/// diagram's pole elsewhere.
fn checked_poles(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    lines: &[usize],
    context: &LscfContext,
    diagram: &[Complex64],
    refined: &[Complex64],
) -> Vec<Complex64> {
    let problem = ContextProblem::new(freqs_hz, curves, lines, context, diagram);
    let Some(base) = problem.cost(diagram) else {
        return diagram.to_vec();
    };
    let variance = base / problem.dof(diagram.len()) as f64;
    let significant = |members: &[usize]| {
        let mut trial = diagram.to_vec();
        for &r in members {
            trial[r] = refined[r];
        }
        let drop = problem.cost(&trial).map_or(0.0, |c| base - c);
        drop > chi_square_99(2 * members.len()) * variance
    };
    let alone: Vec<bool> = (0..diagram.len()).map(|r| significant(&[r])).collect();
    let mut taken: Vec<Complex64> = (0..diagram.len())
        .map(|r| if alone[r] { refined[r] } else { diagram[r] })
        .collect();
    for [a, b] in overlapping_pairs(diagram) {
        if !alone[a] && !alone[b] && significant(&[a, b]) {
            taken[a] = refined[a];
            taken[b] = refined[b];
        }
    }
    taken
}

/// Neighbours (by frequency) whose half-power bands overlap: |f₁ − f₂| < ζ₁f₁ + ζ₂f₂, as
/// indices into `poles`.
fn overlapping_pairs(poles: &[Complex64]) -> Vec<[usize; 2]> {
    let mut order: Vec<usize> = (0..poles.len()).collect();
    order.sort_by(|&a, &b| poles[a].im.total_cmp(&poles[b].im));
    let half_width = |p: Complex64| -p.re / (2.0 * PI);
    order
        .windows(2)
        .filter(|w| {
            let (a, b) = (poles[w[0]], poles[w[1]]);
            (b.norm() - a.norm()).abs() / (2.0 * PI) < half_width(a) + half_width(b)
        })
        .map(|w| [w[0], w[1]])
        .collect()
}

/// The 99 % point of χ² with `dof` degrees of freedom (Wilson–Hilferty: within 0.5 % from two
/// degrees of freedom up; 9.21 for two).
fn chi_square_99(dof: usize) -> f64 {
    let v = dof as f64;
    let a = 2.0 / (9.0 * v);
    v * (1.0 - a + 2.326_348 * a.sqrt()).powi(3)
}

/// The refined poles `refined` of [`crate::lsfd::refine_with`] (index-aligned with their
/// diagram poles `diagram`; the curves already checked by it), each checked against its diagram
/// pole in the LSCF model's `context` on the lines `fit_lines` chooses in `band_hz` (module
/// docs): the modal model of the poles taken ([`lsfd`]).
///
/// # Errors
/// As [`lsfd`].
#[allow(clippy::too_many_arguments)]
pub fn check_refined(
    freqs_hz: &[f64],
    curves: &[&[Complex64]],
    quantity: Quantity,
    diagram: &[Complex64],
    refined: &[Complex64],
    band_hz: [f64; 2],
    fit_lines: RefineLines,
    context: &LscfContext,
) -> Result<ModalFit, EmaError> {
    let band = crate::band::positive_lines(freqs_hz, band_hz);
    let lines = refinement_lines(freqs_hz, &band, diagram, fit_lines);
    let taken = checked_poles(freqs_hz, curves, &lines, context, diagram, refined);
    lsfd(freqs_hz, curves, quantity, &taken, band_hz)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_points_match_the_tables() {
        // 99 % points of χ² (Abramowitz & Stegun, table 26.8): 2, 4, 6, 10 degrees of freedom.
        for (dof, want) in [(2, 9.210), (4, 13.277), (6, 16.812), (10, 23.209)] {
            let got = chi_square_99(dof);
            assert!((got / want - 1.0).abs() < 5e-3, "{dof}: {got} vs {want}");
        }
    }

    #[test]
    fn overlapping_neighbours_are_paired() {
        let pole = |f: f64, z: f64| {
            let w = 2.0 * PI * f;
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        };
        let poles = [
            pole(40.056, 0.012),
            pole(15.0, 0.01),
            pole(40.0, 0.01),
            pole(65.0, 0.008),
        ];
        assert_eq!(overlapping_pairs(&poles), vec![[2, 0]]);
    }
}
