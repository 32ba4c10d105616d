//! # lamdyn-ema
//!
//! Experimental modal analysis: from impact-test FRFs to poles, damping and mode shapes.
//!
//! | module | what |
//! |---|---|
//! | [`identify`] | the whole chain on an FRF set: diagram, selection, refinement, modes |
//! | [`lscf`] | LSCF / RFP-Z common-denominator poles at many orders in one pass |
//! | [`stabilization`] | stabilization diagram, automatic and targeted pole selection |
//! | [`lsfd`] | residues with lower/upper residuals, synthesis, FRAC, pole refinement |
//! | [`local_residues`] | each mode's residues from the lines around its pole: the shapes |
//! | `local_refit` | the refinement's last step: each pole standing alone refitted on its own lines |
//! | `pole_fit` | Levenberg–Marquardt on the poles, the residues eliminated |
//! | `projection` | the residue problem of given poles solved and differentiated (variable projection) |
//! | `rank_one` | the joint pole fit with rank-one residues (shape times participation) |
//! | `denominator` | the LSCF model's roots and their partial-fraction columns |
//! | [`context`] | the refined poles checked in the LSCF model's context (its other roots fixed) |
//! | [`noise`] | each curve's noise level from its line-to-line second differences |
//! | [`quality`] | each mode's verdict: sound, doubtful or a smear over a cluster |
//! | [`second_shape`] | whether a pole's curves hold a second shape under it (two close modes) |
//! | [`shapes`] | MAC, MPC, MPD, real modes, CMIF |
//! | [`spectra`] | H1/H2/Hv and coherence from hammer hits, force and exponential windows |
//! | [`welch`] | H1/H2/Hv and coherence from continuous excitation (Welch averaging) |
//! | [`band`] | the lines of a band, edges with a slack for rounded frequency axes |

#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod band;
mod columns;
mod companion;
pub mod context;
mod denominator;
mod error;
pub mod identify;
mod local_refit;
pub mod local_residues;
pub mod lscf;
pub mod lsfd;
pub mod noise;
mod pole_fit;
mod projection;
pub mod quality;
mod rank_one;
mod residual_spread;
pub mod second_shape;
pub mod shapes;
pub mod spectra;
pub mod stabilization;
#[cfg(test)]
mod test_frfs;
pub mod thin_qr;
pub mod welch;

pub use error::EmaError;
