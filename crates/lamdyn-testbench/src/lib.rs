//! # lamdyn-testbench
//!
//! The virtual test bench: a layered model of a laminate of higher
//! fidelity than the homogenized shell the chain identifies — every layer meshed with 20-node
//! hexahedra — to produce test data with a known core.
//!
//! | module | what |
//! |---|---|
//! | [`cases`] | named cases: the CalculiX cross-check laminate |
//! | [`description`] | the TOML description of a virtual test, the built-in `roof` |
//! | [`frf`] | FRFs with a frequency-dependent core: reduced basis, and the direct check |
//! | [`hex20`] | the C3D20 element: shape functions, stiffness, consistent mass |
//! | [`inverse`] | the layered inverse: G* of the core per measured mode through this model |
//! | [`impact`] | a simulated impact test: sensor grid, hammer, supports, accelerance FRFs, hammer hits as time signals, noise |
//! | [`mesh`] | layered plates and shallow shells of hexahedra |
//! | [`system`] | sparse K per layer and M; lowest modes by shift-invert Lanczos |
//!
//! Units: m, kg, s, N, Pa; eigenvalues ω² in rad²/s².

#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod cases;
pub mod description;
mod error;
pub mod frf;
pub mod hex20;
pub mod impact;
pub mod inverse;
pub mod mesh;
pub mod seq;
pub mod system;

pub use error::BenchError;
