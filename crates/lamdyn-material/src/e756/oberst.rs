//! ASTM E756-05 Oberst beam: a damping layer (E_1, η_1, thickness H_1 = T H, density ρ_1 = D ρ)
//! bonded on one side of a uniform base beam (E, H, ρ).
//!
//! Forward (two bonded layers, M = E_1*/E):
//! EI_c* = (E H³/12) (1 + 4MT + 6MT² + 4MT³ + M²T⁴)/(1 + MT),  λ_c = EI_c* k_n⁴ / (ρH + ρ_1H_1).
//!
//! Reduction of the standard, with α = (f_c/f_n)²(1 + DT) and β = 4 + 6T + 4T²:
//! E_1 = E [(α − β) + √((α − β)² − 4T²(1 − α))] / (2T³)
//! η_1 = η_c (1 + MT)(1 + 4MT + 6MT² + 4MT³ + M²T⁴) / [MT (3 + 6T + 4T² + 2MT³ + M²T⁴)]
//!
//! The η_1 formula is the first-order (small-loss) inverse of the forward model and the E_1
//! formula ignores the loss's effect on frequency; [`OberstBeam::reduce_exact`] solves the same
//! quadratic with complex α* = α(1 + iη_c) instead, exactly.

use super::{ReducedModulus, Resonance, UniformBeam, check_mode};
use crate::error::{MaterialError, check};
use crate::units::Quantity;
use num_complex::Complex64;

/// An Oberst beam: base beam, its modulus, and the damping layer's thickness and density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OberstBeam {
    base: UniformBeam,
    base_young_pa: f64,
    layer_thickness_m: f64,
    layer_density_kg_m3: f64,
}

const CONTEXT: &str = "Oberst beam";

impl OberstBeam {
    /// Builds the beam.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for non-positive or non-finite values.
    pub fn new(
        base: UniformBeam,
        base_young_pa: f64,
        layer_thickness_m: f64,
        layer_density_kg_m3: f64,
    ) -> Result<Self, MaterialError> {
        check::si(CONTEXT, "young_pa", base_young_pa, Quantity::StiffModulus)?;
        check::si(
            CONTEXT,
            "layer.thickness_m",
            layer_thickness_m,
            Quantity::Thickness,
        )?;
        check::si(
            CONTEXT,
            "layer.density_kg_m3",
            layer_density_kg_m3,
            Quantity::Density,
        )?;
        Ok(Self {
            base,
            base_young_pa,
            layer_thickness_m,
            layer_density_kg_m3,
        })
    }

    fn t(&self) -> f64 {
        self.layer_thickness_m / self.base.thickness_m()
    }
    fn d(&self) -> f64 {
        self.layer_density_kg_m3 / self.base.density_kg_m3()
    }

    /// (1 + 4MT + 6MT² + 4MT³ + M²T⁴)/(1 + MT): EI_c / (E H³/12).
    fn stiffness_ratio(m: Complex64, t: f64) -> Complex64 {
        (1.0 + m * (4.0 * t + 6.0 * t * t + 4.0 * t.powi(3)) + m * m * t.powi(4)) / (1.0 + m * t)
    }

    /// Forward model: (bare base beam, composite) resonances of mode n for a layer with Young's
    /// modulus E_1 (Pa) and loss factor η_1; the base beam is lossless.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0, E_1 ≤ 0 or η_1 < 0.
    pub fn resonances(
        &self,
        mode: usize,
        layer_young_pa: f64,
        layer_loss_factor: f64,
    ) -> Result<(Resonance, Resonance), MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "layer young_pa", layer_young_pa)?;
        check::non_negative(CONTEXT, "layer loss_factor", layer_loss_factor)?;
        let base = self.base.resonance(mode, self.base_young_pa, 0.0)?;
        let h = self.base.thickness_m();
        let m =
            Complex64::new(layer_young_pa, layer_young_pa * layer_loss_factor) / self.base_young_pa;
        let ei = self.base_young_pa * h.powi(3) / 12.0 * Self::stiffness_ratio(m, self.t());
        let mass =
            self.base.density_kg_m3() * h + self.layer_density_kg_m3 * self.layer_thickness_m;
        let k = self.base.wavenumber(mode);
        Ok((
            base,
            Resonance::from_eigenvalue(mode, ei * k.powi(4) / mass),
        ))
    }

    /// The standard's reduction from the bare-beam frequency f_n (Hz), the composite frequency f_c
    /// (Hz) and the composite loss factor η_c.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0 or non-positive inputs;
    /// [`MaterialError::InvalidData`] when the data give no positive modulus (the composite is
    /// not stiffer per unit mass than the bare beam).
    pub fn reduce(
        &self,
        mode: usize,
        base_freq_hz: f64,
        composite_freq_hz: f64,
        composite_loss_factor: f64,
    ) -> Result<ReducedModulus, MaterialError> {
        let alpha = self.alpha(mode, base_freq_hz, composite_freq_hz, composite_loss_factor)?;
        let (t, beta) = (self.t(), self.beta());
        let disc = (alpha - beta).powi(2) - 4.0 * t * t * (1.0 - alpha);
        let m = ((alpha - beta) + disc.max(0.0).sqrt()) / (2.0 * t.powi(3));
        if !(disc >= 0.0 && m > 0.0) {
            return Err(self.no_modulus(mode, alpha));
        }
        let n = 1.0 + 4.0 * m * t + 6.0 * m * t * t + 4.0 * m * t.powi(3) + m * m * t.powi(4);
        let eta = composite_loss_factor * (1.0 + m * t) * n
            / (m * t * (3.0 + 6.0 * t + 4.0 * t * t + 2.0 * m * t.powi(3) + m * m * t.powi(4)));
        Ok(ReducedModulus {
            mode,
            storage_pa: m * self.base_young_pa,
            loss_factor: eta,
        })
    }

    /// The exact complex inverse of [`OberstBeam::resonances`]: the standard's quadratic in M
    /// with α* = (f_c/f_n)²(1 + iη_c)(1 + DT).
    ///
    /// # Errors
    /// As [`OberstBeam::reduce`].
    pub fn reduce_exact(
        &self,
        mode: usize,
        base_freq_hz: f64,
        composite_freq_hz: f64,
        composite_loss_factor: f64,
    ) -> Result<ReducedModulus, MaterialError> {
        let alpha = self.alpha(mode, base_freq_hz, composite_freq_hz, composite_loss_factor)?;
        let alpha_c = Complex64::new(alpha, alpha * composite_loss_factor);
        let (t, beta) = (self.t(), self.beta());
        let disc = (alpha_c - beta) * (alpha_c - beta) - 4.0 * t * t * (1.0 - alpha_c);
        let m = ((alpha_c - beta) + disc.sqrt()) / (2.0 * t.powi(3));
        if m.re <= 0.0 {
            return Err(self.no_modulus(mode, alpha));
        }
        Ok(ReducedModulus {
            mode,
            storage_pa: m.re * self.base_young_pa,
            loss_factor: m.im / m.re,
        })
    }

    fn beta(&self) -> f64 {
        let t = self.t();
        4.0 + 6.0 * t + 4.0 * t * t
    }

    fn alpha(&self, mode: usize, f_n: f64, f_c: f64, eta_c: f64) -> Result<f64, MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "f_base_hz", f_n)?;
        check::positive(CONTEXT, "f_composite_hz", f_c)?;
        check::non_negative(CONTEXT, "loss_factor", eta_c)?;
        Ok((f_c / f_n).powi(2) * (1.0 + self.d() * self.t()))
    }

    fn no_modulus(&self, mode: usize, alpha: f64) -> MaterialError {
        MaterialError::InvalidData {
            context: format!("Oberst reduction, mode {mode}"),
            reason: format!(
                "alpha = (f_c/f_n)^2 (1 + D T) = {alpha:.6} gives no positive layer modulus (needs \
                 alpha > 1)"
            ),
        }
    }
}
