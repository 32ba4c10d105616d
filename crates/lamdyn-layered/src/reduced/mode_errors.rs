//! A mesh's error taken out of a reduced model mode by mode.
//!
//! A mesh converges mode by mode: at a core scale s a mode's eigenvalue on a level of the mesh
//! ladder is λ_L = λ_∞ e^ε, with ε its own error (complex: the faces and the core converge at
//! different rates, so the loss factor moves too). A model fitted to measured FRFs on that
//! level would take ε up into the core's law. Instead each mode's faces and core stiffness are
//! scaled in its own direction: with y the elastic mode of rank r at Re s (an eigenvector of
//! Vᵀ(K_e + Re s K_c + K_s)V, Vᵀ M V = I),
//!
//!   K_e ← T_α K_e T_α,   K_c ← T_β K_c T_β,   T_x = I + (√x − 1) y yᵀ,
//!
//! with real α and β from the first-order change of the model's complex eigenvalue λ of that
//! rank at s (eigenvector φ of Z = (1 + iη_e)K_e + s K_c + K_s, complex symmetric) to the
//! wanted λ_L e^{−ε},
//!
//!   (α − 1)(1 + iη_e) p(K_e) + (β − 1) s p(K_c) = λ_L e^{−ε} − λ,
//!   p(A) = (φᵀy)(φᵀA y) / φᵀφ   (= yᵀA y where φ = y),
//!
//! (two real equations) in [`PASSES`] passes (the modes' steps move each other). The mode's eigenvalue is then λ_∞ at the
//! s measured and close to it nearby (the faces and the core each carry their own share); the
//! other modes keep their Rayleigh quotients and move only through their couplings with y,
//! scaled by √α and √β (second order); each matrix keeps its inertia, so the core's stiffness
//! stays positive semi-definite at any s the fit visits; and Z stays
//! linear in s, so the FRFs and their derivatives keep their form. (Adding
//! (β − 1)(yᵀK_c y) y yᵀ instead, which keeps the other modes exactly at s, takes stiffness
//! from the directions the core barely stiffens, such as a support's bounce, and made the
//! supported close pair's fit settle on a core 200 times too stiff: docs/fit.md.)
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

/// Passes of [`ReducedModel::take_out_mode_errors`]: each mode's step is first order and moves
/// the other modes through their couplings, so each pass leaves a fraction of what was left
/// (about 1/40 on the tests' plate).
pub const PASSES: usize = 3;

impl ReducedModel {
    /// Takes each mode's error out of the model ([module docs](self)), in [`PASSES`] passes of
    /// the eigenvalue's first-order change to the wanted one.
    /// Returns (α, β) per error, None where the mode is not found, the two equations are
    /// singular in the first pass (a mode whose faces and core do not set its eigenvalue, such
    /// as a support's bounce, or a core without loss), or a pass would take its scales outside
    /// [`SCALE_LIMIT`]; such a mode keeps the passes before.
    pub fn take_out_mode_errors(&mut self, errors: &[ModeError]) -> Vec<Option<[f64; 2]>> {
        let mut now: Vec<Option<ElasticMode>> =
            errors.iter().map(|e| self.elastic_eigenpair(e)).collect();
        let wanted: Vec<Option<Complex64>> = now
            .iter()
            .zip(errors)
            .map(|(l, e)| l.as_ref().map(|l| l.value * (-e.ln_error).exp()))
            .collect();
        let mut scales: Vec<Option<[f64; 2]>> =
            wanted.iter().map(|w| w.map(|_| [1.0; 2])).collect();
        let within = |x: f64| (1.0 / SCALE_LIMIT..=SCALE_LIMIT).contains(&x);
        for pass in 0..PASSES {
            if pass > 0 {
                now = errors.iter().map(|e| self.elastic_eigenpair(e)).collect();
            }
            let steps: Vec<Option<Step>> = (0..errors.len())
                .map(|k| {
                    scales[k]?;
                    self.step_to(&errors[k], now[k].as_ref()?, wanted[k]?)
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
                scale_in_direction(&mut self.k_elastic, &step.y, alpha);
                scale_in_direction(&mut self.k_core, &step.y, beta);
                scales[k] = Some([a * alpha, b * beta]);
            }
        }
        scales
    }

    /// The complex elastic eigenvalue of `e`'s rank at its core scale and its eigenvector
    /// (increasing real part; below 1e-6 of its target is rigid).
    fn elastic_eigenpair(&self, e: &ModeError) -> Option<ElasticMode> {
        let z = self.dynamic_stiffness_matrix(0.0, e.core_scale);
        let (value, vector) = crate::seq::eigenpairs(z.as_ref())
            .into_iter()
            .filter(|(l, _)| l.re > 1e-6 * e.target)
            .nth(e.rank)?;
        Some(ElasticMode { value, vector })
    }

    /// The step of `e`'s mode from `now` to the eigenvalue `wanted` to first order (module
    /// docs); None without the real mode or where the two equations are singular.
    fn step_to(&self, e: &ModeError, now: &ElasticMode, wanted: Complex64) -> Option<Step> {
        let y = self.elastic_mode(e.core_scale.re, e.rank, e.target)?;
        let faces =
            Complex64::new(1.0, self.elastic_loss) * now.change_by_scaling(&self.k_elastic, &y);
        let core = e.core_scale * now.change_by_scaling(&self.k_core, &y);
        let change = wanted - now.value;
        let det = faces.re * core.im - core.re * faces.im;
        if det.abs() <= 1e-3 * faces.norm() * core.norm() {
            return None;
        }
        let alpha = 1.0 + (change.re * core.im - core.re * change.im) / det;
        let beta = 1.0 + (faces.re * change.im - change.re * faces.im) / det;
        (alpha.is_finite() && beta.is_finite()).then_some(Step {
            y,
            scales: [alpha, beta],
        })
    }

    /// The elastic eigenvector of `rank` of Vᵀ(K_e + s K_c + K_s)V at real scale `s` (unit
    /// length; eigenvalues below 1e-6 `target` are rigid), if the model has that many.
    fn elastic_mode(&self, s: f64, rank: usize, target: f64) -> Option<Vec<f64>> {
        let m = self.size();
        let k = Mat::from_fn(m, m, |i, j| {
            self.k_elastic[(i, j)] + s * self.k_core[(i, j)] + self.k_springs[(i, j)]
        });
        let (w, u) = crate::seq::symmetric_eigen(k.as_ref())?;
        let first = (0..m).find(|&j| w[j] > 1e-6 * target)?;
        let j = first + rank;
        (j < m).then(|| (0..m).map(|i| u[(i, j)]).collect())
    }
}

/// A complex eigenvalue of the model and its right eigenvector φ (Z φ = λ φ; Z is complex
/// symmetric, so φᵀ is its left one).
struct ElasticMode {
    value: Complex64,
    vector: Vec<Complex64>,
}

impl ElasticMode {
    /// ∂λ/∂x of A ← T_x A T_x at x = 1 ([`scale_in_direction`]), A's factor in Z left out:
    /// φᵀ (y uᵀ + u yᵀ) φ / (2 φᵀφ) = (φᵀy)(uᵀφ) / φᵀφ, u = A y.
    fn change_by_scaling(&self, a: &Mat<f64>, y: &[f64]) -> Complex64 {
        let phi = &self.vector;
        let dot = |v: &[f64]| -> Complex64 { phi.iter().zip(v).map(|(p, x)| p * x).sum() };
        let phi_phi: Complex64 = phi.iter().map(|p| p * p).sum();
        dot(y) * dot(&times(a, y)) / phi_phi
    }
}

/// One pass's step of a mode ([`ReducedModel::take_out_mode_errors`]).
struct Step {
    /// The mode, unit length.
    y: Vec<f64>,
    /// (α, β).
    scales: [f64; 2],
}

/// A ← T A T with T = I + γ y yᵀ, (1 + γ)² = `scale` > 0 (y unit length): yᵀAy is scaled by
/// `scale`, zᵀAz is kept for every z ⟂ y, and the couplings zᵀAy by √scale. A congruence keeps
/// A's inertia: a stiffness stays positive semi-definite with as many null directions (T⁻¹ of
/// A's) at any scale, where adding (scale − 1) yᵀAy · y yᵀ would take stiffness from the directions A
/// barely stiffens (a support's bounce in the core's matrix) and make it indefinite.
fn scale_in_direction(a: &mut Mat<f64>, y: &[f64], scale: f64) {
    let m = y.len();
    let gamma = scale.sqrt() - 1.0;
    let u = times(a, y);
    let q: f64 = y.iter().zip(&u).map(|(a, b)| a * b).sum();
    for j in 0..m {
        for i in 0..m {
            a[(i, j)] += gamma * (y[i] * u[j] + u[i] * y[j]) + gamma * gamma * q * y[i] * y[j];
        }
    }
}

/// A y.
fn times(a: &Mat<f64>, y: &[f64]) -> Vec<f64> {
    (0..y.len())
        .map(|i| y.iter().enumerate().map(|(j, v)| a[(i, j)] * v).sum())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf::{FrfBasis, MeasuredPoint, ObservedModel};
    use crate::inverse::small_test_plate;

    /// Scaling a stiffness in a direction keeps it positive semi-definite with as many null
    /// directions, scales yᵀAy and keeps zᵀAz for z ⟂ y; adding (scale − 1) yᵀAy · y yᵀ instead makes a
    /// matrix with a near-null direction indefinite.
    #[test]
    fn a_stiffness_scaled_in_a_direction_keeps_its_null_space() {
        // A = diag(0, 1e-4, 1, 4) in a rotated frame; y mostly along the stiff directions, with
        // a part along the null one (a support's bounce in the core's matrix).
        let (c, s) = (0.8f64, 0.6f64);
        let q = Mat::from_fn(4, 4, |i, j| match (i, j) {
            (0, 0) | (1, 1) => c,
            (0, 1) => -s,
            (1, 0) => s,
            (2, 2) | (3, 3) => c,
            (2, 3) => s,
            (3, 2) => -s,
            _ => 0.0,
        });
        let d = [0.0, 1e-4, 1.0, 4.0];
        let a = Mat::from_fn(4, 4, |i, j| {
            (0..4).map(|k| q[(i, k)] * d[k] * q[(j, k)]).sum()
        });
        let y = [0.3, 0.1, 0.7, 0.64];
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        let y: Vec<f64> = y.iter().map(|v| v / norm).collect();
        let quad = |m: &Mat<f64>, v: &[f64]| -> f64 {
            (0..4)
                .map(|i| (0..4).map(|j| v[i] * m[(i, j)] * v[j]).sum::<f64>())
                .sum()
        };
        let lowest = |m: &Mat<f64>| crate::seq::symmetric_eigen(m.as_ref()).unwrap().0[0];
        let mut scaled = a.clone();
        scale_in_direction(&mut scaled, &y, 0.9);
        assert!((quad(&scaled, &y) / quad(&a, &y) - 0.9).abs() < 1e-12);
        // Still positive semi-definite, one null direction (T⁻¹ of A's).
        assert!(lowest(&scaled).abs() < 1e-14, "{}", lowest(&scaled));
        let second = crate::seq::symmetric_eigen(scaled.as_ref()).unwrap().0[1];
        assert!(second > 1e-5, "{second}");
        // z ⟂ y keeps its quadratic form.
        let z = [y[1], -y[0], 0.0, 0.0];
        assert!((quad(&scaled, &z) - quad(&a, &z)).abs() < 1e-12);
        let mut added = a.clone();
        let shift = -0.1 * quad(&a, &y);
        for i in 0..4 {
            for j in 0..4 {
                added[(i, j)] += shift * y[i] * y[j];
            }
        }
        assert!(lowest(&added) < -1e-3, "{}", lowest(&added));
    }

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
        // Measured: 4e-3 … 2e-2 before, 2.9e-9 after (three passes; 7.5e-11 after four).
        let error_after = worst(&after, &truth, 4);
        assert!(error_after < 1e-8, "{error_after:.2e}");
        for factor in [1.0 / 1.5, 1.5] {
            let s = s0 * factor;
            let (was, now, wanted) = (eig(&build([6, 5]), s), eig(&coarse, s), eig(&fine, s));
            let (e_was, e_now) = (worst(&was, &wanted, 4), worst(&now, &wanted, 4));
            // Measured: 7.0e-4 against 2.0e-2 (s / 1.5), 5.7e-4 against 1.6e-2 (s x 1.5).
            assert!(
                e_now < 0.1 * e_was,
                "s x {factor}: {e_now:.2e} against {e_was:.2e}"
            );
        }
        // The fifth mode had no error given: it keeps its eigenvalue (measured: 3.7e-12).
        assert!((after[4] / before[4] - 1.0).norm() < 1e-9);
    }
}
