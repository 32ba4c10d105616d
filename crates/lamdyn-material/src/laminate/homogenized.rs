//! The paper's homogenized (apparent) bending stiffness of a sandwich plate, eqs. 28–31.
//!
//! φ(ω)  = ω √(ρ_S B_eq) / (2 K_eq)                                  (eq. 31)
//! B_K   = B_eq / (√(1+φ²) + φ)²                                     (eq. 29)
//! E_eff = 12 B_K / h³   (the inverse of eq. 33)
//!
//! Eq. 29 is the dispersion of a shear beam without rotary inertia: with B_K k⁴ = ρ_S ω² and
//! 1/B_K = 1/B_eq + k²/K_eq, κ = B_eq/B_K solves κ − 2φ√κ − 1 = 0, whose root is
//! √κ = φ + √(1+φ²). Its exact inverse is φ = (κ − 1)/(2√κ) (eq. 37).
//!
//! Accuracy limit (method-notes §3): against exact sandwich-beam theory the error of B_K stays
//! below 1 % while φ < 0.1 and reaches about 10 % near φ = 0.33, because B_K → 0 as ω grows
//! while a real sandwich tends to its faces bending separately. Every [`Homogenized`] carries φ,
//! and [`Homogenized::warning`] reports |φ| > [`PHI_ACCURACY_LIMIT`].

use super::{Kinematics, Section};
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;
use std::fmt;

/// |φ| above which the paper's homogenization is outside its 1 % accuracy range.
pub const PHI_ACCURACY_LIMIT: f64 = 0.1;

/// Largest relative difference of the paper's E_eff' from exact sandwich theory's at which the
/// paper's model counts as valid: its own stated accuracy (1 %, [`PHI_ACCURACY_LIMIT`]).
pub const PAPER_STORAGE_AGREEMENT: f64 = 0.01;

/// Largest relative difference of the paper's loss factor from exact sandwich theory's at which
/// the paper's model counts as valid. On the paper's roof the two differ by 0.3–1.5 % over
/// 5–80 Hz; a stack of thin faces on a thick core, where the core's own bending matters, puts
/// them several times apart at small φ.
pub const PAPER_LOSS_AGREEMENT: f64 = 0.1;

/// Whether the paper's effective modulus `paper` agrees with exact sandwich theory's `exact`
/// within [`PAPER_STORAGE_AGREEMENT`] in E' and [`PAPER_LOSS_AGREEMENT`] in the loss factor.
pub fn agrees_with_exact(paper: Complex64, exact: Complex64) -> bool {
    let (eta_paper, eta_exact) = (paper.im / paper.re, exact.im / exact.re);
    (paper.re - exact.re).abs() <= PAPER_STORAGE_AGREEMENT * exact.re.abs()
        && (eta_paper - eta_exact).abs() <= PAPER_LOSS_AGREEMENT * eta_exact.abs()
}

/// φ(ω) = ω √(ρ_S B_eq) / (2 K_eq) (eq. 31); ω in rad/s, ρ_S in kg/m², B_eq in N·m, K_eq in N/m.
pub fn phi(
    omega_rad_s: f64,
    surface_density_kg_m2: f64,
    b_eq: Complex64,
    k_eq: Complex64,
) -> Complex64 {
    omega_rad_s * (surface_density_kg_m2 * b_eq).sqrt() / (2.0 * k_eq)
}

/// B_K = B_eq / (√(1+φ²) + φ)² (eq. 29), N·m.
pub fn apparent_stiffness(b_eq: Complex64, phi: Complex64) -> Complex64 {
    let s = (1.0 + phi * phi).sqrt() + phi;
    b_eq / (s * s)
}

/// φ = (κ − 1)/(2√κ) with κ = B_eq/B_K (eq. 37), the exact inverse of eq. 29.
pub fn phi_from_stiffness_ratio(kappa: Complex64) -> Complex64 {
    (kappa - 1.0) / (2.0 * kappa.sqrt())
}

/// The homogenized plate at one frequency. Complex values serialise as `[re, im]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Homogenized {
    /// Angular frequency ω, rad/s.
    pub omega_rad_s: f64,
    /// Total thickness h, m.
    pub thickness_m: f64,
    /// Surface density ρ_S, kg/m².
    pub surface_density_kg_m2: f64,
    /// Bending stiffness of the bonded stack B_eq, N·m (eq. 14).
    pub b_eq: Complex64,
    /// Equivalent shear stiffness K_eq, N/m (eq. 24).
    pub k_eq: Complex64,
    /// Shear parameter φ (eq. 31).
    pub phi: Complex64,
    /// Apparent stiffness B_K, N·m (eq. 29).
    pub b_k: Complex64,
    /// Effective complex modulus of the homogeneous plate, Pa.
    pub e_eff: Complex64,
}

impl Homogenized {
    /// Applies eqs. 29 and 31 to B_eq and K_eq of `section` at ω, and reports E_eff under
    /// `kinematics` (E_eff = 12 B_K/h³ for a beam, times (1−ν²) for a plate).
    pub fn new(
        omega_rad_s: f64,
        b_eq: Complex64,
        k_eq: Complex64,
        section: &Section,
        kinematics: Kinematics,
    ) -> Self {
        let h = section.thickness_m();
        let rho_s = section.surface_density_kg_m2();
        let phi = phi(omega_rad_s, rho_s, b_eq, k_eq);
        let b_k = apparent_stiffness(b_eq, phi);
        let e_eff = 12.0 * b_k / (h * h * h) * kinematics.effective_modulus_factor();
        Self {
            omega_rad_s,
            thickness_m: h,
            surface_density_kg_m2: rho_s,
            b_eq,
            k_eq,
            phi,
            b_k,
            e_eff,
        }
    }

    /// Frequency f = ω/2π, Hz.
    pub fn freq_hz(&self) -> f64 {
        self.omega_rad_s / (2.0 * PI)
    }

    /// Loss factor of the effective modulus, Im E_eff / Re E_eff.
    pub fn loss_factor(&self) -> f64 {
        self.e_eff.im / self.e_eff.re
    }

    /// True while |φ| ≤ [`PHI_ACCURACY_LIMIT`].
    pub fn within_accuracy_limit(&self) -> bool {
        self.phi.norm() <= PHI_ACCURACY_LIMIT
    }

    /// The warning to show when |φ| exceeds the accuracy limit.
    pub fn warning(&self) -> Option<ModelWarning> {
        ModelWarning::check(self.omega_rad_s, self.phi)
    }
}

/// A result that is computed but outside the model's accuracy range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum ModelWarning {
    /// |φ| > 0.1: the paper's B_K is more than about 1 % off exact sandwich theory.
    PhiBeyondLimit {
        /// Frequency, Hz.
        freq_hz: f64,
        /// |φ|.
        phi: f64,
    },
}

impl ModelWarning {
    /// `Some(PhiBeyondLimit)` when |φ| > [`PHI_ACCURACY_LIMIT`].
    pub fn check(omega_rad_s: f64, phi: Complex64) -> Option<Self> {
        (phi.norm() > PHI_ACCURACY_LIMIT).then(|| Self::PhiBeyondLimit {
            freq_hz: omega_rad_s / (2.0 * PI),
            phi: phi.norm(),
        })
    }
}

impl fmt::Display for ModelWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::PhiBeyondLimit { freq_hz, phi } => write!(
                f,
                "phi = {phi:.3} > {PHI_ACCURACY_LIMIT} at {freq_hz:.2} Hz: the paper's \
                 homogenization is beyond its accuracy limit (B_K more than ~1 % off exact \
                 sandwich theory)"
            ),
        }
    }
}
