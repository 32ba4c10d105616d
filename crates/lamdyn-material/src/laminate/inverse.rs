//! The paper's inverse homogenization: from the laminate's effective modulus E*(f) to the core's
//! shear modulus G_a*(f), eqs. 33–45, with the paper's approximations as options.
//!
//! B_K*  = E* h³/12                                                     (eq. 33)
//! B_eq  = bonded bending stiffness, core neglected (eq. 35) or not (eq. 14)
//! κ*    = B_eq / B_K*                                                  (eq. 36)
//! φ*    = (κ* − 1) / (2√κ*)                                            (eq. 37)
//! K_eq* = ω √(ρ_S B_eq) / (2 φ*)                                        (eq. 38)
//! 1/K_a* = 1/K_eq* − 1/K_1 − 1/K_3    (eq. 39; eq. 40 drops the faces' terms)
//! G_a*  = c K_a*,  c = 9T(r−1)² / (h_g [1+3(r−1)²]²), r = 2 + T          (eqs. 41–42)
//!       or c = 9T/(16 h_g)                                             (eq. 43, thin core)
//!
//! with T = h_a/h_g. Eq. 41 is eq. 26 in the limit M_2 → 0 (core carries no bending stress):
//! then the core's shear stress is uniform and its compliance is exactly c/G_a. With
//! [`CoreShearFormula::Eq26`] the core's own bending is kept and G_a enters eqs. 25–27 through
//! M_2 = E_a/E_g too; the inverse then solves the forward model by Newton's method.
//!
//! [`paper_forward`] is the forward model with the same options, so every option round-trips
//! exactly; with `Eq26`, `Included` and `FullStack` it equals [`super::LayerStack::homogenize`].
//! The faces' shear compliances 1/K_1, 1/K_3 (eqs. 25, 27) are taken with M_2 = 0 under eqs.
//! 41/43 and with the actual core under eq. 26.

use super::{Homogenized, Kinematics, SandwichStack, Section, phi_from_stiffness_ratio};
use crate::error::MaterialError;
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;

/// How the core's shear compliance is related to its shear modulus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CoreShearFormula {
    /// Eq. 41 (general core thickness, core bending neglected). Needs identical faces.
    #[default]
    Eq41,
    /// Eq. 43 (thin core: eq. 41 with r → 2). Needs identical faces.
    Eq43,
    /// Eq. 26 in full (core bending kept, E_a = 2(1+ν_a)G_a); solved iteratively.
    Eq26,
}

/// Whether the faces' own shear compliance is subtracted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaceShear {
    /// Eq. 40: K_a ≈ K_eq (faces infinitely stiff in shear).
    #[default]
    Neglected,
    /// Eq. 39: 1/K_a = 1/K_eq − 1/K_1 − 1/K_3.
    Included,
}

/// How B_eq is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaceBending {
    /// Eq. 35: the core's bending stiffness is neglected.
    #[default]
    CoreNeglected,
    /// Eq. 14: the whole bonded stack, core included (needs the core modulus: iterative).
    FullStack,
}

/// Options of the paper's inverse. The default is the paper's own chain: eqs. 35, 40 and 41,
/// beam kinematics.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PaperInverseOptions {
    /// Core shear formula (eq. 41, 43 or 26).
    pub core_shear: CoreShearFormula,
    /// Faces' shear (eq. 40 or 39).
    pub face_shear: FaceShear,
    /// Bending stiffness (eq. 35 or 14).
    pub bending: FaceBending,
    /// Beam (as written) or plate in cylindrical bending.
    pub kinematics: Kinematics,
}

impl PaperInverseOptions {
    /// Options from their parts.
    pub fn new(
        core_shear: CoreShearFormula,
        face_shear: FaceShear,
        bending: FaceBending,
        kinematics: Kinematics,
    ) -> Self {
        Self {
            core_shear,
            face_shear,
            bending,
            kinematics,
        }
    }

    /// The paper's homogenization without its simplifications (eqs. 14, 24–27 in full): the
    /// inverse of [`super::LayerStack::homogenize`].
    pub fn full_model(kinematics: Kinematics) -> Self {
        Self::new(
            CoreShearFormula::Eq26,
            FaceShear::Included,
            FaceBending::FullStack,
            kinematics,
        )
    }

    /// A label such as `eqs. 35, 40, 41`.
    pub fn label(&self) -> String {
        let b = match self.bending {
            FaceBending::CoreNeglected => "35",
            FaceBending::FullStack => "14",
        };
        let f = match self.face_shear {
            FaceShear::Neglected => "40",
            FaceShear::Included => "39",
        };
        let c = match self.core_shear {
            CoreShearFormula::Eq41 => "41",
            CoreShearFormula::Eq43 => "43",
            CoreShearFormula::Eq26 => "26",
        };
        let k = match self.kinematics {
            Kinematics::Beam => "",
            Kinematics::Plate { .. } => ", plate",
        };
        format!("paper inverse (eqs. {b}, {f}, {c}{k})")
    }

    fn closed_form(&self) -> bool {
        self.bending == FaceBending::CoreNeglected && self.core_shear != CoreShearFormula::Eq26
    }
}

/// The core modulus recovered at one frequency, with the paper's intermediate quantities.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CoreEstimate {
    /// Angular frequency, rad/s.
    pub omega_rad_s: f64,
    /// Core shear modulus G_a* (eq. 41/43/26), Pa.
    pub core_shear_pa: Complex64,
    /// κ* = B_eq/B_K* (eq. 36).
    pub kappa: Complex64,
    /// φ* (eq. 37).
    pub phi: Complex64,
    /// Equivalent shear stiffness K_eq* (eq. 38), N/m.
    pub k_eq: Complex64,
    /// Bending stiffness B_eq used, N·m.
    pub b_eq: Complex64,
    /// Newton iterations (0 for the closed-form chain).
    pub iterations: usize,
}

impl CoreEstimate {
    /// Storage modulus G_a' (eq. 44), Pa.
    pub fn storage_pa(&self) -> f64 {
        self.core_shear_pa.re
    }
    /// Loss factor η_a (eq. 45).
    pub fn loss_factor(&self) -> f64 {
        self.core_shear_pa.im / self.core_shear_pa.re
    }
}

/// The forward model of the paper's homogenization under `options`: the laminate of `stack`
/// with core shear modulus `core_shear_pa` (Pa) at ω (rad/s).
///
/// # Errors
/// [`MaterialError::UnsupportedStack`] when eq. 41/43 is asked of a stack with different faces.
pub fn paper_forward(
    stack: &SandwichStack,
    omega_rad_s: f64,
    core_shear_pa: Complex64,
    options: &PaperInverseOptions,
) -> Result<Homogenized, MaterialError> {
    let section = stack.section(core_shear_pa, options.kinematics);
    let core_free = section.without_bending_of(1);
    let b_eq = match options.bending {
        FaceBending::CoreNeglected => core_free.bending_stiffness(),
        FaceBending::FullStack => section.bending_stiffness(),
    };
    let (inv_k_core, faces_section) = match options.core_shear {
        CoreShearFormula::Eq26 => (three_layer(&section)?[1], &section),
        f => (core_coefficient(stack, f)? / core_shear_pa, &core_free),
    };
    let inv_k = inv_k_core + face_compliance(faces_section, options.face_shear)?;
    Ok(Homogenized::new(
        omega_rad_s,
        b_eq,
        1.0 / inv_k,
        &section,
        options.kinematics,
    ))
}

/// The paper's inverse at one line: the core shear modulus G_a* (Pa) that makes the laminate of
/// `stack` have the effective modulus `e_eff_pa` (Pa) at ω (rad/s) under `options`.
///
/// The default options give the paper's closed-form chain (eqs. 33–38, 40, 41). Options with the
/// full bending stiffness or eq. 26 solve [`paper_forward`] by Newton's method from the
/// closed-form estimate.
///
/// # Errors
/// - [`MaterialError::InvalidParameter`] for ω ≤ 0 or a non-finite or non-positive E_eff'.
/// - [`MaterialError::NoCoreSolution`] when the laminate shows no shear softening (Re φ* ≤ 0,
///   e.g. stiffer than the bonded stack), or the faces' shear compliance alone exceeds the measured one.
/// - [`MaterialError::UnsupportedStack`] when eq. 41/43 is asked of different faces.
/// - [`MaterialError::NoConvergence`] if Newton's method fails (not seen in the tests).
pub fn paper_inverse(
    stack: &SandwichStack,
    omega_rad_s: f64,
    e_eff_pa: Complex64,
    options: &PaperInverseOptions,
) -> Result<CoreEstimate, MaterialError> {
    crate::error::check::positive("paper inverse", "omega_rad_s", omega_rad_s)?;
    crate::error::check::positive("paper inverse", "E_eff'", e_eff_pa.re)?;
    crate::error::check::finite("paper inverse", "E_eff''", e_eff_pa.im)?;
    if options.closed_form() {
        return closed_form(stack, omega_rad_s, e_eff_pa, options);
    }
    // Start from the closed form with eq. 41 generalised to any faces (Jourawski, M_2 = 0).
    let start_opts = PaperInverseOptions {
        bending: FaceBending::CoreNeglected,
        ..*options
    };
    let g0 = closed_form_with(
        stack,
        omega_rad_s,
        e_eff_pa,
        &start_opts,
        jourawski_coefficient(stack),
    )?;
    newton(stack, omega_rad_s, e_eff_pa, options, g0.core_shear_pa)
}

fn closed_form(
    stack: &SandwichStack,
    omega_rad_s: f64,
    e_eff_pa: Complex64,
    options: &PaperInverseOptions,
) -> Result<CoreEstimate, MaterialError> {
    let c = core_coefficient(stack, options.core_shear)?;
    closed_form_with(stack, omega_rad_s, e_eff_pa, options, c)
}

/// Eqs. 33–41 with core coefficient `c` (1/K_a = c/G_a); bending per eq. 35.
fn closed_form_with(
    stack: &SandwichStack,
    omega_rad_s: f64,
    e_eff_pa: Complex64,
    options: &PaperInverseOptions,
    c: Complex64,
) -> Result<CoreEstimate, MaterialError> {
    let no_solution = |reason: String| MaterialError::NoCoreSolution {
        freq_hz: omega_rad_s / (2.0 * PI),
        model: options.label(),
        reason,
    };
    let h = stack.thickness_m();
    let e_beam = e_eff_pa / options.kinematics.effective_modulus_factor();
    let b_k = e_beam * h * h * h / 12.0; // eq. 33
    let core_free = stack
        .section(Complex64::new(1.0, 0.0), options.kinematics)
        .without_bending_of(1);
    let b_eq = core_free.bending_stiffness(); // eq. 35
    let kappa = b_eq / b_k; // eq. 36
    let phi = phi_from_stiffness_ratio(kappa); // eq. 37
    if phi.re <= 0.0 {
        return Err(no_solution(format!(
            "the laminate shows no shear softening (Re phi* = {:.3e} <= 0; E_eff' = {:.6e} Pa, \
             bonded 12 B_eq/h^3 = {:.6e} Pa)",
            phi.re,
            e_eff_pa.re,
            12.0 * b_eq.re / (h * h * h) * options.kinematics.effective_modulus_factor()
        )));
    }
    let rho_s = stack.surface_density_kg_m2();
    let k_eq = omega_rad_s * (rho_s * b_eq).sqrt() / (2.0 * phi); // eq. 38
    let inv_k_a = 1.0 / k_eq - face_compliance(&core_free, options.face_shear)?; // eq. 39/40
    if inv_k_a.re <= 0.0 {
        return Err(no_solution(format!(
            "the faces' own shear compliance exceeds the measured one (1/K_eq = {:.6e} m/N)",
            (1.0 / k_eq).re
        )));
    }
    Ok(CoreEstimate {
        omega_rad_s,
        core_shear_pa: c / inv_k_a, // eq. 41/43
        kappa,
        phi,
        k_eq,
        b_eq,
        iterations: 0,
    })
}

/// Newton's method on G ↦ E_eff(G)/E_target − 1, with the derivative by a central complex
/// difference (the map is analytic in G) and steps limited to half of |G|.
fn newton(
    stack: &SandwichStack,
    omega_rad_s: f64,
    e_target: Complex64,
    options: &PaperInverseOptions,
    mut g: Complex64,
) -> Result<CoreEstimate, MaterialError> {
    const MAX_ITER: usize = 60;
    const STEP_TOL: f64 = 1e-14;
    let residual = |g: Complex64| -> Result<Complex64, MaterialError> {
        Ok(paper_forward(stack, omega_rad_s, g, options)?.e_eff / e_target - 1.0)
    };
    let mut last_step = f64::INFINITY;
    for iteration in 1..=MAX_ITER {
        let r = residual(g)?;
        let delta = g * 1e-6;
        let slope = (residual(g + delta)? - residual(g - delta)?) / (2.0 * delta);
        let mut step = r / slope;
        if step.norm() > 0.5 * g.norm() {
            step *= 0.5 * g.norm() / step.norm();
        }
        g -= step;
        last_step = step.norm() / g.norm();
        if last_step < STEP_TOL || r.norm() < 1e-15 {
            let h = paper_forward(stack, omega_rad_s, g, options)?;
            return Ok(CoreEstimate {
                omega_rad_s,
                core_shear_pa: g,
                kappa: h.b_eq / h.b_k,
                phi: h.phi,
                k_eq: h.k_eq,
                b_eq: h.b_eq,
                iterations: iteration,
            });
        }
    }
    Err(MaterialError::NoConvergence {
        context: options.label(),
        iterations: MAX_ITER,
        last_step,
    })
}

/// c in 1/K_a = c/G_a for eqs. 41 and 43, 1/m.
fn core_coefficient(
    stack: &SandwichStack,
    formula: CoreShearFormula,
) -> Result<Complex64, MaterialError> {
    if !stack.is_symmetric() {
        return Err(MaterialError::UnsupportedStack {
            context: format!("paper {formula:?}").replace("Eq", "eq. "),
            reason: format!(
                "assumes identical faces, got {} m / {} Pa below and {} m / {} Pa above; use eq. \
                 26",
                stack.bottom().thickness_m,
                stack.bottom().young_pa,
                stack.top().thickness_m,
                stack.top().young_pa
            ),
        });
    }
    let h_g = stack.bottom().thickness_m;
    let t = stack.core().thickness_m / h_g;
    let c = match formula {
        CoreShearFormula::Eq43 => 9.0 * t / (16.0 * h_g),
        _ => {
            let r1 = 1.0 + t; // r − 1 with r = 2 h_NP / h_g = 2 + T (eq. 42)
            let b = 1.0 + 3.0 * r1 * r1;
            9.0 * t * r1 * r1 / (h_g * b * b)
        }
    };
    Ok(Complex64::new(c, 0.0))
}

/// c in 1/K_a = c/G_a for a core without bending stress (Jourawski, any faces); equals eq. 41
/// for identical faces.
fn jourawski_coefficient(stack: &SandwichStack) -> Complex64 {
    let unit = Complex64::new(1.0, 0.0);
    stack
        .section(unit, Kinematics::Beam)
        .without_bending_of(1)
        .shear_compliances()[1]
}

/// 1/K_1 + 1/K_3 from eqs. 25 and 27 (or 0 for eq. 40).
fn face_compliance(section: &Section, face_shear: FaceShear) -> Result<Complex64, MaterialError> {
    Ok(match face_shear {
        FaceShear::Neglected => Complex64::new(0.0, 0.0),
        FaceShear::Included => {
            let c = three_layer(section)?;
            c[0] + c[2]
        }
    })
}

fn three_layer(section: &Section) -> Result<[Complex64; 3], MaterialError> {
    section
        .paper_three_layer_compliances()
        .ok_or_else(|| MaterialError::UnsupportedStack {
            context: "paper eqs. 25-27".into(),
            reason: format!("need three layers, got {}", section.layers().len()),
        })
}
