//! # lamdyn-fit
//!
//! The paper's central step (eqs. 2–10, Tables 2–3): the FRFs of the FE model with the stiffness
//! K*(ω) = K0 E*(ω)/E_ref are computed exactly from one set of real modes, and the modulus law
//! E*(ω) is fitted to measured FRFs.
//!
//! | module | what |
//! |---|---|
//! | [`probe`] | sensor and hammer channels mapped to FE nodes |
//! | [`synthesis`] | exact modal FRF synthesis with a residual (static) term, fast RMS |
//! | [`supports`] | grounded springs and dashpots of the part, projected on the modes |
//! | [`direct`] | direct complex solves with faer's sparse LU (the independent check) |
//! | [`misfit`] | RMS (eqs. 2, 10), log-RMS and complex misfits over a band |
//! | [`spline`] | not-a-knot cubic spline (the per-mode law's interpolation) |
//! | [`law`] | eq. 7, fractional Zener and per-mode laws with unconstrained parameters |
//! | [`lm`] | Levenberg–Marquardt on faer |
//! | `start` | starting points: storage modulus at the peaks, screened grid of loss parameters |
//! | [`fit`] | multi-start fit, covariance and 95 % intervals |
//! | [`frf_fit`] | the core's law fitted to the measured FRFs through the layered model |
//! | [`modes`] | mode-wise estimates and the Table-3 peak comparison |
//! | [`joint`] | the core's law fitted to all modes with the inputs known within a tolerance |
//! | [`synthetic`] | measurement grids and seeded noise for tests and demos |
//!
//! Units: Pa, Hz on frequency axes, ω in rad/s in formulas, FRFs per newton.

#![deny(missing_docs)]
#![allow(non_snake_case)]
#![allow(clippy::needless_range_loop)]

pub mod direct;
mod error;
pub mod fit;
pub mod frf_fit;
pub mod joint;
pub mod law;
pub mod lm;
pub mod master;
pub mod misfit;
pub mod modes;
pub mod peaks;
pub mod probe;
pub mod spline;
mod start;
pub mod supports;
pub mod synthesis;
pub mod synthetic;

pub use error::FitError;
