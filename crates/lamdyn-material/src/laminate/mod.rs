//! Layered plates: stacks of layers, the paper's homogenization (eqs. 11–32) and its inverse
//! (eqs. 33–45).
//!
//! - [`LayerStack`]: N layers with any laws; [`LayerStack::section`] evaluates the moduli at one
//!   frequency into a [`Section`] (neutral plane, B_eq, K_eq), and [`LayerStack::homogenize`]
//!   gives the apparent stiffness B_K(ω), φ(ω) and E_eff*(ω) ([`Homogenized`]).
//! - [`SandwichStack`]: two elastic faces around a core of unknown modulus, the input of the
//!   inverses ([`paper_inverse`], and the exact one in [`crate::sandwich`]).
//! - [`Kinematics`]: beam (the paper's equations as written, per unit width) or plate in
//!   cylindrical bending (each layer's E replaced by E/(1−ν²)).
//! - [`StackSpec`]: the TOML description of a stack.
//!
//! All quantities are per unit width and SI: B in N·m, K in N/m, ρ_S in kg/m², moduli in Pa.

mod homogenized;
mod inverse;
mod section;
mod spec;

pub use homogenized::{
    Homogenized, ModelWarning, PAPER_LOSS_AGREEMENT, PAPER_STORAGE_AGREEMENT, PHI_ACCURACY_LIMIT,
    agrees_with_exact, apparent_stiffness, phi, phi_from_stiffness_ratio,
};
pub use inverse::{
    CoreEstimate, CoreShearFormula, FaceBending, FaceShear, PaperInverseOptions, paper_forward,
    paper_inverse,
};
pub use section::{Section, SectionLayer};
pub use spec::{LayerSpec, StackSpec};

use crate::error::{MaterialError, check};
use crate::law::{ConstantModulus, ViscoelasticLaw};
use crate::units::Quantity;
use num_complex::Complex64;
use std::sync::Arc;

/// How a layered section bends.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Kinematics {
    /// A beam of unit width: moduli used as given (the paper's eqs. 14–31 as written).
    #[default]
    Beam,
    /// A plate in cylindrical bending: each layer bends with E/(1−ν²); the effective modulus is
    /// reported for a plate model whose Poisson ratio is `poisson` (E_eff = 12 B_K (1−ν²)/h³).
    Plate {
        /// Poisson ratio of the homogeneous plate model that uses E_eff (usually the faces').
        poisson: f64,
    },
}

impl Kinematics {
    /// Factor from a layer's Young's modulus to its bending modulus: 1 or 1/(1−ν²).
    pub fn bending_factor(self, layer_poisson: f64) -> f64 {
        match self {
            Self::Beam => 1.0,
            Self::Plate { .. } => 1.0 / (1.0 - layer_poisson * layer_poisson),
        }
    }

    /// Factor from the beam-equivalent modulus 12 B_K/h³ to the reported E_eff: 1 or (1−ν²).
    pub fn effective_modulus_factor(self) -> f64 {
        match self {
            Self::Beam => 1.0,
            Self::Plate { poisson } => 1.0 - poisson * poisson,
        }
    }

    fn validate(self) -> Result<Self, MaterialError> {
        if let Self::Plate { poisson } = self {
            check::poisson("plate kinematics", "poisson", poisson)?;
        }
        Ok(self)
    }
}

/// Which modulus a layer's law describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModulusKind {
    /// The law gives Young's modulus E*; G* = E*/(2(1+ν)).
    Young,
    /// The law gives the shear modulus G*; E* = 2(1+ν) G*.
    Shear,
}

/// One layer of a stack.
#[derive(Debug, Clone)]
pub struct Layer {
    name: String,
    thickness_m: f64,
    density_kg_m3: f64,
    poisson: f64,
    kind: ModulusKind,
    law: Arc<dyn ViscoelasticLaw>,
}

impl Layer {
    /// A layer whose `kind` modulus follows `law`; ν relates E and G (isotropic).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for a non-positive thickness or density, or ν outside
    /// (−1, 0.5), naming the layer.
    pub fn new(
        name: impl Into<String>,
        thickness_m: f64,
        density_kg_m3: f64,
        poisson: f64,
        kind: ModulusKind,
        law: Arc<dyn ViscoelasticLaw>,
    ) -> Result<Self, MaterialError> {
        let name = name.into();
        let ctx = format!("layer '{name}'");
        check::si(&ctx, "thickness_m", thickness_m, Quantity::Thickness)?;
        check::si(&ctx, "density_kg_m3", density_kg_m3, Quantity::Density)?;
        check::poisson(&ctx, "poisson", poisson)?;
        Ok(Self {
            name,
            thickness_m,
            density_kg_m3,
            poisson,
            kind,
            law,
        })
    }

    /// An elastic layer with Young's modulus E (Pa) and a constant loss factor.
    ///
    /// # Errors
    /// As [`Layer::new`], and [`MaterialError::InvalidParameter`] for E ≤ 0 or η < 0.
    pub fn elastic(
        name: impl Into<String>,
        thickness_m: f64,
        density_kg_m3: f64,
        young_pa: f64,
        poisson: f64,
        loss_factor: f64,
    ) -> Result<Self, MaterialError> {
        let name = name.into();
        let law = ConstantModulus::new(young_pa, loss_factor)
            .map_err(|e| e.context(&format!("layer '{name}'")))?;
        Self::new(
            name,
            thickness_m,
            density_kg_m3,
            poisson,
            ModulusKind::Young,
            Arc::new(law),
        )
    }

    /// The layer's name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Thickness, m.
    pub fn thickness_m(&self) -> f64 {
        self.thickness_m
    }
    /// Density, kg/m³.
    pub fn density_kg_m3(&self) -> f64 {
        self.density_kg_m3
    }
    /// Poisson ratio.
    pub fn poisson(&self) -> f64 {
        self.poisson
    }

    /// Complex Young's and shear moduli (E*, G*) in Pa at ω (rad/s).
    pub fn moduli(&self, omega_rad_s: f64) -> (Complex64, Complex64) {
        let m = self.law.modulus(omega_rad_s);
        let two_one_plus_nu = 2.0 * (1.0 + self.poisson);
        match self.kind {
            ModulusKind::Young => (m, m / two_one_plus_nu),
            ModulusKind::Shear => (m * two_one_plus_nu, m),
        }
    }
}

/// Largest factor between a given surface density and its layers' Σ ρ_i h_i. A part's
/// measured mass per area differs from its nominal layers by their tolerances and by what the
/// layers leave out (adhesive, coatings, inserts): some percent, rarely some ten; a factor
/// beyond 1.5 is a wrong unit (g/m², a mass not divided by the area) or a wrong layer.
pub const SURFACE_DENSITY_FACTOR: f64 = 1.5;

/// A given surface density `given` (kg/m²) within [`SURFACE_DENSITY_FACTOR`] of its layers'
/// Σ ρ_i h_i, `of_layers`.
fn check_surface_density(context: &str, given: f64, of_layers: f64) -> Result<(), MaterialError> {
    let ratio = given / of_layers;
    if (1.0 / SURFACE_DENSITY_FACTOR..=SURFACE_DENSITY_FACTOR).contains(&ratio) {
        return Ok(());
    }
    Err(MaterialError::InvalidParameter {
        context: context.into(),
        field: "surface_density_kg_m2".into(),
        value: format!("{given}"),
        requirement: format!(
            "contradicts the layers, whose densities times thicknesses sum to {of_layers:.4} \
             kg/m^2 ({ratio:.2} times that; at most a factor {SURFACE_DENSITY_FACTOR} is \
             accepted): check its unit (kg/m^2) and the layers' densities and thicknesses"
        ),
    })
}

/// A stack of layers, bottom to top, with an optional measured surface density.
#[derive(Debug, Clone)]
pub struct LayerStack {
    layers: Vec<Layer>,
    surface_density_kg_m2: Option<f64>,
}

impl LayerStack {
    /// A stack of `layers` (bottom to top). `surface_density_kg_m2`, when given, replaces
    /// Σ ρ_i h_i (e.g. the measured mass of a part over its area, as in the paper).
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for an empty stack or a non-positive surface density.
    pub fn new(
        layers: Vec<Layer>,
        surface_density_kg_m2: Option<f64>,
    ) -> Result<Self, MaterialError> {
        if layers.is_empty() {
            return Err(MaterialError::InvalidParameter {
                context: "stack".into(),
                field: "layers".into(),
                value: "[]".into(),
                requirement: "must hold at least one layer".into(),
            });
        }
        let stack = Self {
            layers,
            surface_density_kg_m2,
        };
        if let Some(rho) = surface_density_kg_m2 {
            check::positive("stack", "surface_density_kg_m2", rho)?;
            check_surface_density("stack", rho, stack.layers_surface_density_kg_m2())?;
        }
        Ok(stack)
    }

    /// The layers, bottom to top.
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// Total thickness h = Σ h_i, m.
    pub fn thickness_m(&self) -> f64 {
        self.layers.iter().map(|l| l.thickness_m).sum()
    }

    /// Surface density ρ_S, kg/m²: the override if given, else Σ ρ_i h_i.
    pub fn surface_density_kg_m2(&self) -> f64 {
        self.surface_density_kg_m2
            .unwrap_or_else(|| self.layers_surface_density_kg_m2())
    }

    /// The layers' Σ ρ_i h_i, kg/m² (the override left out).
    pub fn layers_surface_density_kg_m2(&self) -> f64 {
        self.layers
            .iter()
            .map(|l| l.density_kg_m3 * l.thickness_m)
            .sum()
    }

    /// The section at ω (rad/s) under `kinematics`.
    pub fn section(&self, omega_rad_s: f64, kinematics: Kinematics) -> Section {
        let layers = self.layers.iter().map(|l| {
            let (e, g) = l.moduli(omega_rad_s);
            (l.thickness_m, e * kinematics.bending_factor(l.poisson), g)
        });
        Section::new(layers, self.surface_density_kg_m2())
    }

    /// The paper's homogenized plate at ω (rad/s): B_eq (eq. 14), K_eq (eqs. 24–27, for any
    /// number of layers), φ (eq. 31), B_K (eq. 29) and E_eff = 12 B_K/h³.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] for invalid plate kinematics.
    pub fn homogenize(
        &self,
        omega_rad_s: f64,
        kinematics: Kinematics,
    ) -> Result<Homogenized, MaterialError> {
        let kinematics = kinematics.validate()?;
        let section = self.section(omega_rad_s, kinematics);
        Ok(Homogenized::new(
            omega_rad_s,
            section.bending_stiffness(),
            section.shear_stiffness(),
            &section,
            kinematics,
        ))
    }
}

/// An elastic face of a [`SandwichStack`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Thickness, m.
    pub thickness_m: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Young's modulus, Pa.
    pub young_pa: f64,
    /// Poisson ratio.
    pub poisson: f64,
    /// Constant loss factor (0 for glass at room temperature, up to ~2e-4).
    pub loss_factor: f64,
}

impl Face {
    fn validate(&self, ctx: &str) -> Result<(), MaterialError> {
        check::si(ctx, "thickness_m", self.thickness_m, Quantity::Thickness)?;
        check::si(ctx, "density_kg_m3", self.density_kg_m3, Quantity::Density)?;
        check::si(ctx, "young_pa", self.young_pa, Quantity::StiffModulus)?;
        check::poisson(ctx, "poisson", self.poisson)?;
        check::non_negative(ctx, "loss_factor", self.loss_factor)?;
        Ok(())
    }

    /// Complex Young's modulus E (1 + iη), Pa.
    pub fn young(&self) -> Complex64 {
        Complex64::new(self.young_pa, self.young_pa * self.loss_factor)
    }
}

/// Geometry of a core whose modulus is the unknown of an inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreGeometry {
    /// Thickness, m.
    pub thickness_m: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Poisson ratio (E = 2(1+ν)G where the core's extension matters).
    pub poisson: f64,
}

/// Two elastic faces around a viscoelastic core: the laminate of the paper's inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SandwichStack {
    bottom: Face,
    core: CoreGeometry,
    top: Face,
    surface_density_kg_m2: Option<f64>,
}

impl SandwichStack {
    /// Builds the sandwich.
    ///
    /// # Errors
    /// [`MaterialError::InvalidParameter`] naming the face or core and the field.
    pub fn new(
        bottom: Face,
        core: CoreGeometry,
        top: Face,
        surface_density_kg_m2: Option<f64>,
    ) -> Result<Self, MaterialError> {
        bottom.validate("bottom face")?;
        top.validate("top face")?;
        check::si("core", "thickness_m", core.thickness_m, Quantity::Thickness)?;
        check::si(
            "core",
            "density_kg_m3",
            core.density_kg_m3,
            Quantity::Density,
        )?;
        check::poisson("core", "poisson", core.poisson)?;
        let sandwich = Self {
            bottom,
            core,
            top,
            surface_density_kg_m2,
        };
        if let Some(rho) = surface_density_kg_m2 {
            check::positive("sandwich", "surface_density_kg_m2", rho)?;
            check_surface_density("sandwich", rho, sandwich.layers_surface_density_kg_m2())?;
        }
        Ok(sandwich)
    }

    /// The paper's roof (Table 1): 1.715 mm glass / 0.42 mm PVB / 1.715 mm glass, glass
    /// E = 70 GPa (eq. 35), ν = 0.22, ρ = 2500 kg/m³; PVB ρ = 1070 kg/m³, ν = 0.49 (assumed, not in
    /// the paper); surface density 10.40 kg/m² as measured (8.54 kg over 0.8212 m²).
    pub fn paper_roof() -> Self {
        let glass = Face {
            thickness_m: 1.715e-3,
            density_kg_m3: 2500.0,
            young_pa: 70e9,
            poisson: 0.22,
            loss_factor: 0.0,
        };
        let core = CoreGeometry {
            thickness_m: 0.42e-3,
            density_kg_m3: 1070.0,
            poisson: 0.49,
        };
        Self {
            bottom: glass,
            core,
            top: glass,
            surface_density_kg_m2: Some(10.40),
        }
    }

    /// Lower face.
    pub fn bottom(&self) -> &Face {
        &self.bottom
    }
    /// Upper face.
    pub fn top(&self) -> &Face {
        &self.top
    }
    /// Core geometry.
    pub fn core(&self) -> &CoreGeometry {
        &self.core
    }

    /// Total thickness h = h_1 + h_a + h_3 (eq. 34), m.
    pub fn thickness_m(&self) -> f64 {
        self.bottom.thickness_m + self.core.thickness_m + self.top.thickness_m
    }

    /// Surface density ρ_S, kg/m²: the override if given, else Σ ρ_i h_i.
    pub fn surface_density_kg_m2(&self) -> f64 {
        self.surface_density_kg_m2
            .unwrap_or_else(|| self.layers_surface_density_kg_m2())
    }

    /// The layers' Σ ρ_i h_i, kg/m² (the override left out).
    pub fn layers_surface_density_kg_m2(&self) -> f64 {
        self.bottom.density_kg_m3 * self.bottom.thickness_m
            + self.core.density_kg_m3 * self.core.thickness_m
            + self.top.density_kg_m3 * self.top.thickness_m
    }

    /// True when both faces are identical (thickness, modulus, loss, ν) to 1e-12 relative.
    pub fn is_symmetric(&self) -> bool {
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
        same(self.bottom.thickness_m, self.top.thickness_m)
            && same(self.bottom.young_pa, self.top.young_pa)
            && same(self.bottom.loss_factor, self.top.loss_factor)
            && same(self.bottom.poisson, self.top.poisson)
    }

    /// The section with core shear modulus `core_shear_pa` (E_core = 2(1+ν)G) under
    /// `kinematics`.
    pub fn section(&self, core_shear_pa: Complex64, kinematics: Kinematics) -> Section {
        let face = |f: &Face| {
            let e = f.young();
            (
                f.thickness_m,
                e * kinematics.bending_factor(f.poisson),
                e / (2.0 * (1.0 + f.poisson)),
            )
        };
        let nu_c = self.core.poisson;
        let core = (
            self.core.thickness_m,
            core_shear_pa * 2.0 * (1.0 + nu_c) * kinematics.bending_factor(nu_c),
            core_shear_pa,
        );
        Section::new(
            [face(&self.bottom), core, face(&self.top)],
            self.surface_density_kg_m2(),
        )
    }

    /// A [`LayerStack`] with this geometry and a core whose shear modulus follows `law`.
    pub fn with_core_law(
        &self,
        law: Arc<dyn ViscoelasticLaw>,
    ) -> Result<LayerStack, MaterialError> {
        let face = |name: &str, f: &Face| {
            Layer::elastic(
                name,
                f.thickness_m,
                f.density_kg_m3,
                f.young_pa,
                f.poisson,
                f.loss_factor,
            )
        };
        let core = Layer::new(
            "core",
            self.core.thickness_m,
            self.core.density_kg_m3,
            self.core.poisson,
            ModulusKind::Shear,
            law,
        )?;
        LayerStack::new(
            vec![
                face("bottom face", &self.bottom)?,
                core,
                face("top face", &self.top)?,
            ],
            self.surface_density_kg_m2,
        )
    }

    /// Plate kinematics with the faces' Poisson ratio (the bottom face's).
    pub fn plate_kinematics(&self) -> Kinematics {
        Kinematics::Plate {
            poisson: self.bottom.poisson,
        }
    }
}
