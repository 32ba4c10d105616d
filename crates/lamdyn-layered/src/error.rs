//! Errors of the layered model.

use thiserror::Error;

/// What went wrong building or solving a layered model.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum LayeredError {
    /// Input that cannot be built (a size, a layer, a support), naming the field.
    #[error("{0}")]
    Invalid(String),
    /// The solver failed (singular shifted matrix, no convergence).
    #[error("solver: {0}")]
    Solver(String),
    /// The convergence ladder stopped before its tolerance was met (how far it got).
    #[error("{0}")]
    Tolerance(String),
}
