//! The layered model's FRFs between points of its surface, with their derivative with respect
//! to the core's scale: what an FRF fit of the core's law needs at each measured line.
//!
//! With Z(s, ω) = Vᵀ[(1 + iη_e) K_e + s K_c + K_s + iω C_s − ω² M]V the reduced dynamic
//! stiffness ([`crate::reduced`]), R the sensors' rows (u·d at each sensor, [`SurfaceProbe`])
//! times the basis V and F = Vᵀ f the references' unit loads in the basis, the receptance
//! between every sensor and every reference and its derivative with respect to s are
//!
//!   H = R Z⁻¹ F,   ∂H/∂s = −R Z⁻¹ K_c Z⁻¹ F,
//!
//! both from one LU factorisation of Z per line (the derivative of an inverse, Golub & Van Loan
//! §2.1). The core's modulus enters only through s = G*(ω)/G_a, so the core may change across a
//! resonance (no modal superposition with constant modes). The basis must hold the references'
//! static residual vectors (pass their [`SurfaceProbe::load`] to [`ReducedModel::new`]); the
//! rigid-body modes of a free part are in it as modes of (K, M), so the residual mass at low
//! frequency is modelled.

use crate::error::LayeredError;
use crate::inverse::{LayeredPlate, PartModel};
use crate::probe::SurfaceProbe;
use crate::reduced::{ModeError, ReducedModel};
use crate::sensitivity::Input;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use num_complex::Complex64;

/// A reduced layered model observed at sensors and driven at references.
#[derive(Clone)]
pub struct ObservedModel {
    model: ReducedModel,
    /// R: n_sensors × m, each sensor's row u·d times the basis.
    sensors: Mat<c64>,
    /// F: m × n_references, the references' unit loads in the basis.
    loads: Mat<c64>,
    /// Vᵀ K_c V, complex for the products with complex vectors.
    core: Mat<c64>,
    /// Which parts of each input's derivative are not zero (`ReducedModel::input_parts`).
    input_parts: Vec<[bool; 5]>,
}

/// The receptance at one line and its derivatives with respect to the core's scale s and to
/// the inputs' changes δ.
#[derive(Debug, Clone)]
pub struct LineReceptance {
    /// H: n_sensors × n_references, m/N.
    pub h: Mat<c64>,
    /// ∂H/∂s, m/N.
    pub dh_ds: Mat<c64>,
    /// ∂H/∂δ_k for each input k the call was given changes for (empty without), m/N.
    pub dh_dinputs: Vec<Mat<c64>>,
}

/// How an input's change δ enters the model: A(δ) = A + f(δ) ∂A/∂ln θ with f(δ) = e^δ − 1 for
/// an input the matrices scale with exactly ([`Input::scales_exactly`]), else f(δ) = δ (first
/// order). Returns (f(δ), f′(δ)).
pub fn input_change(input: Input, delta: f64) -> (f64, f64) {
    if input.scales_exactly() {
        (delta.exp_m1(), delta.exp())
    } else {
        (delta, 1.0)
    }
}

/// A measured point where the model is read or driven: its name, position (m) and direction.
#[derive(Debug, Clone, Copy)]
pub struct MeasuredPoint<'a> {
    /// The channel's name (for errors).
    pub name: &'a str,
    /// Position, m.
    pub point_m: [f64; 3],
    /// Direction of the motion read or the force applied (any length).
    pub direction: [f64; 3],
}

/// The reduced basis of an [`ObservedModel::build`]: `modes` real modes at each core-modulus
/// ratio (to G_ref), continued by `krylov_orders` core-sensitivity terms, plus the references'
/// residual vectors ([`ReducedModel::with_orders`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrfBasis {
    /// Real modes per reference modulus.
    pub modes: usize,
    /// Reference moduli as ratios to G_ref.
    pub ratios: Vec<f64>,
    /// Terms of the core-sensitivity sequence.
    pub krylov_orders: usize,
}

impl Default for FrfBasis {
    /// 30 modes at 0.5 and 2 × G_ref, two orders: checked against full solves of the damped
    /// glass plate in lamdyn-testbench's `tests/frf_fit.rs` (its core's G' spans a factor 3.5
    /// over the band about one basis at its geometric mean).
    fn default() -> Self {
        Self {
            modes: 30,
            ratios: vec![0.5, 2.0],
            krylov_orders: 2,
        }
    }
}

impl ObservedModel {
    /// The model `model` read at `sensors` and driven at `references` (each a unit force along
    /// its direction).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for no sensor or no reference, or a probe naming a dof outside
    /// the model.
    pub fn new(
        model: ReducedModel,
        sensors: &[SurfaceProbe],
        references: &[SurfaceProbe],
    ) -> Result<Self, LayeredError> {
        if sensors.is_empty() || references.is_empty() {
            return Err(LayeredError::Invalid(format!(
                "{} sensor(s) and {} reference(s): an FRF needs at least one of each",
                sensors.len(),
                references.len()
            )));
        }
        let (n, m) = (model.basis.nrows(), model.size());
        let outside = sensors
            .iter()
            .chain(references)
            .flat_map(|p| p.entries())
            .any(|&(dof, _)| dof >= n);
        if outside {
            return Err(LayeredError::Invalid(format!(
                "a sensor or reference names a dof outside the model's {n}"
            )));
        }
        let row = |p: &SurfaceProbe, k: usize| {
            let v: f64 = p
                .entries()
                .iter()
                .map(|&(dof, w)| w * model.basis[(dof, k)])
                .sum();
            c64::new(v, 0.0)
        };
        let sensors_r = Mat::from_fn(sensors.len(), m, |i, k| row(&sensors[i], k));
        let loads = Mat::from_fn(m, references.len(), |k, j| row(&references[j], k));
        let core = complex(model.core_matrix());
        let input_parts = (0..model.inputs().len())
            .map(|k| model.input_parts(k))
            .collect();
        Ok(Self {
            model,
            sensors: sensors_r,
            loads,
            core,
            input_parts,
        })
    }

    /// `plate` meshed on `elements` with the core at `g_ref_pa`, reduced on `basis` with the
    /// residual vectors of `references`, read at `sensors`, with the derivatives for `inputs`.
    /// A point is placed on the top surface within the stack's thickness (a channel given on
    /// the mid-surface is half of it away).
    ///
    /// # Errors
    /// As [`crate::inverse::LayeredInverse::build`]; a point not on the part (its name and
    /// distance); no sensor or reference.
    pub fn build(
        plate: &LayeredPlate,
        elements: [usize; 2],
        g_ref_pa: f64,
        basis: &FrfBasis,
        (sensors, references): (&[MeasuredPoint], &[MeasuredPoint]),
        inputs: &[Input],
    ) -> Result<Self, LayeredError> {
        let part = PartModel::assemble(plate, elements, g_ref_pa)?;
        let thickness: f64 = plate.layers.iter().map(|l| l.thickness_m).sum();
        let tolerance = thickness * (1.0 + 1e-6);
        let locate = |p: &MeasuredPoint| {
            SurfaceProbe::locate(&part.mesh, p.point_m, p.direction, tolerance, p.name)
        };
        let sensors = sensors.iter().map(locate).collect::<Result<Vec<_>, _>>()?;
        let references = references
            .iter()
            .map(locate)
            .collect::<Result<Vec<_>, _>>()?;
        let n = part.system.n_dofs;
        let loads: Vec<Vec<f64>> = references.iter().map(|r| r.load(n)).collect();
        let shift = -(2.0 * std::f64::consts::PI).powi(2);
        let mut model = ReducedModel::with_orders(
            &part.system,
            &part.cores,
            &basis.ratios,
            basis.modes,
            &loads,
            shift,
            basis.krylov_orders,
        )?;
        model.set_elastic_loss(part.face_loss)?;
        part.add_input_derivatives(&mut model, plate, elements, g_ref_pa, inputs)?;
        Self::new(model, &sensors, &references)
    }

    /// Number of sensors.
    pub fn n_sensors(&self) -> usize {
        self.sensors.nrows()
    }

    /// Number of references.
    pub fn n_references(&self) -> usize {
        self.loads.ncols()
    }

    /// Size of the reduced basis.
    pub fn basis_size(&self) -> usize {
        self.model.size()
    }

    /// The reduced model.
    pub fn model(&self) -> &ReducedModel {
        &self.model
    }

    /// H and ∂H/∂s at ω (rad/s) for the core scale s (module docs), the inputs as built.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] where Z is singular (a non-finite result): an undamped
    /// resonance exactly on the line.
    pub fn receptance(
        &self,
        omega: f64,
        core_scale: Complex64,
    ) -> Result<LineReceptance, LayeredError> {
        self.receptance_with_inputs(omega, core_scale, &[])
    }

    /// Takes each mode's mesh error out of the model
    /// ([`ReducedModel::take_out_mode_errors`]); returns (α, β) per error, None where left.
    pub fn take_out_mode_errors(&mut self, errors: &[ModeError]) -> Vec<Option<[f64; 2]>> {
        let scales = self.model.take_out_mode_errors(errors);
        self.core = complex(self.model.core_matrix());
        scales
    }

    /// The inputs whose changes [`Self::receptance_with_inputs`] takes, in order.
    pub fn inputs(&self) -> Vec<Input> {
        self.model.inputs()
    }

    /// H, ∂H/∂s and ∂H/∂δ_k at ω (rad/s) for the core scale s with the inputs changed by
    /// `deltas` (ln θ/θ₀, one per [`Self::inputs`], or none for the inputs as built):
    /// Z = Z₀ + Σ f(δ_k) ∂Z/∂ln θ_k ([`input_change`]), ∂H/∂δ_k = −R Z⁻¹ f′(δ_k) ∂Z/∂ln θ_k Z⁻¹ F,
    /// all from one LU of Z.
    ///
    /// # Errors
    /// As [`Self::receptance`]; [`LayeredError::Invalid`] for a count of changes other than
    /// none or one per input.
    pub fn receptance_with_inputs(
        &self,
        omega: f64,
        core_scale: Complex64,
        deltas: &[f64],
    ) -> Result<LineReceptance, LayeredError> {
        let inputs = self.model.inputs();
        if !deltas.is_empty() && deltas.len() != inputs.len() {
            return Err(LayeredError::Invalid(format!(
                "{} input change(s) for a model with {} input(s)",
                deltas.len(),
                inputs.len()
            )));
        }
        let at = (omega, core_scale);
        let mut z = self.model.dynamic_stiffness_matrix(omega, core_scale);
        // Z += Σ f(δ_k) ∂Z/∂ln θ_k and ∂Z/∂s = K_c + Σ f(δ_k) ∂K_c/∂ln θ_k; the inputs'
        // derivatives ∂H/∂δ_k = −C Z⁻¹ f'(δ_k) (∂Z/∂ln θ_k) q, each without its matrix formed.
        let mut core = None::<Mat<c64>>;
        let mut slopes: Vec<f64> = Vec::with_capacity(deltas.len());
        for (k, (&input, &delta)) in inputs.iter().zip(deltas).enumerate() {
            let (f, df) = input_change(input, delta);
            slopes.push(df);
            if f == 0.0 {
                continue;
            }
            self.model
                .add_input_derivative(k, at, self.input_parts[k], f, &mut z);
            let dc = self.model.input_core_derivative(k);
            let c = core.get_or_insert_with(|| self.core.clone());
            for j in 0..dc.ncols() {
                for (ci, &di) in c.col_as_slice_mut(j).iter_mut().zip(dc.col_as_slice(j)) {
                    *ci += c64::new(f * di, 0.0);
                }
            }
        }
        let lu = z.partial_piv_lu();
        let q = lu.solve(&self.loads);
        let dq = lu.solve(core.as_ref().unwrap_or(&self.core) * &q);
        let h = &self.sensors * &q;
        let dh_ds = -(&self.sensors * &dq);
        let dh_dinputs: Vec<Mat<c64>> = slopes
            .iter()
            .enumerate()
            .map(|(k, &df)| {
                let dz_q = self
                    .model
                    .input_derivative_times(k, at, self.input_parts[k], &q);
                let dh = &self.sensors * lu.solve(&dz_q);
                let scale = c64::new(-df, 0.0);
                Mat::from_fn(dh.nrows(), dh.ncols(), |i, j| dh[(i, j)] * scale)
            })
            .collect();
        let finite = |x: &Mat<c64>| {
            (0..x.nrows()).all(|i| {
                (0..x.ncols()).all(|j| x[(i, j)].re.is_finite() && x[(i, j)].im.is_finite())
            })
        };
        if !(finite(&h) && finite(&dh_ds) && dh_dinputs.iter().all(finite)) {
            return Err(LayeredError::Solver(format!(
                "the reduced dynamic stiffness is singular at {:.4} Hz (core scale \
                 {core_scale:.4})",
                omega / (2.0 * std::f64::consts::PI)
            )));
        }
        Ok(LineReceptance {
            h,
            dh_ds,
            dh_dinputs,
        })
    }
}

/// `a` as a complex matrix, for the products with complex vectors.
fn complex(a: &Mat<f64>) -> Mat<c64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| c64::new(a[(i, j)], 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inverse::small_test_plate_on;

    /// A point at (x, y) from the plate's corner (the plan is centred on the origin).
    fn point(name: &str, x: f64, y: f64, direction: [f64; 3]) -> MeasuredPoint<'_> {
        MeasuredPoint {
            name,
            point_m: [x - 0.25, y - 0.2, 0.0],
            direction,
        }
    }

    fn supported_model() -> ObservedModel {
        let plate = small_test_plate_on(0.2, [2e4, 2e4, 5e4], [5.0, 5.0, 20.0], 0.0);
        let sensors = [
            point("s1", 0.11, 0.07, [0.0, 0.0, 1.0]),
            point("s2", 0.37, 0.29, [0.0, 0.0, 1.0]),
            point("s3", 0.25, 0.33, [1.0, 0.0, 0.0]),
        ];
        let references = [point("hammer", 0.13, 0.31, [0.0, 0.0, 1.0])];
        let basis = FrfBasis {
            modes: 12,
            ..FrfBasis::default()
        };
        ObservedModel::build(
            &plate,
            [6, 5],
            5e6,
            &basis,
            (&sensors, &references),
            &Input::ALL,
        )
        .unwrap()
    }

    /// ∂H/∂s and every ∂H/∂δ_k against central differences of H itself (step 1e-5; the
    /// difference's truncation error is O(h²) ≈ 1e-10 relative, its rounding about 1e-16/h,
    /// so 1e-6 is safe and an error in a term fails it by orders of magnitude).
    #[test]
    fn derivatives_match_central_differences() {
        let model = supported_model();
        let inputs = model.inputs();
        assert_eq!(inputs.len(), Input::ALL.len());
        let omega = 2.0 * std::f64::consts::PI * 180.0;
        let s = Complex64::new(1.3, 0.8);
        let deltas: Vec<f64> = (0..inputs.len()).map(|k| 0.01 * (k as f64 - 3.0)).collect();
        let at = model.receptance_with_inputs(omega, s, &deltas).unwrap();
        let norm = |m: &Mat<c64>| m.norm_l2();
        let h = 1e-5;
        let step = |ds: Complex64, k: Option<usize>, sign: f64| {
            let mut d = deltas.clone();
            if let Some(k) = k {
                d[k] += sign * h;
            }
            model
                .receptance_with_inputs(omega, s + ds * sign, &d)
                .unwrap()
                .h
        };
        let central = |ds: Complex64, k: Option<usize>| {
            (step(ds, k, 1.0) - step(ds, k, -1.0)) * faer::Scale(c64::new(0.5 / h, 0.0))
        };
        let fd_s = central(Complex64::new(h, 0.0), None);
        let e = norm(&(&fd_s - &at.dh_ds)) / norm(&at.dh_ds);
        assert!(e < 1e-6, "dH/ds: {e:.2e}");
        for k in 0..inputs.len() {
            let fd = central(Complex64::new(0.0, 0.0), Some(k));
            let e = norm(&(&fd - &at.dh_dinputs[k])) / norm(&at.dh_dinputs[k]);
            assert!(e < 1e-6, "dH/d{:?}: {e:.2e}", inputs[k]);
        }
    }

    /// The receptance is symmetric between two points (the consistent point load).
    #[test]
    fn receptance_is_reciprocal() {
        let plate = small_test_plate_on(0.2, [2e4, 2e4, 5e4], [5.0, 5.0, 20.0], 0.0);
        let a = [point("a", 0.11, 0.07, [0.0, 0.0, 1.0])];
        let b = [point("b", 0.37, 0.29, [0.3, 0.0, 1.0])];
        let basis = FrfBasis {
            modes: 12,
            ..FrfBasis::default()
        };
        let build = |s: &[MeasuredPoint], r: &[MeasuredPoint]| {
            ObservedModel::build(&plate, [6, 5], 5e6, &basis, (s, r), &[]).unwrap()
        };
        let (ab, ba) = (build(&a, &b), build(&b, &a));
        // Each basis holds only its own reference's residual vector: the two agree to the
        // basis's truncation, far below the response itself.
        let w = 2.0 * std::f64::consts::PI * 60.0;
        let s = Complex64::new(1.0, 0.5);
        let (x, y) = (
            ab.receptance(w, s).unwrap().h[(0, 0)],
            ba.receptance(w, s).unwrap().h[(0, 0)],
        );
        assert!((x - y).norm() < 1e-3 * x.norm(), "{x} against {y}");
    }

    /// A reference off the part is refused with its name and distance; a wrong count of input
    /// changes is refused.
    #[test]
    fn points_off_the_part_and_wrong_changes_are_refused() {
        let plate = small_test_plate_on(0.2, [2e4, 2e4, 5e4], [0.0; 3], 0.0);
        let sensors = [point("s1", 0.11, 0.07, [0.0, 0.0, 1.0])];
        let off = [MeasuredPoint {
            point_m: [0.0, 0.0, 0.05],
            ..point("hammer", 0.0, 0.0, [0.0, 0.0, 1.0])
        }];
        let basis = FrfBasis {
            modes: 8,
            ..FrfBasis::default()
        };
        let Err(e) = ObservedModel::build(&plate, [4, 4], 5e6, &basis, (&sensors, &off), &[])
        else {
            panic!("a hammer 5 cm above the plate was placed");
        };
        let text = e.to_string();
        assert!(
            text.contains("hammer") && text.contains("not on the part"),
            "{text}"
        );
        let model = supported_model();
        let e = model
            .receptance_with_inputs(100.0, Complex64::new(1.0, 0.1), &[0.0; 2])
            .unwrap_err();
        assert!(e.to_string().contains("2 input change(s)"), "{e}");
    }
}
