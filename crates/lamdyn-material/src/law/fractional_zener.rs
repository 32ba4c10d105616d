//! Fractional-derivative Zener (standard linear solid) law.
//!
//! G*(ω) = (G0 + G∞ (iωτ)^α) / (1 + (iωτ)^α),  0 < α < 1
//!
//! with (iωτ)^α = (ωτ)^α e^{iαπ/2} (principal branch). G0 is the relaxed (ω → 0) modulus,
//! G∞ > G0 the unrelaxed (ω → ∞) one. The law has a non-negative relaxation spectrum, so it is
//! causal and passive [Bagley & Torvik 1983; Pritz 1996].

use super::ViscoelasticLaw;
use crate::error::{MaterialError, check};
use num_complex::Complex64;
use std::f64::consts::FRAC_PI_2;

/// Fractional Zener law G* = (G0 + G∞ (iωτ)^α)/(1 + (iωτ)^α).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractionalZener {
    g0_pa: f64,
    g_inf_pa: f64,
    tau_s: f64,
    alpha: f64,
}

const CONTEXT: &str = "fractional Zener law";

impl FractionalZener {
    /// Builds the law from G0 (relaxed modulus, Pa), G∞ (unrelaxed modulus, Pa), τ (relaxation
    /// time, s) and α (fractional order).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when a value is NaN or infinite, G0 ≤ 0, G∞ ≤ G0
    /// (negative loss), τ ≤ 0, or α outside (0, 1).
    pub fn new(g0_pa: f64, g_inf_pa: f64, tau_s: f64, alpha: f64) -> Result<Self, MaterialError> {
        check::positive(CONTEXT, "g0_pa", g0_pa)?;
        check::greater_than(
            CONTEXT,
            "g_inf_pa",
            g_inf_pa,
            "g0_pa",
            g0_pa,
            " (a passive material stiffens with frequency)",
        )?;
        check::positive(CONTEXT, "tau_s", tau_s)?;
        check::open_interval(CONTEXT, "alpha", alpha, 0.0, 1.0)?;
        Ok(Self {
            g0_pa,
            g_inf_pa,
            tau_s,
            alpha,
        })
    }

    /// The core of the sandwich-beam benchmark of Van Beeumen, Meerbergen & Michiels (2013),
    /// after Navarrete & Desmet: G0 = 350.4 kPa, G∞ = 3.062 GPa, τ = 8.230 ns, α = 0.675.
    pub fn sandwich_benchmark_core() -> Self {
        Self {
            g0_pa: 350.4e3,
            g_inf_pa: 3.062e9,
            tau_s: 8.230e-9,
            alpha: 0.675,
        }
    }

    /// Relaxed modulus G0, Pa.
    pub fn g0_pa(&self) -> f64 {
        self.g0_pa
    }
    /// Unrelaxed modulus G∞, Pa.
    pub fn g_inf_pa(&self) -> f64 {
        self.g_inf_pa
    }
    /// Relaxation time τ, s.
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
    /// Fractional order α.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }
}

impl ViscoelasticLaw for FractionalZener {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        let x = omega_rad_s * self.tau_s;
        if x <= 0.0 {
            return Complex64::new(self.g0_pa, 0.0);
        }
        let s = Complex64::from_polar(x.powf(self.alpha), self.alpha * FRAC_PI_2);
        (self.g0_pa + self.g_inf_pa * s) / (1.0 + s)
    }

    /// Exact: (iωτ)^α on the principal branch for ω = ω' + iσ (arg iωτ just past π/2 for
    /// σ ≪ ω'), the same expression as on the real axis.
    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        if omega.im == 0.0 {
            return self.modulus(omega.re);
        }
        let s = (Complex64::new(0.0, 1.0) * omega * self.tau_s).powf(self.alpha);
        (self.g0_pa + self.g_inf_pa * s) / (1.0 + s)
    }

    fn describe(&self) -> String {
        format!(
            "fractional Zener: G0 = {:.6e} Pa, Ginf = {:.6e} Pa, tau = {:.6e} s, alpha = {}",
            self.g0_pa, self.g_inf_pa, self.tau_s, self.alpha
        )
    }
}
