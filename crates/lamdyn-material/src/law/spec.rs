//! Serialisable law descriptions for TOML and JSON inputs.
//!
//! ```toml
//! shear_law = { kind = "fractional_zener", g0_pa = 3.504e5, g_inf_pa = 3.062e9, tau_s = 8.23e-9, alpha = 0.675 }
//! ```
//!
//! Field names carry their SI unit. Unknown fields are rejected by the deserialiser, and
//! [`LawSpec::build`] checks the physics.

use super::{
    ConstantModulus, FractionalZener, GeneralizedMaxwell, PaperEq7Law, PronyTerm,
    TemperatureShifted, ViscoelasticLaw, WlfShift,
};
use crate::error::MaterialError;
use serde::{Deserialize, Serialize};

/// A law as written in an input file; `kind` selects the law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LawSpec {
    /// Paper eq. 7.
    PaperEq7 {
        /// Relaxed modulus E0, Pa.
        e0_pa: f64,
        /// Storage decay time μ, s.
        mu_s: f64,
        /// Loss decay time t0, s.
        t0_s: f64,
        /// Viscous constant c, Pa·s.
        c_pa_s: f64,
    },
    /// Fractional-derivative Zener.
    FractionalZener {
        /// Relaxed modulus, Pa.
        g0_pa: f64,
        /// Unrelaxed modulus, Pa.
        g_inf_pa: f64,
        /// Relaxation time, s.
        tau_s: f64,
        /// Fractional order in (0, 1).
        alpha: f64,
    },
    /// Generalized Maxwell (Prony series).
    GeneralizedMaxwell {
        /// Long-term modulus, Pa.
        g_e_pa: f64,
        /// Maxwell elements.
        terms: Vec<PronyTermSpec>,
    },
    /// Constant complex modulus.
    Constant {
        /// Storage modulus, Pa.
        storage_pa: f64,
        /// Loss factor.
        #[serde(default)]
        loss_factor: f64,
    },
    /// A law at another temperature through the WLF shift.
    Wlf {
        /// WLF C1.
        c1: f64,
        /// WLF C2, K.
        c2_k: f64,
        /// Temperature at which `law` is given, K.
        reference_temperature_k: f64,
        /// Temperature of use, K.
        temperature_k: f64,
        /// The law at the reference temperature.
        law: Box<LawSpec>,
    },
}

/// One Prony term as written in an input file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PronyTermSpec {
    /// Modulus of the term, Pa.
    pub g_pa: f64,
    /// Relaxation time, s.
    pub tau_s: f64,
}

impl LawSpec {
    /// Validates the description and builds the law.
    ///
    /// # Errors
    /// The law's own parameter checks ([`MaterialError::InvalidParameter`]).
    pub fn build(&self) -> Result<Box<dyn ViscoelasticLaw>, MaterialError> {
        Ok(match self {
            Self::PaperEq7 {
                e0_pa,
                mu_s,
                t0_s,
                c_pa_s,
            } => Box::new(PaperEq7Law::new(*e0_pa, *mu_s, *t0_s, *c_pa_s)?),
            Self::FractionalZener {
                g0_pa,
                g_inf_pa,
                tau_s,
                alpha,
            } => Box::new(FractionalZener::new(*g0_pa, *g_inf_pa, *tau_s, *alpha)?),
            Self::GeneralizedMaxwell { g_e_pa, terms } => {
                let terms = terms.iter().map(|t| PronyTerm {
                    g_pa: t.g_pa,
                    tau_s: t.tau_s,
                });
                Box::new(GeneralizedMaxwell::new(*g_e_pa, terms.collect())?)
            }
            Self::Constant {
                storage_pa,
                loss_factor,
            } => Box::new(ConstantModulus::new(*storage_pa, *loss_factor)?),
            Self::Wlf {
                c1,
                c2_k,
                reference_temperature_k,
                temperature_k,
                law,
            } => {
                let inner = law.build().map_err(|e| e.context("wlf.law"))?;
                let shift = WlfShift::new(*c1, *c2_k, *reference_temperature_k)?;
                Box::new(TemperatureShifted::new(inner, shift, *temperature_k)?)
            }
        })
    }
}
