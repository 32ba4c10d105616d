//! Errors of the test bench.

use lamdyn_layered::LayeredError;
use thiserror::Error;

/// What went wrong building or solving a bench model.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum BenchError {
    /// A description that cannot be built, naming the field.
    #[error("{0}")]
    Invalid(String),
    /// The solver failed (singular shifted matrix, no convergence).
    #[error("solver: {0}")]
    Solver(String),
    /// The layered model failed.
    #[error(transparent)]
    Model(#[from] LayeredError),
}
