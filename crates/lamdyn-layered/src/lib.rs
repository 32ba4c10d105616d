//! # lamdyn-layered
//!
//! The layered model of a laminated plate: every layer meshed with 20-node hexahedra, so the
//! core's shear is modelled as it is rather than through one effective modulus. The chain
//! identifies the core through it (`lamdyn run`'s layered inverse) and the virtual test bench
//! (lamdyn-testbench) simulates its tests with it.
//!
//! The operators are kept per layer: with layer l's stiffness K_l assembled at a reference
//! modulus and its mass M_l at a reference density,
//!
//!   K(ω) = Σ_l a_l(ω) K_l + K_s + iω C_s,  M = Σ_l b_l M_l,
//!
//! where a_l is a layer's modulus ratio (complex and frequency dependent for a viscoelastic
//! layer), b_l its density ratio and K_s, C_s the supports' springs and dashpots.
//!
//! | module | what |
//! |---|---|
//! | [`frf`] | FRFs between surface points and their derivative with respect to the core |
//! | [`hex20`] | the C3D20 element: shape functions, stiffness, consistent mass |
//! | [`mesh`] | layered plates and shallow shells of hexahedra, graded towards the edges |
//! | [`plan`] | the part's plan: a rectangle, or any quadrilateral mesh of the mid-surface (Gmsh) |
//! | [`probe`] | sensors and hammers at any point of the top surface (shape functions) |
//! | [`system`] | sparse K and M per layer, supports; lowest modes by shift-invert Lanczos |
//! | [`reduced`] | reduced basis over a range of core moduli; FRFs and complex eigenvalues |
//! | [`inverse`] | the core's G* per measured mode through the reduced model |
//! | [`sensitivity`] | how G* moves with the face modulus, thicknesses and densities |
//! | [`convergence`] | a ladder of meshes and Richardson extrapolation: the inverse converged to a tolerance |
//! | [`seq`] | sequential products and eigenvalues (same bits on any thread count) |
//! | [`supports`] | springs and dashpots at points of the bottom surface |
//!
//! Units: m, kg, s, N, Pa; eigenvalues ω² in rad²/s².

#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod convergence;
mod error;
pub mod frf;
pub mod hex20;
pub mod inverse;
pub mod mesh;
pub mod ordering;
pub mod plan;
pub mod probe;
pub mod reduced;
pub mod sensitivity;
pub mod seq;
pub mod supports;
pub mod system;

pub use error::LayeredError;
