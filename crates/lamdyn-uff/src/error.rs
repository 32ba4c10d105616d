//! Errors of the UFF reader and writer: every one names the line (1-based) where the problem is.

use thiserror::Error;

/// What went wrong reading or writing a UFF file.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum UffError {
    /// Malformed content at a line of the file.
    #[error("line {line}: {reason}")]
    Syntax {
        /// 1-based line number (for binary data: the line the data starts on).
        line: usize,
        /// What is wrong, with the offending text.
        reason: String,
    },
    /// A value that cannot be written (e.g. a label too long for its field, NaN).
    #[error("cannot write: {0}")]
    Write(String),
    /// Data that does not convert to the requested form (e.g. FRFs with different axes).
    #[error("{0}")]
    Convert(String),
    /// A file that cannot be opened.
    #[error("cannot open '{path}': {reason}")]
    Open {
        /// The file.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// An error in a named file.
    #[error("'{path}' {source}")]
    InFile {
        /// The file.
        path: String,
        /// The error, naming the line.
        source: Box<UffError>,
    },
}

pub(crate) fn syntax(line: usize, reason: impl Into<String>) -> UffError {
    UffError::Syntax {
        line,
        reason: reason.into(),
    }
}
