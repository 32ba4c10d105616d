//! # lamdyn-report
//!
//! Reports of the pipeline's results: charts rendered to SVG and PNG with an embedded font,
//! mode-shape contour maps, and a self-contained HTML report.
//!
//! | module | what |
//! |---|---|
//! | [`chart`] | a chart description (axes, series) rendered by plotters |
//! | [`ema`] | the stabilization diagram and the CMIF of an identification |
//! | [`shape`] | a measured mode shape as a filled contour map over the plan |
//! | [`html`] | the self-contained HTML report with inline SVG figures |

#![deny(missing_docs)]

pub mod chart;
pub mod ema;
mod error;
pub mod html;
pub mod shape;

pub use chart::{Axis, Chart, Mark, Series};
pub use error::ReportError;
pub use html::HtmlReport;
pub use shape::shape_map;
