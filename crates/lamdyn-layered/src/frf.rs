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
use crate::probe::SurfaceProbe;
use crate::reduced::ReducedModel;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use num_complex::Complex64;

/// A reduced layered model observed at sensors and driven at references.
pub struct ObservedModel {
    model: ReducedModel,
    /// R: n_sensors × m, each sensor's row u·d times the basis.
    sensors: Mat<c64>,
    /// F: m × n_references, the references' unit loads in the basis.
    loads: Mat<c64>,
    /// Vᵀ K_c V, complex for the products with complex vectors.
    core: Mat<c64>,
}

/// The receptance at one line and its derivative with respect to the core's scale s.
#[derive(Debug, Clone)]
pub struct LineReceptance {
    /// H: n_sensors × n_references, m/N.
    pub h: Mat<c64>,
    /// ∂H/∂s, m/N.
    pub dh_ds: Mat<c64>,
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
        let kc = model.core_matrix();
        let core = Mat::from_fn(m, m, |i, j| c64::new(kc[(i, j)], 0.0));
        Ok(Self {
            model,
            sensors: sensors_r,
            loads,
            core,
        })
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

    /// H and ∂H/∂s at ω (rad/s) for the core scale s (module docs).
    ///
    /// # Errors
    /// [`LayeredError::Solver`] where Z is singular (a non-finite result): an undamped
    /// resonance exactly on the line.
    pub fn receptance(
        &self,
        omega: f64,
        core_scale: Complex64,
    ) -> Result<LineReceptance, LayeredError> {
        let z = self.model.dynamic_stiffness_matrix(omega, core_scale);
        let lu = z.partial_piv_lu();
        let q = lu.solve(&self.loads);
        let dq = lu.solve(&self.core * &q);
        let h = &self.sensors * &q;
        let dh_ds = -(&self.sensors * &dq);
        let finite = |x: &Mat<c64>| {
            (0..x.nrows()).all(|i| {
                (0..x.ncols()).all(|j| x[(i, j)].re.is_finite() && x[(i, j)].im.is_finite())
            })
        };
        if !(finite(&h) && finite(&dh_ds)) {
            return Err(LayeredError::Solver(format!(
                "the reduced dynamic stiffness is singular at {:.4} Hz (core scale {core_scale:.4})",
                omega / (2.0 * std::f64::consts::PI)
            )));
        }
        Ok(LineReceptance { h, dh_ds })
    }
}
