//! ASTM E756-05 sandwich beam: two identical base beams (E, H, ρ) bonded by a core (G_1*, H_1,
//! ρ_1), with T = H_1/H and D = ρ_1/ρ.
//!
//! Forward: RKU ([`crate::sandwich::RkuBeam`]) with faces E, H, core E_2 = 0, at k_n = β_n/l:
//! λ_s = EI_s* k_n⁴ / (ρH(2 + DT)). Reduction, with A = (f_s/f_n)²(2 + DT) B/2 and
//! B = 1/(6(1+T)²):
//!
//! G_1 = [(A − B) − 2(A − B)² − 2(Aη_s)²] (2π C_n E H H_1/l²) / [(1 − 2A + 2B)² + 4(Aη_s)²]
//! η_1 = Aη_s / [(A − B) − 2(A − B)² − 2(Aη_s)²]
//!
//! Derivation of exactness: symmetric RKU with E_2 = 0 gives EI_s = EH³/6 + EH(H + H_1)² g/(1+2g),
//! hence A* = A(1 + iη_s) = B + g/(1 + 2g); solving for g = (A* − B)/(1 − 2(A* − B)) and
//! G_1* = g E H H_1 k_n² with k_n² = 2π C_n/l² splits into exactly the two formulas above.

use super::{ReducedModulus, Resonance, UniformBeam, c_n, check_mode};
use crate::error::{MaterialError, check};
use crate::sandwich::RkuBeam;
use crate::units::Quantity;
use num_complex::Complex64;
use std::f64::consts::PI;

/// An E756 sandwich beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SandwichBeam {
    base: UniformBeam,
    base_young_pa: f64,
    core_thickness_m: f64,
    core_density_kg_m3: f64,
}

const CONTEXT: &str = "sandwich beam";

impl SandwichBeam {
    /// Builds the beam; `base` is one of the two identical base beams.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for non-positive or non-finite values.
    pub fn new(
        base: UniformBeam,
        base_young_pa: f64,
        core_thickness_m: f64,
        core_density_kg_m3: f64,
    ) -> Result<Self, MaterialError> {
        check::si(CONTEXT, "young_pa", base_young_pa, Quantity::StiffModulus)?;
        check::si(
            CONTEXT,
            "layer.thickness_m",
            core_thickness_m,
            Quantity::Thickness,
        )?;
        check::si(
            CONTEXT,
            "layer.density_kg_m3",
            core_density_kg_m3,
            Quantity::Density,
        )?;
        Ok(Self {
            base,
            base_young_pa,
            core_thickness_m,
            core_density_kg_m3,
        })
    }

    fn t(&self) -> f64 {
        self.core_thickness_m / self.base.thickness_m()
    }

    fn rku(&self) -> RkuBeam {
        let h = self.base.thickness_m();
        let e = Complex64::new(self.base_young_pa, 0.0);
        RkuBeam {
            h1_m: h,
            e1_pa: e,
            h2_m: self.core_thickness_m,
            e2_pa: Complex64::new(0.0, 0.0),
            h3_m: h,
            e3_pa: e,
        }
    }

    /// Forward model: (base beam, sandwich) resonances of mode n for a core with shear modulus
    /// G_1 (Pa) and loss factor η_1.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0, G_1 ≤ 0 or η_1 < 0.
    pub fn resonances(
        &self,
        mode: usize,
        core_shear_pa: f64,
        core_loss_factor: f64,
    ) -> Result<(Resonance, Resonance), MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "core shear_pa", core_shear_pa)?;
        check::non_negative(CONTEXT, "core loss_factor", core_loss_factor)?;
        let base = self.base.resonance(mode, self.base_young_pa, 0.0)?;
        let k = self.base.wavenumber(mode);
        let g = Complex64::new(core_shear_pa, core_shear_pa * core_loss_factor);
        let ei = self.rku().flexural_rigidity(g, k);
        let mass = 2.0 * self.base.density_kg_m3() * self.base.thickness_m()
            + self.core_density_kg_m3 * self.core_thickness_m;
        Ok((
            base,
            Resonance::from_eigenvalue(mode, ei * k.powi(4) / mass),
        ))
    }

    /// The standard's reduction from the base-beam frequency f_n (Hz), the sandwich frequency
    /// f_s (Hz) and the sandwich loss factor η_s.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for mode 0 or non-positive inputs;
    /// [`MaterialError::InvalidData`] when the data give a non-positive core modulus.
    pub fn reduce(
        &self,
        mode: usize,
        base_freq_hz: f64,
        sandwich_freq_hz: f64,
        sandwich_loss_factor: f64,
    ) -> Result<ReducedModulus, MaterialError> {
        check_mode(CONTEXT, mode)?;
        check::positive(CONTEXT, "f_base_hz", base_freq_hz)?;
        check::positive(CONTEXT, "f_sandwich_hz", sandwich_freq_hz)?;
        check::non_negative(CONTEXT, "loss_factor", sandwich_loss_factor)?;
        let t = self.t();
        let d = self.core_density_kg_m3 / self.base.density_kg_m3();
        let b = 1.0 / (6.0 * (1.0 + t) * (1.0 + t));
        let a = (sandwich_freq_hz / base_freq_hz).powi(2) * (2.0 + d * t) * b / 2.0;
        let (x, y) = (a - b, a * sandwich_loss_factor);
        let num = x - 2.0 * x * x - 2.0 * y * y;
        let l = self.base.length_m();
        let scale = 2.0
            * PI
            * c_n(mode)
            * self.base_young_pa
            * self.base.thickness_m()
            * self.core_thickness_m
            / (l * l);
        let g1 = num * scale / ((1.0 - 2.0 * a + 2.0 * b).powi(2) + 4.0 * y * y);
        if g1.is_nan() || g1 <= 0.0 {
            return Err(MaterialError::InvalidData {
                context: format!("sandwich reduction, mode {mode}"),
                reason: format!(
                    "A = {a:.6}, B = {b:.6}: the data give a non-positive core modulus ({g1:.3e} \
                     Pa); is f_sandwich above the shear-free limit and below the bonded one?"
                ),
            });
        }
        Ok(ReducedModulus {
            mode,
            storage_pa: g1,
            loss_factor: y / num,
        })
    }
}
