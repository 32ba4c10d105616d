//! Errors of the report crate.

use thiserror::Error;

/// What went wrong while drawing or writing a report.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReportError {
    /// plotters could not draw the chart.
    #[error("drawing the chart failed: {0}")]
    Draw(String),
    /// The PNG encoder failed.
    #[error("encoding the PNG failed: {0}")]
    Png(String),
}
