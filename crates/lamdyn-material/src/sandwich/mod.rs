//! Exact sandwich-beam theory beside the paper's homogenization.
//!
//! - [`MeadMarkus`]: the sandwich beam of Mead & Markus (1969) — elastic faces in bending and
//!   extension, a core in shear only — with its apparent bending stiffness at a wavenumber or at
//!   a frequency, and the closed-form inverse G*(B, ω) ([`exact_inverse`]).
//! - [`RkuBeam`]: the Ross–Kerwin–Ungar (1959) complex flexural rigidity of a three-layer beam,
//!   which adds the core's extension and bending; RKU with E_2 → 0 is Mead–Markus.

mod mead_markus;
mod rku;

pub use mead_markus::{ExactCoreEstimate, MeadMarkus, MeadMarkusWave, exact_inverse};
pub use rku::RkuBeam;
