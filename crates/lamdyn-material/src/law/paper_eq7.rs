//! The paper's effective-modulus law, eq. 7, with its maximum-loss identities eqs. 8–9.
//!
//! E*(ω) = E0 e^{−μω} + i 2 c ω e^{−t0 ω}                                  (eq. 7)
//!
//! The paper writes the loss term as i 2 (c/t0) ω t0 e^{−t0 ω}; it is the same. With
//! η = E''/E' = (2c/E0) ω e^{−(t0−μ)ω}, setting dη/dω = 0 gives
//!
//! ω_ηmax = 1/(t0 − μ)                                                      (eq. 8)
//! η_max  = 2 c ω_ηmax e^{−1} / E0                                          (eq. 9)
//!
//! which is why t0 > μ is required. The law is a curve fit, not a causal material law
//! (method-notes §3): its storage modulus falls with frequency.

use super::ViscoelasticLaw;
use crate::error::{MaterialError, check};
use num_complex::Complex64;

/// Paper eq. 7: E*(ω) = E0 exp(−μω) + i 2cω exp(−t0 ω), ω in rad/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperEq7Law {
    e0_pa: f64,
    mu_s: f64,
    t0_s: f64,
    c_pa_s: f64,
}

const CONTEXT: &str = "paper eq. 7 law";

impl PaperEq7Law {
    /// Builds the law from E0 (relaxed modulus, Pa), μ (storage decay time, s), t0 (loss decay
    /// time, s) and c (viscous constant, Pa·s).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when a value is NaN or infinite, E0 ≤ 0, μ < 0,
    /// c < 0, or t0 ≤ μ (eq. 8 needs t0 > μ).
    pub fn new(e0_pa: f64, mu_s: f64, t0_s: f64, c_pa_s: f64) -> Result<Self, MaterialError> {
        check::positive(CONTEXT, "e0_pa", e0_pa)?;
        check::non_negative(CONTEXT, "mu_s", mu_s)?;
        check::greater_than(
            CONTEXT,
            "t0_s",
            t0_s,
            "mu_s",
            mu_s,
            " (eq. 8 needs t0 > mu)",
        )?;
        check::non_negative(CONTEXT, "c_pa_s", c_pa_s)?;
        Ok(Self {
            e0_pa,
            mu_s,
            t0_s,
            c_pa_s,
        })
    }

    /// The paper's Table 2 values: E0 = 67.45 GPa, μ = 0.686 ms, t0 = 4.295 ms, c = 1.617 MPa·s.
    pub fn paper_table2() -> Self {
        Self {
            e0_pa: 67.45e9,
            mu_s: 0.686e-3,
            t0_s: 4.295e-3,
            c_pa_s: 1.617e6,
        }
    }

    /// E0, the relaxed (ω = 0) modulus, Pa.
    pub fn e0_pa(&self) -> f64 {
        self.e0_pa
    }
    /// μ, decay time of the storage modulus, s.
    pub fn mu_s(&self) -> f64 {
        self.mu_s
    }
    /// t0, decay time of the loss modulus, s.
    pub fn t0_s(&self) -> f64 {
        self.t0_s
    }
    /// c, viscous constant, Pa·s.
    pub fn c_pa_s(&self) -> f64 {
        self.c_pa_s
    }

    /// Angular frequency of maximum loss factor, ω_ηmax = 1/(t0 − μ) in rad/s (eq. 8).
    pub fn omega_at_max_loss(&self) -> f64 {
        1.0 / (self.t0_s - self.mu_s)
    }

    /// Maximum loss factor η_max = 2 c ω_ηmax e^{−1} / E0 (eq. 9).
    pub fn max_loss_factor(&self) -> f64 {
        2.0 * self.c_pa_s * self.omega_at_max_loss() * (-1.0f64).exp() / self.e0_pa
    }
}

impl ViscoelasticLaw for PaperEq7Law {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        let w = omega_rad_s;
        Complex64::new(
            self.e0_pa * (-self.mu_s * w).exp(),
            2.0 * self.c_pa_s * w * (-self.t0_s * w).exp(),
        )
    }

    fn describe(&self) -> String {
        format!(
            "paper eq. 7: E0 = {:.6e} Pa, mu = {:.6e} s, t0 = {:.6e} s, c = {:.6e} Pa s",
            self.e0_pa, self.mu_s, self.t0_s, self.c_pa_s
        )
    }
}
