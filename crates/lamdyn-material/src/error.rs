//! Errors of the material crate.
//!
//! Every variant names what was wrong and carries the offending numbers, so a caller (the CLI,
//! a job file reader) can prefix its own location with [`MaterialError::context`] and show the
//! message as is.

use thiserror::Error;

/// What went wrong in a law, a stack or an inverse.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum MaterialError {
    /// A parameter is NaN, infinite, or outside its physical range.
    #[error("{context}: {field} = {value} {requirement}")]
    InvalidParameter {
        /// What the parameter belongs to (`fractional Zener law`, `layers[1] ('PVB')`).
        context: String,
        /// The parameter's name as the user writes it (`t0_s`, `alpha`).
        field: String,
        /// The offending value, formatted.
        value: String,
        /// What it must satisfy (`must be positive`, `must lie in (0, 1)`).
        requirement: String,
    },
    /// A model that needs a particular stack was given another.
    #[error("{context}: {reason}")]
    UnsupportedStack {
        /// The model that refused the stack.
        context: String,
        /// Why, with the numbers.
        reason: String,
    },
    /// Data handed to a check or an inverse is unusable (too short, unsorted, NaN).
    #[error("{context}: {reason}")]
    InvalidData {
        /// Which data.
        context: String,
        /// What is wrong with it, naming the index where one applies.
        reason: String,
    },
    /// The measured laminate stiffness admits no core modulus under the chosen model.
    #[error("no core modulus at {freq_hz:.4} Hz ({model}): {reason}")]
    NoCoreSolution {
        /// Frequency of the line, Hz.
        freq_hz: f64,
        /// The inverse that was asked (`paper eq. 41`, `Mead-Markus`).
        model: String,
        /// Why, with the numbers.
        reason: String,
    },
    /// An iteration stopped before its tolerance was met.
    #[error(
        "{context}: no convergence after {iterations} iterations (last relative step \
         {last_step:.3e})"
    )]
    NoConvergence {
        /// What was iterated.
        context: String,
        /// Iterations done.
        iterations: usize,
        /// The last relative update.
        last_step: f64,
    },
}

impl MaterialError {
    /// Prefixes the error's context (or model) with a location such as `layers[1] ('PVB')`.
    pub fn context(self, location: &str) -> Self {
        let join = |c: String| format!("{location}: {c}");
        match self {
            Self::InvalidParameter {
                context,
                field,
                value,
                requirement,
            } => Self::InvalidParameter {
                context: join(context),
                field,
                value,
                requirement,
            },
            Self::UnsupportedStack { context, reason } => Self::UnsupportedStack {
                context: join(context),
                reason,
            },
            Self::InvalidData { context, reason } => Self::InvalidData {
                context: join(context),
                reason,
            },
            Self::NoCoreSolution {
                freq_hz,
                model,
                reason,
            } => Self::NoCoreSolution {
                freq_hz,
                model: join(model),
                reason,
            },
            Self::NoConvergence {
                context,
                iterations,
                last_step,
            } => Self::NoConvergence {
                context: join(context),
                iterations,
                last_step,
            },
        }
    }
}

/// Checks on scalar parameters, shared by laws, layers and beams.
pub(crate) mod check {
    use super::MaterialError;

    fn invalid(context: &str, field: &str, value: f64, requirement: &str) -> MaterialError {
        MaterialError::InvalidParameter {
            context: context.to_string(),
            field: field.to_string(),
            value: format!("{value}"),
            requirement: requirement.to_string(),
        }
    }

    /// `value` must be a finite number.
    pub fn finite(context: &str, field: &str, value: f64) -> Result<f64, MaterialError> {
        if value.is_finite() {
            Ok(value)
        } else {
            Err(invalid(context, field, value, "must be a finite number"))
        }
    }

    /// `value` must be finite and > 0.
    pub fn positive(context: &str, field: &str, value: f64) -> Result<f64, MaterialError> {
        finite(context, field, value)?;
        if value > 0.0 {
            Ok(value)
        } else {
            Err(invalid(context, field, value, "must be positive"))
        }
    }

    /// `value` must be finite and >= 0.
    pub fn non_negative(context: &str, field: &str, value: f64) -> Result<f64, MaterialError> {
        finite(context, field, value)?;
        if value >= 0.0 {
            Ok(value)
        } else {
            Err(invalid(context, field, value, "must not be negative"))
        }
    }

    /// `value` must lie in the open interval (lo, hi).
    pub fn open_interval(
        context: &str,
        field: &str,
        value: f64,
        lo: f64,
        hi: f64,
    ) -> Result<f64, MaterialError> {
        finite(context, field, value)?;
        if value > lo && value < hi {
            Ok(value)
        } else {
            Err(invalid(
                context,
                field,
                value,
                &format!("must lie in ({lo}, {hi})"),
            ))
        }
    }

    /// `value` must lie in the plausible SI range of `quantity` ([`crate::units`]).
    pub fn si(
        context: &str,
        field: &str,
        value: f64,
        quantity: crate::units::Quantity,
    ) -> Result<f64, MaterialError> {
        crate::units::check(quantity, value)
            .map_err(|why| invalid(context, field, value, &why.to_string()))
    }

    /// A Poisson ratio of an isotropic solid: in (-1, 0.5).
    pub fn poisson(context: &str, field: &str, value: f64) -> Result<f64, MaterialError> {
        open_interval(context, field, value, -1.0, 0.5)
    }

    /// `value` must exceed `bound` (named `bound_field` in the message).
    pub fn greater_than(
        context: &str,
        field: &str,
        value: f64,
        bound_field: &str,
        bound: f64,
        why: &str,
    ) -> Result<f64, MaterialError> {
        finite(context, field, value)?;
        if value > bound {
            Ok(value)
        } else {
            Err(invalid(
                context,
                field,
                value,
                &format!("must exceed {bound_field} = {bound}{why}"),
            ))
        }
    }
}
