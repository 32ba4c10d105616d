//! The pipeline's error: what failed, with its causes as a source chain.
//!
//! Each layer's `Display` says only its own part ("stage 'model' failed", "measurement.frf");
//! the causes are in [`std::error::Error::source`], so a caller prints the whole chain the way
//! it likes (the CLI: `stage 'model' failed: invalid model '[model.spec]': ...`). Errors of the
//! other lamdyn crates keep their types ([`PipelineError::Frf`], ...), so a caller can still
//! match on them.
//!
//! Inside the crate, [`Context`] adds a layer to any error (`.context("measurement.channels")`)
//! and [`bail!`](crate::bail) / [`err!`](crate::err) make a described one.

/// An error of the pipeline (module docs).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// A stage of the chain failed; the cause is the source.
    #[error("stage '{stage}' failed")]
    Stage {
        /// The stage's name.
        stage: &'static str,
        /// Why.
        #[source]
        source: Box<PipelineError>,
    },
    /// What was being done when the error below it happened.
    #[error("{message}")]
    Context {
        /// What was being done (a file, a field, a step).
        message: String,
        /// The error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// Invalid input or a failed check, described (the field, file or line named).
    #[error("{0}")]
    Invalid(String),
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// FRF sets and their CSV files.
    #[error(transparent)]
    Frf(#[from] lamdyn_frf::FrfError),
    /// The shell FE model.
    #[error(transparent)]
    Fem(#[from] lamdyn_fem::FemError),
    /// The fit of the law.
    #[error(transparent)]
    Fit(#[from] lamdyn_fit::FitError),
    /// The modal identification.
    #[error(transparent)]
    Ema(#[from] lamdyn_ema::EmaError),
    /// UFF files.
    #[error(transparent)]
    Uff(#[from] lamdyn_uff::UffError),
    /// Laws, stacks and inverses.
    #[error(transparent)]
    Material(#[from] lamdyn_material::MaterialError),
    /// The layered model and the virtual test.
    #[error(transparent)]
    Bench(#[from] lamdyn_testbench::BenchError),
    /// Figures.
    #[error(transparent)]
    Report(#[from] lamdyn_report::ReportError),
    /// JSON (results, cache entries).
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// TOML written by the pipeline (the demo's job file).
    #[error(transparent)]
    TomlWrite(#[from] toml::ser::Error),
}

/// The pipeline's result.
pub type Result<T, E = PipelineError> = std::result::Result<T, E>;

/// Adds what was being done to an error (module docs).
pub trait Context<T> {
    /// Wraps the error with `message`.
    ///
    /// # Errors
    /// The wrapped error.
    fn context(self, message: impl Into<String>) -> Result<T>;

    /// Wraps the error with the message `f` makes (only on error).
    ///
    /// # Errors
    /// The wrapped error.
    fn with_context<S: Into<String>, F: FnOnce() -> S>(self, f: F) -> Result<T>;
}

impl<T, E> Context<T> for std::result::Result<T, E>
where
    E: std::error::Error + Send + Sync + 'static,
{
    fn context(self, message: impl Into<String>) -> Result<T> {
        self.map_err(|e| PipelineError::Context {
            message: message.into(),
            source: Box::new(e),
        })
    }

    fn with_context<S: Into<String>, F: FnOnce() -> S>(self, f: F) -> Result<T> {
        self.map_err(|e| PipelineError::Context {
            message: f().into(),
            source: Box::new(e),
        })
    }
}

impl<T> Context<T> for Option<T> {
    fn context(self, message: impl Into<String>) -> Result<T> {
        self.ok_or_else(|| PipelineError::Invalid(message.into()))
    }

    fn with_context<S: Into<String>, F: FnOnce() -> S>(self, f: F) -> Result<T> {
        self.ok_or_else(|| PipelineError::Invalid(f().into()))
    }
}

/// A described error ([`PipelineError::Invalid`]) from a format string.
#[macro_export]
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::PipelineError::Invalid(format!($($arg)*))
    };
}

/// Returns a described error ([`PipelineError::Invalid`]) from a format string.
#[macro_export]
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::err!($($arg)*))
    };
}

/// The whole chain of an error as one line: "outer: cause: cause".
pub fn chain_text(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        // A transparent layer repeats its source's text: show it once.
        if !text.ends_with(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_text_joins_the_layers_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let e: Result<()> = Err(io).context("cannot read 'a.csv'");
        let e = e.context("measurement.channels").unwrap_err();
        let staged = PipelineError::Stage {
            stage: "measurement",
            source: Box::new(e),
        };
        assert_eq!(
            chain_text(&staged),
            "stage 'measurement' failed: measurement.channels: cannot read 'a.csv': no such file"
        );
    }
}
