//! Generalized Maxwell law (Prony series).
//!
//! G(t)  = G_e + Σ_k g_k e^{−t/τ_k}                      (relaxation modulus)
//! G*(ω) = G_e + Σ_k g_k iωτ_k / (1 + iωτ_k)              (its Fourier transform)
//!
//! With G_e > 0, g_k > 0 and τ_k > 0 every term is a Maxwell element in parallel with a spring:
//! causal and passive by construction [Ferry 1980, ch. 3; Tschoegl 1989].

use super::ViscoelasticLaw;
use crate::error::{MaterialError, check};
use num_complex::Complex64;

/// One Maxwell element of a Prony series: strength g_k (Pa) and relaxation time τ_k (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PronyTerm {
    /// Modulus of the term, Pa.
    pub g_pa: f64,
    /// Relaxation time, s.
    pub tau_s: f64,
}

/// Generalized Maxwell law G*(ω) = G_e + Σ g_k iωτ_k/(1 + iωτ_k).
#[derive(Debug, Clone, PartialEq)]
pub struct GeneralizedMaxwell {
    g_e_pa: f64,
    terms: Vec<PronyTerm>,
}

const CONTEXT: &str = "generalized Maxwell law";

impl GeneralizedMaxwell {
    /// Builds the law from the long-term (equilibrium) modulus G_e (Pa) and the Prony terms.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when a value is NaN or infinite, G_e ≤ 0, or a term
    /// has g_k ≤ 0 or τ_k ≤ 0 (the field names the term: `terms[2].tau_s`).
    pub fn new(g_e_pa: f64, terms: Vec<PronyTerm>) -> Result<Self, MaterialError> {
        check::positive(CONTEXT, "g_e_pa", g_e_pa)?;
        for (k, t) in terms.iter().enumerate() {
            check::positive(CONTEXT, &format!("terms[{k}].g_pa"), t.g_pa)?;
            check::positive(CONTEXT, &format!("terms[{k}].tau_s"), t.tau_s)?;
        }
        Ok(Self { g_e_pa, terms })
    }

    /// Long-term modulus G_e, Pa.
    pub fn g_e_pa(&self) -> f64 {
        self.g_e_pa
    }

    /// The Prony terms.
    pub fn terms(&self) -> &[PronyTerm] {
        &self.terms
    }

    /// Relaxation modulus G(t) = G_e + Σ g_k exp(−t/τ_k) in Pa at time `t_s` ≥ 0.
    pub fn relaxation_modulus(&self, t_s: f64) -> f64 {
        self.g_e_pa
            + self
                .terms
                .iter()
                .map(|t| t.g_pa * (-t_s / t.tau_s).exp())
                .sum::<f64>()
    }
}

impl ViscoelasticLaw for GeneralizedMaxwell {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        let mut g = Complex64::new(self.g_e_pa, 0.0);
        for t in &self.terms {
            let iwt = Complex64::new(0.0, omega_rad_s * t.tau_s);
            g += t.g_pa * iwt / (1.0 + iwt);
        }
        g
    }

    /// Exact: the same sum with iωτ_k at complex ω.
    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        let mut g = Complex64::new(self.g_e_pa, 0.0);
        for t in &self.terms {
            let iwt = Complex64::new(0.0, 1.0) * omega * t.tau_s;
            g += t.g_pa * iwt / (1.0 + iwt);
        }
        g
    }

    fn describe(&self) -> String {
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|t| format!("({:.4e} Pa, {:.4e} s)", t.g_pa, t.tau_s))
            .collect();
        format!(
            "generalized Maxwell: G_e = {:.6e} Pa, terms [{}]",
            self.g_e_pa,
            terms.join(", ")
        )
    }
}
