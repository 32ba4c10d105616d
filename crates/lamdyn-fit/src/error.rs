//! Errors of the fit crate.

use thiserror::Error;

/// What went wrong in synthesis, misfit or fit.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum FitError {
    /// Inputs that do not fit together (axes, channels, counts, values).
    #[error("{context}: {reason}")]
    Inconsistent {
        /// Which inputs.
        context: String,
        /// What is wrong, with the numbers.
        reason: String,
    },
    /// An error of the FE model.
    #[error(transparent)]
    Fem(#[from] lamdyn_fem::FemError),
    /// An error of the FRF data.
    #[error(transparent)]
    Frf(#[from] lamdyn_frf::FrfError),
    /// An error of the layered model.
    #[error(transparent)]
    Layered(#[from] lamdyn_layered::LayeredError),
    /// A law's parameters left the physical range.
    #[error(transparent)]
    Law(#[from] lamdyn_material::MaterialError),
    /// The direct solver failed.
    #[error("direct solve at {freq_hz:.4} Hz: {reason}")]
    DirectSolve {
        /// Frequency, Hz.
        freq_hz: f64,
        /// Why.
        reason: String,
    },
}

pub(crate) fn inconsistent(context: &str, reason: String) -> FitError {
    FitError::Inconsistent {
        context: context.into(),
        reason,
    }
}
