//! # lamdyn-frf
//!
//! The FRF set shared by the test-data, identification and fit stages: frequency lines,
//! response channels (node, direction in the global frame), references (excitations), complex
//! values, and the physical quantity they hold.
//!
//! | item | what |
//! |---|---|
//! | [`FrfSet`] | responses × references × lines, with channel geometry and units |
//! | [`Quantity`] | receptance (m/N), mobility (m/s/N), accelerance (m/s²/N), conversions |
//! | [`FrfSet::rms`] | the paper's RMS FRF over channels (eq. 2, as RMS of magnitudes) |
//! | [`csv`] | a plain CSV layout for FRFs and channel tables |
//! | [`text`] | text files as instruments write them: encodings, separators, decimal commas |
//!
//! Convention: time dependence e^{+iωt}; H = X/F (response over force, the H1 estimator's
//! target). Frequencies in Hz on the axis, ω = 2πf in formulas.

#![deny(missing_docs)]

pub mod csv;
mod set;
pub mod text;

pub use set::{Channel, FrfError, FrfSet, Quantity};
