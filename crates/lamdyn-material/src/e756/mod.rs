//! ASTM E756-05 beam reductions, each with the forward model that produces its test data.
//!
//! The standard tests a clamped–free (Oberst) beam of free length l; mode n has the uniform-beam
//! wavenumber k_n = β_n/l with β_n l the n-th root of 1 + cos β cosh β = 0
//! ([`clamped_free_root`]: 1.87510, 4.69409, 7.85476, 10.99554, 14.13717, 17.27876, …) and
//! C_n = (β_n l)²/(2π). Loss factors are modal: η = Δf/f from the half-power bandwidth, or
//! Im λ / Re λ of the complex eigenvalue λ = ω_n²(1 + iη) in the forward models.
//!
//! | configuration | reduction | forward model |
//! |---|---|---|
//! | uniform beam | [`UniformBeam::reduce`] → (E, η) | [`UniformBeam::resonance`] |
//! | Oberst free layer | [`OberstBeam::reduce`] → (E_1, η_1) | [`OberstBeam::resonances`] |
//! | sandwich beam | [`SandwichBeam::reduce`] → (G_1, η_1) | [`SandwichBeam::resonances`] (RKU) |
//!
//! The sandwich reduction is the exact inverse of symmetric RKU with E_core = 0 at k_n, so the
//! round trip holds to rounding; the Oberst reduction of the standard is first order in the
//! layer's loss and [`OberstBeam::reduce_exact`] gives the exact complex inverse beside it.
//! Formulas as quoted in method-notes §4.

mod oberst;
mod sandwich;
mod uniform;

pub use oberst::OberstBeam;
pub use sandwich::SandwichBeam;
pub use uniform::UniformBeam;

use crate::error::MaterialError;
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

/// β_n l: the n-th positive root of 1 + cos x cosh x = 0 (clamped–free beam), n ≥ 1.
///
/// Solved by Newton's method on cos x + 1/cosh x = 0 from (2n − 1)π/2.
///
/// # Panics
/// If `mode` is 0 (modes are numbered from 1; inputs are validated before this).
pub fn clamped_free_root(mode: usize) -> f64 {
    assert!(mode >= 1, "expected a mode number >= 1, got 0");
    let mut x = (2 * mode - 1) as f64 * PI / 2.0;
    if mode == 1 {
        x = 1.875;
    }
    for _ in 0..50 {
        let f = x.cos() + 1.0 / x.cosh();
        let df = -x.sin() - x.tanh() / x.cosh();
        let step = f / df;
        x -= step;
        if step.abs() < 1e-15 * x {
            break;
        }
    }
    x
}

/// C_n = (β_n l)²/(2π).
pub fn c_n(mode: usize) -> f64 {
    let b = clamped_free_root(mode);
    b * b / (2.0 * PI)
}

/// A resonance of a beam: frequency (Hz) and modal loss factor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Resonance {
    /// Mode number n (1-based).
    pub mode: usize,
    /// Resonance frequency f_n = √(Re λ)/(2π), Hz.
    pub freq_hz: f64,
    /// Modal loss factor Im λ / Re λ.
    pub loss_factor: f64,
}

impl Resonance {
    /// The resonance of the complex eigenvalue λ = EI* k⁴/m (rad²/s²).
    fn from_eigenvalue(mode: usize, lambda: Complex64) -> Self {
        Self {
            mode,
            freq_hz: lambda.re.sqrt() / (2.0 * PI),
            loss_factor: lambda.im / lambda.re,
        }
    }

    /// Half-power bandwidth Δf = η f (Hz), the quantity E756 measures.
    pub fn half_power_bandwidth_hz(&self) -> f64 {
        self.loss_factor * self.freq_hz
    }
}

/// A modulus and loss factor recovered from a beam test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReducedModulus {
    /// Mode number n.
    pub mode: usize,
    /// Storage modulus (E or G), Pa.
    pub storage_pa: f64,
    /// Loss factor.
    pub loss_factor: f64,
}

fn check_mode(context: &str, mode: usize) -> Result<(), MaterialError> {
    if mode == 0 {
        return Err(MaterialError::InvalidParameter {
            context: context.into(),
            field: "mode".into(),
            value: "0".into(),
            requirement: "must be 1 or more (modes are numbered from 1)".into(),
        });
    }
    Ok(())
}
