//! A mesh's error taken out of a reduced model mode by mode.
//!
//! A mesh converges mode by mode: at a core scale s a mode's eigenvalue on a level of the mesh
//! ladder is λ_L = λ_∞ e^ε, with ε its own error (complex: the faces and the core converge at
//! different rates, so the loss factor moves too). A model fitted to measured FRFs on that
//! level would take ε up into the core's law. Instead each mode's faces and core stiffness are
//! scaled in its own direction: with y the elastic mode of rank r at Re s (an eigenvector of
//! Vᵀ(K_e + Re s K_c + K_s)V, Vᵀ M V = I) and λ the model's eigenvalue of that rank at s, real
//! α and β solve the first-order change to the wanted eigenvalue λ_L e^{−ε},
//!
//!   (α − 1)(1 + iη_e) yᵀK_e y + (β − 1) s yᵀK_c y = λ_L e^{−ε} − λ,
//!
//! (two real equations), and
//!
//!   K_e ← K_e + (α − 1)(yᵀK_e y) y yᵀ,   K_c ← K_c + (β − 1)(yᵀK_c y) y yᵀ,
//!
//! in [`PASSES`] passes (y is real, the mode complex). The mode's eigenvalue is then λ_∞ at the
//! s measured and close to it nearby (the faces and the core each carry their own share), the
//! other modes keep theirs (the y are orthogonal at one s, nearly so between the modes' own s),
//! and Z stays linear in s, so the FRFs and their derivatives keep their form.
//!
//! Checked against a mesh twice as fine in the tests (their figures are there).

use super::ReducedModel;
use faer::Mat;
use num_complex::Complex64;

/// One mode's error on the model's mesh ([module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeError {
    /// The core scale s = G*/G_a where the error holds.
    pub core_scale: Complex64,
    /// The mode's rank among the elastic ones at Re s (0: the lowest).
    pub rank: usize,
    /// ω² of the mode (rad²/s²), for the rigid-body floor: eigenvalues below 1e-6 of it are not
    /// elastic.
    pub target: f64,
    /// ε = ln(λ_L/λ_∞).
    pub ln_error: Complex64,
}

/// Scales outside [1/`SCALE_LIMIT`, `SCALE_LIMIT`] are refused. A coarse mesh's faces and
/// core are a few per cent too stiff, and the split moves them by no more than that
/// (docs/fit.md, "A correction mode by mode"); a larger scale means an error the faces and the
/// core do not make, such as a support's bounce whose patch the coarse mesh integrates
/// otherwise, or a pole matched to another branch.
pub const SCALE_LIMIT: f64 = 1.1;

/// Passes of [`ReducedModel::take_out_mode_errors`]: the real mode y is the complex one's
/// approximation (to the mode's loss), so one pass leaves a part of the error of the order of
/// the mode's loss factor and each further pass that part of what is left (the tests).
pub const PASSES: usize = 3;

impl ReducedModel {
    /// Takes each mode's error out of the model ([module docs](self)), in [`PASSES`] passes of
    /// the eigenvalue's first-order change, (α − 1) faces + (β − 1) core = λ_wanted − λ.
    /// Returns (α, β) per error, None where the mode is not found, the two equations are
    /// singular in the first pass (a mode whose faces and core do not set its eigenvalue, such
    /// as a support's bounce, or a core without loss), or a pass would take its scales outside
    /// [`SCALE_LIMIT`]; such a mode keeps the passes before.
    pub fn take_out_mode_errors(&mut self, errors: &[ModeError]) -> Vec<Option<[f64; 2]>> {
        let mut now: Vec<Option<Complex64>> =
            errors.iter().map(|e| self.elastic_eigenvalue(e)).collect();
        let wanted: Vec<Option<Complex64>> = now
            .iter()
            .zip(errors)
            .map(|(l, e)| l.map(|l| l * (-e.ln_error).exp()))
            .collect();
        let mut scales: Vec<Option<[f64; 2]>> =
            wanted.iter().map(|w| w.map(|_| [1.0; 2])).collect();
        let within = |x: f64| (1.0 / SCALE_LIMIT..=SCALE_LIMIT).contains(&x);
        for pass in 0..PASSES {
            if pass > 0 {
                now = errors.iter().map(|e| self.elastic_eigenvalue(e)).collect();
            }
            let steps: Vec<Option<Step>> = (0..errors.len())
                .map(|k| {
                    scales[k]?;
                    self.step_to(&errors[k], now[k]?, wanted[k]?)
                })
                .collect();
            for (k, step) in steps.into_iter().enumerate() {
                let Some(step) = step else {
                    if pass == 0 {
                        scales[k] = None;
                    }
                    continue;
                };
                let Some([a, b]) = scales[k] else { continue };
                let [alpha, beta] = step.scales;
                if !(within(a * alpha) && within(b * beta)) {
                    scales[k] = None;
                    continue;
                }
                rank_one(&mut self.k_elastic, &step.y, (alpha - 1.0) * step.faces);
                rank_one(&mut self.k_core, &step.y, (beta - 1.0) * step.core);
                scales[k] = Some([a * alpha, b * beta]);
            }
        }
        scales
    }

    /// The complex elastic eigenvalue of `e`'s rank at its core scale (increasing real part;
    /// below 1e-6 of its target is rigid).
    fn elastic_eigenvalue(&self, e: &ModeError) -> Option<Complex64> {
        let all = self.complex_eigenvalues(e.core_scale);
        all.into_iter()
            .filter(|l| l.re > 1e-6 * e.target)
            .nth(e.rank)
    }

    /// The step of `e`'s mode from its eigenvalue `now` to `wanted` to first order (module
    /// docs); None without the mode or where the two equations are singular.
    fn step_to(&self, e: &ModeError, now: Complex64, wanted: Complex64) -> Option<Step> {
        let y = self.elastic_mode(e.core_scale.re, e.rank, e.target)?;
        let (ke, kc) = (quadratic(&self.k_elastic, &y), quadratic(&self.k_core, &y));
        let faces = Complex64::new(1.0, self.elastic_loss) * ke;
        let core = e.core_scale * kc;
        let change = wanted - now;
        let det = faces.re * core.im - core.re * faces.im;
        if det.abs() <= 1e-3 * faces.norm() * core.norm() {
            return None;
        }
        let alpha = 1.0 + (change.re * core.im - core.re * change.im) / det;
        let beta = 1.0 + (faces.re * change.im - change.re * faces.im) / det;
        (alpha.is_finite() && beta.is_finite()).then_some(Step {
            y,
            scales: [alpha, beta],
            faces: ke,
            core: kc,
        })
    }

    /// The elastic eigenvector of `rank` of Vᵀ(K_e + s K_c + K_s)V at real scale `s` (unit
    /// length; eigenvalues below 1e-6 `target` are rigid), if the model has that many.
    fn elastic_mode(&self, s: f64, rank: usize, target: f64) -> Option<Vec<f64>> {
        let m = self.size();
        let k = Mat::from_fn(m, m, |i, j| {
            self.k_elastic[(i, j)] + s * self.k_core[(i, j)] + self.k_springs[(i, j)]
        });
        let evd = k.self_adjoint_eigen(faer::Side::Lower).ok()?;
        let (u, w) = (evd.U(), evd.S().column_vector());
        let first = (0..m).find(|&j| w[j] > 1e-6 * target)?;
        let j = first + rank;
        (j < m).then(|| (0..m).map(|i| u[(i, j)]).collect())
    }
}

/// One pass's step of a mode ([`ReducedModel::take_out_mode_errors`]).
struct Step {
    /// The mode, unit length.
    y: Vec<f64>,
    /// (α, β).
    scales: [f64; 2],
    /// yᵀK_e y.
    faces: f64,
    /// yᵀK_c y.
    core: f64,
}

/// yᵀ A y.
fn quadratic(a: &Mat<f64>, y: &[f64]) -> f64 {
    let m = y.len();
    (0..m)
        .map(|j| y[j] * (0..m).map(|i| a[(i, j)] * y[i]).sum::<f64>())
        .sum()
}

/// A += c y yᵀ.
fn rank_one(a: &mut Mat<f64>, y: &[f64], c: f64) {
    let m = y.len();
    for j in 0..m {
        for i in 0..m {
            a[(i, j)] += c * y[i] * y[j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf::{FrfBasis, MeasuredPoint, ObservedModel};
    use crate::inverse::small_test_plate;

    /// The free small plate on a 6 × 5 mesh, its first four elastic modes' errors taken against
    /// a 12 × 10 mesh at one core scale: afterwards its eigenvalues are the finer mesh's at that
    /// scale and, within a fraction of the error, at scales a factor 1.5 either side (the
    /// faces' and the core's shares split by α and β); a mode without an error keeps its
    /// eigenvalue.
    #[test]
    fn modes_take_the_finer_meshs_eigenvalues() {
        let plate = small_test_plate();
        let sensor = [MeasuredPoint {
            name: "s",
            point_m: [0.0, 0.0, 0.0],
            direction: [0.0, 0.0, 1.0],
        }];
        let basis = FrfBasis {
            modes: 16,
            ..FrfBasis::default()
        };
        let build = |elements: [usize; 2]| {
            ObservedModel::build(&plate, elements, 5e6, &basis, (&sensor, &sensor), &[]).unwrap()
        };
        let (mut coarse, fine) = (build([6, 5]), build([12, 10]));
        let s0 = Complex64::new(1.0, 0.6);
        // The elastic eigenvalues (the six rigid-body ones are within rounding of 0).
        let eig = |m: &ObservedModel, s: Complex64| -> Vec<Complex64> {
            let all = m.model().complex_eigenvalues(s);
            all.into_iter().filter(|l| l.re > 1.0).collect()
        };
        let (before, truth) = (eig(&coarse, s0), eig(&fine, s0));
        let errors: Vec<ModeError> = (0..4)
            .map(|rank| ModeError {
                core_scale: s0,
                rank,
                target: truth[rank].re,
                ln_error: (before[rank] / truth[rank]).ln(),
            })
            .collect();
        let worst = |a: &[Complex64], b: &[Complex64], n: usize| {
            (0..n)
                .map(|k| (a[k] / b[k] - 1.0).norm())
                .fold(0.0, f64::max)
        };
        let scales = coarse.take_out_mode_errors(&errors);
        assert!(scales.iter().all(Option::is_some), "{scales:?}");
        let error_before = worst(&before, &truth, 4);
        assert!(
            error_before > 1e-3,
            "the coarse mesh is off by {error_before:.2e}"
        );
        let after = eig(&coarse, s0);
        // Measured: 4e-3 … 2e-2 before, 2e-12 … 6e-11 after (three passes).
        let error_after = worst(&after, &truth, 4);
        assert!(error_after < 1e-8, "{error_after:.2e}");
        for factor in [1.0 / 1.5, 1.5] {
            let s = s0 * factor;
            let (was, now, wanted) = (eig(&build([6, 5]), s), eig(&coarse, s), eig(&fine, s));
            let (e_was, e_now) = (worst(&was, &wanted, 4), worst(&now, &wanted, 4));
            // Measured: 1.3e-3 against 2.0e-2 (s / 1.5), 1.2e-3 against 1.6e-2 (s x 1.5).
            assert!(
                e_now < 0.1 * e_was,
                "s x {factor}: {e_now:.2e} against {e_was:.2e}"
            );
        }
        // The fifth mode had no error given: it keeps its eigenvalue.
        assert!((after[4] / before[4] - 1.0).norm() < 1e-9);
    }
}
