//! Errors of the EMA crate.

use thiserror::Error;

/// What went wrong in identification.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum EmaError {
    /// Inputs that do not fit together or are out of range, naming the input.
    #[error("{what}: {reason}")]
    Invalid {
        /// Which input (band, orders, FRFs, time data, ...).
        what: String,
        /// What is wrong, with the numbers.
        reason: String,
    },
}

pub(crate) fn invalid(what: &str, reason: String) -> EmaError {
    EmaError::Invalid {
        what: what.into(),
        reason,
    }
}

/// Every curve has one value per frequency line.
pub(crate) fn check_curves(
    freqs_hz: &[f64],
    curves: &[&[num_complex::Complex64]],
) -> Result<(), EmaError> {
    match curves
        .iter()
        .enumerate()
        .find(|(_, c)| c.len() != freqs_hz.len())
    {
        Some((o, c)) => Err(invalid(
            "FRFs",
            format!(
                "curve {o} has {} values for {} frequency lines",
                c.len(),
                freqs_hz.len()
            ),
        )),
        None => Ok(()),
    }
}
