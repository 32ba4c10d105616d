//! # lamdyn-testbench
//!
//! The virtual test bench: simulated tests of a laminate with a known core, on the layered
//! model of lamdyn-layered (every layer meshed with 20-node hexahedra), of higher fidelity
//! than the homogenized shell the chain identifies.
//!
//! | module | what |
//! |---|---|
//! | [`cases`] | named cases: the CalculiX cross-check laminate |
//! | [`description`] | the TOML description of a virtual test, the built-in `roof` |
//! | [`impact`] | a simulated impact test: sensor grid, hammer, supports, accelerance FRFs, hammer hits as time signals, noise |
//!
//! Units: m, kg, s, N, Pa; eigenvalues ω² in rad²/s².

#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod cases;
pub mod description;
mod error;
pub mod impact;

pub use error::BenchError;
