//! Ross–Kerwin–Ungar (RKU) complex flexural rigidity of a three-layer beam.
//!
//! Layers: 1 = base, 2 = viscoelastic core, 3 = constraining layer, thicknesses H_i, complex
//! moduli E_i, per unit width [Ross, Kerwin & Ungar 1959; Nashif, Jones & Henderson 1985, §7]:
//!
//! g    = G_2* / (E_3 H_3 H_2 k²)                                     (shear parameter)
//! H_21 = (H_1 + H_2)/2,  H_31 = (H_1 + H_3)/2 + H_2
//! D    = [E_2H_2(H_21 − H_31/2) + g(E_2H_2H_21 + E_3H_3H_31)]
//!        / [E_1H_1 + E_2H_2/2 + g(E_1H_1 + E_2H_2 + E_3H_3)]
//! EI   = E_1H_1³/12 + E_2H_2³/12 + E_3H_3³/12 − (E_2H_2²/12)(H_31 − D)/(1 + g)
//!        + E_1H_1D² + E_2H_2(H_21 − D)² + E_3H_3(H_31 − D)²
//!        − [(E_2H_2/2)(H_21 − D) + E_3H_3(H_31 − D)] (H_31 − D)/(1 + g)
//!
//! D is the neutral axis measured from the base layer's mid-plane. Limits: E_2 → 0 gives the
//! Mead–Markus stiffness; g → ∞ gives the perfectly bonded stack. The E_2 = 0 form was checked
//! against an independent energy derivation (`testdata/rku/derive.py`).

use num_complex::Complex64;

/// A three-layer beam for the RKU formula: thicknesses (m) and complex Young's moduli (Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RkuBeam {
    /// Base layer thickness H_1, m.
    pub h1_m: f64,
    /// Base layer modulus E_1, Pa.
    pub e1_pa: Complex64,
    /// Core thickness H_2, m.
    pub h2_m: f64,
    /// Core Young's modulus E_2 (0 to neglect the core's extension and bending), Pa.
    pub e2_pa: Complex64,
    /// Constraining layer thickness H_3, m.
    pub h3_m: f64,
    /// Constraining layer modulus E_3, Pa.
    pub e3_pa: Complex64,
}

impl RkuBeam {
    /// Shear parameter g = G_2*/(E_3 H_3 H_2 k²) at wavenumber `k_rad_m`.
    pub fn shear_parameter(&self, core_shear_pa: Complex64, k_rad_m: f64) -> Complex64 {
        core_shear_pa / (self.e3_pa * self.h3_m * self.h2_m * k_rad_m * k_rad_m)
    }

    /// The RKU flexural rigidity EI* per unit width (N·m) with core shear modulus G_2* (Pa) at
    /// wavenumber `k_rad_m` (rad/m).
    pub fn flexural_rigidity(&self, core_shear_pa: Complex64, k_rad_m: f64) -> Complex64 {
        self.flexural_rigidity_at_shear_parameter(self.shear_parameter(core_shear_pa, k_rad_m))
    }

    /// The RKU flexural rigidity at shear parameter `g`.
    pub fn flexural_rigidity_at_shear_parameter(&self, g: Complex64) -> Complex64 {
        let (h1, h2, h3) = (self.h1_m, self.h2_m, self.h3_m);
        let (e1, e2, e3) = (self.e1_pa, self.e2_pa, self.e3_pa);
        let h21 = 0.5 * (h1 + h2);
        let h31 = 0.5 * (h1 + h3) + h2;
        let d = (e2 * h2 * (h21 - 0.5 * h31) + g * (e2 * h2 * h21 + e3 * h3 * h31))
            / (e1 * h1 + 0.5 * e2 * h2 + g * (e1 * h1 + e2 * h2 + e3 * h3));
        let slip = (h31 - d) / (1.0 + g);
        e1 * h1.powi(3) / 12.0 + e2 * h2.powi(3) / 12.0 + e3 * h3.powi(3) / 12.0
            - e2 * h2 * h2 / 12.0 * slip
            + e1 * h1 * d * d
            + e2 * h2 * (h21 - d) * (h21 - d)
            + e3 * h3 * (h31 - d) * (h31 - d)
            - (0.5 * e2 * h2 * (h21 - d) + e3 * h3 * (h31 - d)) * slip
    }
}
