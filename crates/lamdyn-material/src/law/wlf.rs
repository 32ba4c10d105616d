//! Time–temperature superposition with the Williams–Landel–Ferry shift factor.
//!
//! log10 a_T = −C1 (T − T_ref) / (C2 + T − T_ref)              [Williams, Landel & Ferry 1955]
//!
//! and the modulus at temperature T is the reference modulus at the reduced frequency:
//! M*(ω; T) = M*_ref(a_T ω). Above T_ref, a_T < 1 and the material is softer. Temperatures are in
//! kelvin (only differences enter, so T − T_ref is the same in °C). The formula has a pole at
//! T = T_ref − C2, below which it is meaningless.

use super::ViscoelasticLaw;
use crate::error::{MaterialError, check};
use num_complex::Complex64;

/// WLF constants C1 (dimensionless), C2 (K) and the reference temperature T_ref (K).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WlfShift {
    c1: f64,
    c2_k: f64,
    reference_temperature_k: f64,
}

const CONTEXT: &str = "WLF shift";

impl WlfShift {
    /// Builds the shift from C1, C2 (K) and T_ref (K).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when a value is NaN or infinite, C1 ≤ 0, C2 ≤ 0 or
    /// T_ref ≤ 0 K.
    pub fn new(c1: f64, c2_k: f64, reference_temperature_k: f64) -> Result<Self, MaterialError> {
        check::positive(CONTEXT, "c1", c1)?;
        check::positive(CONTEXT, "c2_k", c2_k)?;
        check::positive(CONTEXT, "reference_temperature_k", reference_temperature_k)?;
        Ok(Self {
            c1,
            c2_k,
            reference_temperature_k,
        })
    }

    /// The shift factor a_T at `temperature_k` (K): 10^(−C1 ΔT/(C2 + ΔT)), ΔT = T − T_ref.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when T is not finite or C2 + ΔT ≤ 0 (at or below the
    /// pole of the WLF formula).
    pub fn shift_factor(&self, temperature_k: f64) -> Result<f64, MaterialError> {
        check::positive(CONTEXT, "temperature_k", temperature_k)?;
        let dt = temperature_k - self.reference_temperature_k;
        let pole = self.reference_temperature_k - self.c2_k;
        check::greater_than(
            CONTEXT,
            "temperature_k",
            temperature_k,
            "T_ref - C2",
            pole,
            " (pole of the WLF formula)",
        )?;
        Ok(10f64.powf(-self.c1 * dt / (self.c2_k + dt)))
    }
}

/// Any law moved to another temperature by a WLF shift: M*(ω; T) = M*_ref(a_T ω).
#[derive(Debug, Clone)]
pub struct TemperatureShifted<L> {
    law: L,
    shift: WlfShift,
    temperature_k: f64,
    a_t: f64,
}

impl<L: ViscoelasticLaw> TemperatureShifted<L> {
    /// Wraps `law` (given at the shift's reference temperature) for use at `temperature_k`.
    ///
    /// # Errors
    /// As [`WlfShift::shift_factor`].
    pub fn new(law: L, shift: WlfShift, temperature_k: f64) -> Result<Self, MaterialError> {
        let a_t = shift.shift_factor(temperature_k)?;
        Ok(Self {
            law,
            shift,
            temperature_k,
            a_t,
        })
    }

    /// The shift factor a_T in use.
    pub fn shift_factor(&self) -> f64 {
        self.a_t
    }

    /// The wrapped reference law.
    pub fn reference_law(&self) -> &L {
        &self.law
    }
}

impl<L: ViscoelasticLaw> ViscoelasticLaw for TemperatureShifted<L> {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        self.law.modulus(self.a_t * omega_rad_s)
    }

    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        self.law.modulus_at_complex(self.a_t * omega)
    }

    fn describe(&self) -> String {
        format!(
            "{} shifted to T = {} K by WLF (C1 = {}, C2 = {} K, Tref = {} K, a_T = {:.6e})",
            self.law.describe(),
            self.temperature_k,
            self.shift.c1,
            self.shift.c2_k,
            self.shift.reference_temperature_k,
            self.a_t
        )
    }
}
