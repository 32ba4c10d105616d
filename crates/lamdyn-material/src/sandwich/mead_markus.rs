//! Mead–Markus sandwich beam: apparent bending stiffness and its exact inverse.
//!
//! Faces 1 and 3 (E_i, H_i) bend and stretch, the core (G_2*, H_2) only shears [Mead & Markus
//! 1969; method-notes §4]. For a sinusoidal deflection of wavenumber k:
//!
//! D(k) = D_t [1 + Y g_k/(1 + g_k)],   g_k = g/k²,   g = (G_2*/H_2)(1/(E_1H_1) + 1/(E_3H_3))
//! D_t  = E_1H_1³/12 + E_3H_3³/12,     Y = d² / [D_t (1/(E_1H_1) + 1/(E_3H_3))],
//! d    = H_2 + (H_1 + H_3)/2.
//!
//! Free waves satisfy D(k) k⁴ = m ω² (m = ρ_S, mass per unit area); with κ = k² this is the cubic
//!
//! D_t κ³ + D_t g(1+Y) κ² − m ω² κ − m ω² g = 0.
//!
//! For real moduli it has exactly one positive root (Descartes' rule: one sign change), the
//! propagating wave; the other two have negative real parts. With a lossy core the propagating
//! root is the one with the largest real part. The apparent stiffness at ω is
//! B(ω) = m ω²/κ² = D(k).
//!
//! Inverse (closed form): given B and ω, κ = ω √(m/B); with R = B/D_t − 1 the stiffness relation
//! gives R(κ + g) = Y g, so g = R κ/(Y − R) and G_2* = g H_2 / (1/(E_1H_1) + 1/(E_3H_3)).
//! A solution needs 0 < Re R < Re Y: the laminate must be stiffer than its faces alone and softer
//! than the bonded stack D_t(1+Y).
//!
//! Per unit width, SI units. Plate kinematics replace each face's E by E/(1−ν²).

use crate::error::{MaterialError, check};
use crate::laminate::{Kinematics, SandwichStack, phi_from_stiffness_ratio};
use crate::roots::polynomial_roots;
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

/// The Mead–Markus model of a sandwich (core modulus given per call).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeadMarkus {
    /// Faces' own bending stiffness D_t, N·m.
    d_t: Complex64,
    /// Geometric parameter Y.
    y: Complex64,
    /// (1/(E_1H_1) + 1/(E_3H_3)) / H_2, so that g = G_2* × this, 1/(Pa·m²).
    coupling: Complex64,
    /// Mass per unit area m, kg/m².
    mass_kg_m2: f64,
    /// Total thickness h, m (to convert B to E_eff = 12B/h³).
    thickness_m: f64,
    kinematics: Kinematics,
}

/// A free wave of the sandwich at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeadMarkusWave {
    /// κ = k², rad²/m² (complex for a lossy core).
    pub kappa: Complex64,
    /// Apparent bending stiffness B = D(k), N·m.
    pub stiffness: Complex64,
}

impl MeadMarkus {
    /// The model of `stack` under `kinematics` (plate: faces bend and stretch with E/(1−ν²)).
    pub fn new(stack: &SandwichStack, kinematics: Kinematics) -> Self {
        let face = |f: &crate::laminate::Face| {
            let e = f.young() * kinematics.bending_factor(f.poisson);
            (e * f.thickness_m, e * f.thickness_m.powi(3) / 12.0)
        };
        let (eh1, d1) = face(stack.bottom());
        let (eh3, d3) = face(stack.top());
        let h2 = stack.core().thickness_m;
        let d = h2 + 0.5 * (stack.bottom().thickness_m + stack.top().thickness_m);
        let flex = 1.0 / eh1 + 1.0 / eh3;
        let d_t = d1 + d3;
        Self {
            d_t,
            y: d * d / (d_t * flex),
            coupling: flex / h2,
            mass_kg_m2: stack.surface_density_kg_m2(),
            thickness_m: stack.thickness_m(),
            kinematics,
        }
    }

    /// Faces' own bending stiffness D_t, N·m.
    pub fn faces_stiffness(&self) -> Complex64 {
        self.d_t
    }

    /// Bending stiffness of the perfectly bonded faces D_t (1 + Y), N·m.
    pub fn bonded_stiffness(&self) -> Complex64 {
        self.d_t * (1.0 + self.y)
    }

    /// Geometric parameter Y.
    pub fn geometric_parameter(&self) -> Complex64 {
        self.y
    }

    /// Shear parameter g = G_2*(1/(E_1H_1) + 1/(E_3H_3))/H_2, 1/m² (g_k = g/k²).
    pub fn shear_parameter(&self, core_shear_pa: Complex64) -> Complex64 {
        core_shear_pa * self.coupling
    }

    /// D(k) = D_t [1 + Y g_k/(1+g_k)] at wavenumber `k_rad_m` (rad/m), N·m.
    pub fn stiffness_at_wavenumber(&self, core_shear_pa: Complex64, k_rad_m: f64) -> Complex64 {
        let gk = self.shear_parameter(core_shear_pa) / (k_rad_m * k_rad_m);
        self.d_t * (1.0 + self.y * gk / (1.0 + gk))
    }

    /// The propagating free wave at ω (rad/s): the root κ of the Mead–Markus cubic with the
    /// largest real part, and B = m ω²/κ².
    pub fn wave(&self, core_shear_pa: Complex64, omega_rad_s: f64) -> MeadMarkusWave {
        let g = self.shear_parameter(core_shear_pa);
        let mw2 = Complex64::new(self.mass_kg_m2 * omega_rad_s * omega_rad_s, 0.0);
        let coeffs = [self.d_t, self.d_t * g * (1.0 + self.y), -mw2, -mw2 * g];
        let kappa = polynomial_roots(&coeffs)
            .into_iter()
            .max_by(|a, b| a.re.total_cmp(&b.re))
            .expect("a cubic has three roots");
        MeadMarkusWave {
            kappa,
            stiffness: mw2 / (kappa * kappa),
        }
    }

    /// The effective modulus E_eff = 12 B(ω)/h³ (times (1−ν²) for a plate), Pa.
    pub fn effective_modulus(&self, core_shear_pa: Complex64, omega_rad_s: f64) -> Complex64 {
        let b = self.wave(core_shear_pa, omega_rad_s).stiffness;
        12.0 * b / self.thickness_m.powi(3) * self.kinematics.effective_modulus_factor()
    }

    /// The core shear modulus G_2* (Pa) that gives apparent stiffness `stiffness` (N·m) at ω.
    ///
    /// # Errors
    /// [`MaterialError::NoCoreSolution`] unless 0 < Re(B/D_t − 1) < Re Y.
    pub fn core_shear(
        &self,
        stiffness: Complex64,
        omega_rad_s: f64,
    ) -> Result<Complex64, MaterialError> {
        let r = stiffness / self.d_t - 1.0;
        let fail = |reason: String| MaterialError::NoCoreSolution {
            freq_hz: omega_rad_s / (2.0 * PI),
            model: "exact inverse (Mead-Markus)".into(),
            reason,
        };
        if r.re <= 0.0 {
            return Err(fail(format!(
                "the laminate is no stiffer than its faces alone (B = {:.6e} N m <= D_t = {:.6e} N \
                 m)",
                stiffness.re, self.d_t.re
            )));
        }
        if r.re >= self.y.re {
            return Err(fail(format!(
                "the laminate is at least as stiff as the bonded faces (B = {:.6e} N m >= D_t (1 + \
                 Y) = {:.6e} N m)",
                stiffness.re,
                self.bonded_stiffness().re
            )));
        }
        let kappa = omega_rad_s * (self.mass_kg_m2 / stiffness).sqrt();
        let g = r * kappa / (self.y - r);
        Ok(g / self.coupling)
    }
}

/// The core recovered by the exact (Mead–Markus) inverse at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ExactCoreEstimate {
    /// Angular frequency, rad/s.
    pub omega_rad_s: f64,
    /// Core shear modulus G*, Pa.
    pub core_shear_pa: Complex64,
    /// Wavenumber squared κ = k² of the free wave, rad²/m².
    pub kappa: Complex64,
    /// The paper's φ* = (κ_B − 1)/(2√κ_B) with κ_B = D_t(1+Y)/B, for comparison with its limit.
    pub phi: Complex64,
}

impl ExactCoreEstimate {
    /// Storage modulus G', Pa.
    pub fn storage_pa(&self) -> f64 {
        self.core_shear_pa.re
    }
    /// Loss factor η.
    pub fn loss_factor(&self) -> f64 {
        self.core_shear_pa.im / self.core_shear_pa.re
    }
}

/// The exact inverse: the core shear modulus that makes the Mead–Markus sandwich of `stack` have
/// effective modulus `e_eff_pa` (B = E_eff h³/12, divided by (1−ν²) for a plate) at ω.
///
/// # Errors
/// [`MaterialError::InvalidParameter`] for ω ≤ 0 or a non-finite E_eff, and
/// [`MaterialError::NoCoreSolution`] as [`MeadMarkus::core_shear`].
pub fn exact_inverse(
    stack: &SandwichStack,
    omega_rad_s: f64,
    e_eff_pa: Complex64,
    kinematics: Kinematics,
) -> Result<ExactCoreEstimate, MaterialError> {
    check::positive("exact inverse", "omega_rad_s", omega_rad_s)?;
    check::positive("exact inverse", "E_eff'", e_eff_pa.re)?;
    check::finite("exact inverse", "E_eff''", e_eff_pa.im)?;
    let mm = MeadMarkus::new(stack, kinematics);
    let h = stack.thickness_m();
    let b = e_eff_pa * h * h * h / 12.0 / kinematics.effective_modulus_factor();
    let core_shear_pa = mm.core_shear(b, omega_rad_s)?;
    Ok(ExactCoreEstimate {
        omega_rad_s,
        core_shear_pa,
        kappa: omega_rad_s * (stack.surface_density_kg_m2() / b).sqrt(),
        phi: phi_from_stiffness_ratio(mm.bonded_stiffness() / b),
    })
}
