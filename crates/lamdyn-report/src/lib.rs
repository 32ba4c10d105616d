//! # lamdyn-report
//!
//! Reports of the pipeline's results: charts rendered to SVG and PNG with an embedded font.
//!
//! | module | what |
//! |---|---|
//! | [`chart`] | a chart description (axes, series) rendered by plotters |
//! | [`ema`] | the stabilization diagram and the CMIF of an identification |

#![deny(missing_docs)]

pub mod chart;
pub mod ema;
mod error;

pub use chart::{Axis, Chart, Mark, Series};
pub use error::ReportError;
