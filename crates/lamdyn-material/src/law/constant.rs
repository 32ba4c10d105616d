//! Constant complex modulus (hysteretic or "structural" damping).
//!
//! M*(ω) = M' (1 + i η), independent of ω. Not causal in the strict sense for η > 0 (a
//! frequency-independent loss needs a storage modulus that varies as (2η/π) ln ω), but the
//! usual model for glass and steel over a narrow band.

use super::ViscoelasticLaw;
use crate::error::{MaterialError, check};
use num_complex::Complex64;

/// Constant complex modulus M' (1 + iη).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantModulus {
    storage_pa: f64,
    loss_factor: f64,
}

const CONTEXT: &str = "constant modulus";

impl ConstantModulus {
    /// Builds the law from the storage modulus (Pa) and the loss factor.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] when a value is NaN or infinite, the storage
    /// modulus is ≤ 0 or the loss factor < 0.
    pub fn new(storage_pa: f64, loss_factor: f64) -> Result<Self, MaterialError> {
        check::positive(CONTEXT, "storage_pa", storage_pa)?;
        check::non_negative(CONTEXT, "loss_factor", loss_factor)?;
        Ok(Self {
            storage_pa,
            loss_factor,
        })
    }
}

impl ViscoelasticLaw for ConstantModulus {
    fn modulus(&self, _omega_rad_s: f64) -> Complex64 {
        Complex64::new(self.storage_pa, self.storage_pa * self.loss_factor)
    }

    fn describe(&self) -> String {
        format!(
            "constant: M' = {:.6e} Pa, eta = {}",
            self.storage_pa, self.loss_factor
        )
    }
}
