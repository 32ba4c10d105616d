//! ASTM E756-05 uniform (bare) beam.
//!
//! f_n = (C_n/l²) √(E H²/(12 ρ))  ⇔  E = 12 ρ l⁴ f_n² / (H² C_n²),   η = Δf_n/f_n.

use super::{ReducedModulus, Resonance, c_n, check_mode, clamped_free_root};
use crate::error::{MaterialError, check};
use crate::units::Quantity;
use num_complex::Complex64;

/// A uniform clamped–free beam: free length l, thickness H, density ρ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformBeam {
    length_m: f64,
    thickness_m: f64,
    density_kg_m3: f64,
}

const CONTEXT: &str = "uniform beam";

impl UniformBeam {
    /// Builds the beam from its free length (m), thickness (m) and density (kg/m³).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for a non-positive or non-finite value.
    pub fn new(length_m: f64, thickness_m: f64, density_kg_m3: f64) -> Result<Self, MaterialError> {
        check::si(CONTEXT, "length_m", length_m, Quantity::Length)?;
        check::si(CONTEXT, "thickness_m", thickness_m, Quantity::Thickness)?;
        check::si(CONTEXT, "density_kg_m3", density_kg_m3, Quantity::Density)?;
        Ok(Self {
            length_m,
            thickness_m,
            density_kg_m3,
        })
    }

    /// Free length l, m.
    pub fn length_m(&self) -> f64 {
        self.length_m
    }
    /// Thickness H, m.
    pub fn thickness_m(&self) -> f64 {
        self.thickness_m
    }
    /// Density ρ, kg/m³.
    pub fn density_kg_m3(&self) -> f64 {
        self.density_kg_m3
    }

    /// Wavenumber k_n = β_n/l of mode n, rad/m.
    pub fn wavenumber(&self, mode: usize) -> f64 {
        clamped_free_root(mode) / self.length_m
    }

    /// Forward model: resonance of mode n for a material E (Pa) with loss factor η.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0, E ≤ 0 or η < 0.
    pub fn resonance(
        &self,
        mode: usize,
        young_pa: f64,
        loss_factor: f64,
    ) -> Result<Resonance, MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "young_pa", young_pa)?;
        check::non_negative(CONTEXT, "loss_factor", loss_factor)?;
        let h = self.thickness_m;
        let ei = Complex64::new(young_pa, young_pa * loss_factor) * h.powi(3) / 12.0;
        let k = self.wavenumber(mode);
        Ok(Resonance::from_eigenvalue(
            mode,
            ei * k.powi(4) / (self.density_kg_m3 * h),
        ))
    }

    /// Reduction: E = 12 ρ l⁴ f_n²/(H² C_n²) and η = the measured modal loss factor.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0, f ≤ 0 or η < 0.
    pub fn reduce(
        &self,
        mode: usize,
        freq_hz: f64,
        loss_factor: f64,
    ) -> Result<ReducedModulus, MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "f_hz", freq_hz)?;
        check::non_negative(CONTEXT, "loss_factor", loss_factor)?;
        Ok(ReducedModulus {
            mode,
            storage_pa: self.young_from_frequency(mode, freq_hz),
            loss_factor,
        })
    }

    /// E = 12 ρ l⁴ f²/(H² C_n²), Pa (no checks).
    pub(crate) fn young_from_frequency(&self, mode: usize, freq_hz: f64) -> f64 {
        let cn = c_n(mode);
        12.0 * self.density_kg_m3 * self.length_m.powi(4) * freq_hz * freq_hz
            / (self.thickness_m * self.thickness_m * cn * cn)
    }
}
