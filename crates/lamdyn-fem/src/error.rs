//! Errors of the FE crate. Messages name the element, node, line or file.

use thiserror::Error;

/// What went wrong building or solving an FE model.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum FemError {
    /// A mesh file could not be read or parsed.
    #[error("{}", mesh_file_message(path, *line, reason))]
    MeshFile {
        /// The file.
        path: String,
        /// 1-based line number (0 when not tied to a line).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The mesh is unusable (bad node, bad element, unused node).
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A parameter is out of range.
    #[error("{context}: {field} = {value} {requirement}")]
    InvalidParameter {
        /// What it belongs to.
        context: String,
        /// The parameter.
        field: String,
        /// The value, formatted.
        value: String,
        /// What it must satisfy.
        requirement: String,
    },
    /// A point could not be mapped to a node.
    #[error("point {index} at ({x}, {y}, {z}) m: {reason}")]
    Locate {
        /// Index of the point in the list given.
        index: usize,
        /// Coordinates, m.
        x: f64,
        /// y, m.
        y: f64,
        /// z, m.
        z: f64,
        /// Why.
        reason: String,
    },
    /// A factorization failed (the matrix is not positive definite at the shift, or a zero
    /// pivot occurred).
    #[error("factorization of K - sigma M failed at sigma = {shift:.6e} rad^2/s^2: {reason}")]
    Factorization {
        /// The shift, rad²/s².
        shift: f64,
        /// Why.
        reason: String,
    },
    /// The eigensolver stopped before all wanted modes converged.
    #[error(
        "modal solver: {converged} of {wanted} modes converged after {restarts} restarts (largest \
         residual {max_residual:.3e})"
    )]
    NoConvergence {
        /// Modes converged.
        converged: usize,
        /// Modes wanted.
        wanted: usize,
        /// Restarts done.
        restarts: usize,
        /// Largest Ritz residual among the wanted.
        max_residual: f64,
    },
    /// The Sturm sequence count disagrees with the modes found.
    #[error(
        "Sturm check: {count} eigenvalues below {cutoff:.6e} rad^2/s^2 but {returned} modes \
         returned; modes were missed"
    )]
    SturmMismatch {
        /// Cut-off, rad²/s².
        cutoff: f64,
        /// Negative pivots of LDLᵀ(K − cutoff·M).
        count: usize,
        /// Modes returned below the cut-off.
        returned: usize,
    },
    /// Writing an output file failed.
    #[error("cannot write '{path}': {reason}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
}

/// "error reading 'FILE' line N: why", without the line when the error is not tied to one.
fn mesh_file_message(path: &str, line: usize, reason: &str) -> String {
    if line == 0 {
        format!("error reading '{path}': {reason}")
    } else {
        format!("error reading '{path}' line {line}: {reason}")
    }
}

pub(crate) fn check_positive(context: &str, field: &str, v: f64) -> Result<f64, FemError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(FemError::InvalidParameter {
            context: context.into(),
            field: field.into(),
            value: format!("{v}"),
            requirement: if v.is_finite() {
                "must be positive".into()
            } else {
                "must be a finite number".into()
            },
        })
    }
}
