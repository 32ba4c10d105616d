//! The cross-section of a layered plate at one frequency: neutral plane, bending stiffness and
//! transverse shear stiffness, per unit width.
//!
//! Symbols (paper eqs. 14–18, 24–27; z measured upwards from the lower surface):
//!
//! | symbol | variable | unit |
//! |---|---|---|
//! | h_i | `thickness_m` | m |
//! | h_Ni | mid-plane of layer i, `z_mid()` | m |
//! | E_i, G_i | `young_pa`, `shear_pa` (complex) | Pa |
//! | h_NP | [`Section::neutral_plane_m`] | m |
//! | I_i | [`Section::second_moments_m3`] | m³ (per unit width) |
//! | B_i, B_eq | [`Section::layer_bending_stiffness`], [`Section::bending_stiffness`] | N·m |
//! | K_i, K_eq | [`Section::shear_compliances`], [`Section::shear_stiffness`] | N/m |
//!
//! Identities:
//!
//! h_NP = Σ E_i h_i h_Ni / Σ E_i h_i                                   (eq. 18, N layers)
//! I_i  = h_i [h_i²/12 + (h_Ni − h_NP)²]                               (eq. 17)
//! B_eq = Σ B_i = Σ E_i I_i                                            (eqs. 14, 16, 30)
//!
//! The shear stiffness follows from the Jourawski (parabolic-per-layer) shear stress of a
//! composite section in bending: with S(z) = ∫₀^z E(ζ)(ζ − h_NP) dζ, the shear stress under a
//! shear force Q is τ(z) = Q S(z)/B_eq, and equating complementary energies,
//!
//! 1/K_eq = Σ 1/K_i,   1/K_i = ∫_{layer i} S(z)² / (G_i B_eq²) dz                (eq. 24)
//!
//! For one layer this is 6/(5 G h), i.e. K = (5/6) G h (eq. 23). For three layers it is exactly
//! the paper's eqs. 25–27 (read per unit width, b = 1), which
//! [`Section::paper_three_layer_compliances`] evaluates literally; the tests check that both
//! agree. S is quadratic in each layer, so a three-point Gauss rule integrates S² exactly.
//!
//! Complex moduli are carried through formally (correspondence principle): for an asymmetric
//! stack with a lossy layer h_NP and I_i become complex.

use num_complex::Complex64;

/// One layer of a [`Section`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionLayer {
    /// Thickness h_i, m.
    pub thickness_m: f64,
    /// Position of the layer's lower face above the section's lower surface, m.
    pub z_bottom_m: f64,
    /// Complex Young's modulus used in bending, Pa (E/(1−ν²) for plate kinematics).
    pub young_pa: Complex64,
    /// Complex shear modulus, Pa.
    pub shear_pa: Complex64,
}

impl SectionLayer {
    /// Mid-plane position h_Ni, m.
    pub fn z_mid(&self) -> f64 {
        self.z_bottom_m + 0.5 * self.thickness_m
    }
    /// Upper face position, m.
    pub fn z_top(&self) -> f64 {
        self.z_bottom_m + self.thickness_m
    }
}

/// A layered cross-section evaluated at one frequency (moduli already complex numbers).
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    layers: Vec<SectionLayer>,
    surface_density_kg_m2: f64,
}

impl Section {
    /// Builds a section from layer thicknesses (m), complex Young's and shear moduli (Pa),
    /// bottom to top, and the surface density (kg/m²).
    ///
    /// # Panics
    /// If `layers` is empty (a programming error: stacks are validated before this).
    pub fn new(
        layers: impl IntoIterator<Item = (f64, Complex64, Complex64)>,
        surface_density_kg_m2: f64,
    ) -> Self {
        let mut z = 0.0;
        let layers: Vec<SectionLayer> = layers
            .into_iter()
            .map(|(h, e, g)| {
                let layer = SectionLayer {
                    thickness_m: h,
                    z_bottom_m: z,
                    young_pa: e,
                    shear_pa: g,
                };
                z += h;
                layer
            })
            .collect();
        assert!(!layers.is_empty(), "expected at least one layer, got none");
        Self {
            layers,
            surface_density_kg_m2,
        }
    }

    /// The layers, bottom to top.
    pub fn layers(&self) -> &[SectionLayer] {
        &self.layers
    }

    /// Total thickness h, m.
    pub fn thickness_m(&self) -> f64 {
        self.layers.last().map_or(0.0, SectionLayer::z_top)
    }

    /// Surface density ρ_S, kg/m².
    pub fn surface_density_kg_m2(&self) -> f64 {
        self.surface_density_kg_m2
    }

    /// The same section with layer `index`'s Young's modulus set to zero (the paper's eq. 35
    /// neglects the core in bending this way).
    pub fn without_bending_of(&self, index: usize) -> Self {
        let mut s = self.clone();
        s.layers[index].young_pa = Complex64::new(0.0, 0.0);
        s
    }

    /// Neutral plane h_NP above the lower surface, m (eq. 18 for N layers).
    pub fn neutral_plane_m(&self) -> Complex64 {
        let num: Complex64 = self
            .layers
            .iter()
            .map(|l| l.young_pa * l.thickness_m * l.z_mid())
            .sum();
        let den: Complex64 = self.layers.iter().map(|l| l.young_pa * l.thickness_m).sum();
        num / den
    }

    /// Second moments I_i about the neutral plane per unit width, m³ (eq. 17).
    pub fn second_moments_m3(&self) -> Vec<Complex64> {
        let z_n = self.neutral_plane_m();
        self.layers
            .iter()
            .map(|l| {
                let d = l.z_mid() - z_n;
                l.thickness_m * (l.thickness_m * l.thickness_m / 12.0 + d * d)
            })
            .collect()
    }

    /// Bending stiffnesses B_i = E_i I_i per unit width, N·m (eq. 16).
    pub fn layer_bending_stiffness(&self) -> Vec<Complex64> {
        self.layers
            .iter()
            .zip(self.second_moments_m3())
            .map(|(l, i)| l.young_pa * i)
            .collect()
    }

    /// Bending stiffness of the perfectly bonded stack B_eq = Σ B_i per unit width, N·m
    /// (eqs. 14, 30).
    pub fn bending_stiffness(&self) -> Complex64 {
        self.layer_bending_stiffness().into_iter().sum()
    }

    /// Shear compliances 1/K_i per layer (m/N), from the Jourawski shear stress (eq. 24 and the
    /// module doc).
    pub fn shear_compliances(&self) -> Vec<Complex64> {
        // Three-point Gauss–Legendre on [-1, 1]: exact for the quartic S(z)².
        const NODES: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
        const WEIGHTS: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        let z_n = self.neutral_plane_m();
        let b_eq = self.bending_stiffness();
        let mut s_bottom = Complex64::new(0.0, 0.0);
        self.layers
            .iter()
            .map(|l| {
                let (z0, h, s0) = (l.z_bottom_m, l.thickness_m, s_bottom);
                let s = |z: f64| s0 + l.young_pa * (0.5 * (z * z - z0 * z0) - z_n * (z - z0));
                let integral: Complex64 = NODES
                    .iter()
                    .zip(WEIGHTS)
                    .map(|(xi, w)| {
                        let sz = s(z0 + 0.5 * h * (1.0 + xi));
                        w * sz * sz
                    })
                    .sum::<Complex64>()
                    * (0.5 * h);
                s_bottom = s(l.z_top());
                integral / (l.shear_pa * b_eq * b_eq)
            })
            .collect()
    }

    /// Equivalent transverse shear stiffness K_eq per unit width, N/m (eq. 24).
    pub fn shear_stiffness(&self) -> Complex64 {
        1.0 / self.shear_compliances().into_iter().sum::<Complex64>()
    }

    /// The paper's eqs. 25–27 for a three-layer section, literally, per unit width (b = 1):
    /// `[1/K_1, 1/K_2, 1/K_3]` in m/N, or `None` if the section does not have three layers.
    pub fn paper_three_layer_compliances(&self) -> Option<[Complex64; 3]> {
        let [l1, l2, l3] = self.layers.as_slice() else {
            return None;
        };
        let (h1, h2, h3) = (l1.thickness_m, l2.thickness_m, l3.thickness_m);
        let i = self.second_moments_m3();
        let m2 = l2.young_pa / l1.young_pa;
        let m3 = l3.young_pa / l1.young_pa;
        let (t2, t3) = (h2 / h1, h3 / h1);
        let r = 2.0 * self.neutral_plane_m() / h1;
        let (r2, r3) = (i[1] / i[0], i[2] / i[0]);
        let a = 1.0 + r2 * m2 + r3 * m3;
        let b = 1.0 + 3.0 * (r - 1.0) * (r - 1.0);
        let den = a * a * b * b;
        let inv_k1 = 6.0 / (5.0 * l1.shear_pa * h1) * (10.0 * r * r - 15.0 * r + 6.0) / den;
        let inv_k2 = (36.0 * t2 * (r - 1.0) * (r - 1.0)
            - 12.0 * m2 * t2 * t2 * (r - 1.0) * (2.0 * t2 - 3.0 * r + 6.0))
            / (l2.shear_pa * h1 * den)
            + 6.0 / (5.0 * l2.shear_pa * h2)
                * m2
                * m2
                * t2.powi(4)
                * (10.0 * r * r - 15.0 * r * t2 - 40.0 * r + 6.0 * t2 * t2 + 30.0 * t2 + 40.0)
                / den;
        let inv_k3 = 6.0 * m3 * m3 * t3.powi(4) / (5.0 * l3.shear_pa * h3)
            * (10.0 * r * r - 25.0 * r * t3 - 40.0 * r * t2 - 40.0 * r
                + 16.0 * t3 * t3
                + 50.0 * t3 * t2
                + 50.0 * t3
                + 40.0 * t2 * t2
                + 80.0 * t2
                + 40.0)
            / den;
        Some([inv_k1, inv_k2, inv_k3])
    }
}
