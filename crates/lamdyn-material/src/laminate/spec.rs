//! The TOML description of a layer stack.
//!
//! ```toml
//! # Layers from bottom to top; SI units.
//! surface_density_kg_m2 = 10.40     # optional: replaces sum(rho_i h_i), e.g. measured mass / area
//!
//! [[layers]]
//! name = "glass"
//! thickness_m = 1.715e-3
//! density_kg_m3 = 2500.0
//! poisson = 0.22
//! young_pa = 70e9
//! loss_factor = 0.0                 # optional, with young_pa or shear_pa
//!
//! [[layers]]
//! name = "PVB"
//! thickness_m = 0.42e-3
//! density_kg_m3 = 1070.0
//! poisson = 0.49
//! shear_law = { kind = "fractional_zener", g0_pa = 3.504e5, g_inf_pa = 3.062e9, tau_s = 8.23e-9, alpha = 0.675 }
//! ```
//!
//! Each layer gives its Poisson ratio and one modulus: `young_pa`, `shear_pa`, `young_law` or
//! `shear_law`. For an inverse ([`StackSpec::to_sandwich`]) the core's modulus is the unknown and
//! may be left out.

use super::{CoreGeometry, Face, Layer, LayerStack, ModulusKind, SandwichStack};
use crate::error::{MaterialError, check};
use crate::law::{ConstantModulus, LawSpec, ViscoelasticLaw};
use crate::units::Quantity;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A stack as written in a TOML file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackSpec {
    /// Measured surface density, kg/m² (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_density_kg_m2: Option<f64>,
    /// Layers, bottom to top.
    pub layers: Vec<LayerSpec>,
}

/// One layer as written in a TOML file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// A name for messages and reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Thickness, m.
    pub thickness_m: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Poisson ratio.
    pub poisson: f64,
    /// Constant Young's modulus, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young_pa: Option<f64>,
    /// Constant shear modulus, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_pa: Option<f64>,
    /// Loss factor of `young_pa` or `shear_pa` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<f64>,
    /// Law of Young's modulus.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young_law: Option<LawSpec>,
    /// Law of the shear modulus.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_law: Option<LawSpec>,
}

/// A layer's modulus kind and law, as read from its spec.
type LayerModulus = (ModulusKind, Arc<dyn ViscoelasticLaw>);

impl LayerSpec {
    fn location(&self, index: usize) -> String {
        match &self.name {
            Some(n) => format!("layers[{index}] ('{n}')"),
            None => format!("layers[{index}]"),
        }
    }

    fn display_name(&self, index: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("layer {index}"))
    }

    /// The modulus given, if exactly one was.
    fn modulus(&self, loc: &str) -> Result<Option<LayerModulus>, MaterialError> {
        let given: Vec<&str> = [
            ("young_pa", self.young_pa.is_some()),
            ("shear_pa", self.shear_pa.is_some()),
            ("young_law", self.young_law.is_some()),
            ("shear_law", self.shear_law.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(n, _)| *n)
        .collect();
        if given.len() > 1 {
            return Err(unsupported(
                loc,
                format!("give one modulus, got {}", given.join(" and ")),
            ));
        }
        if self.loss_factor.is_some() && (self.young_law.is_some() || self.shear_law.is_some()) {
            return Err(unsupported(
                loc,
                "loss_factor goes with young_pa or shear_pa; a law carries its own loss".into(),
            ));
        }
        let eta = self.loss_factor.unwrap_or(0.0);
        let constant = |m: f64, field: &str| -> Result<Arc<dyn ViscoelasticLaw>, MaterialError> {
            let law = ConstantModulus::new(m, eta).map_err(|e| relocate(e, loc, Some(field)))?;
            Ok(Arc::new(law))
        };
        let law =
            |spec: &LawSpec, field: &str| -> Result<Arc<dyn ViscoelasticLaw>, MaterialError> {
                Ok(Arc::from(
                    spec.build()
                        .map_err(|e| e.context(&format!("{loc}.{field}")))?,
                ))
            };
        let built = match (
            self.young_pa,
            self.shear_pa,
            &self.young_law,
            &self.shear_law,
        ) {
            (Some(e), ..) => Some((ModulusKind::Young, constant(e, "young_pa")?)),
            (_, Some(g), ..) => Some((ModulusKind::Shear, constant(g, "shear_pa")?)),
            (_, _, Some(l), _) => Some((ModulusKind::Young, law(l, "young_law")?)),
            (_, _, _, Some(l)) => Some((ModulusKind::Shear, law(l, "shear_law")?)),
            _ => None,
        };
        if let (Some((_, law)), Some(field)) = (&built, given.first()) {
            check_modulus_units(loc, field, law.as_ref())?;
        }
        Ok(built)
    }
}

/// The modulus at 10 Hz, where every law of a laminate is in its measured range, lies in the
/// plausible SI range ([`crate::units`]): catches MPa or GPa written for Pa.
fn check_modulus_units(
    loc: &str,
    field: &str,
    law: &dyn ViscoelasticLaw,
) -> Result<(), MaterialError> {
    let at_10_hz = law.modulus(2.0 * std::f64::consts::PI * 10.0).norm();
    crate::units::check(Quantity::Modulus, at_10_hz).map_err(|why| {
        MaterialError::InvalidParameter {
            context: loc.to_string(),
            field: field.to_string(),
            value: format!("{at_10_hz:.4e} Pa at 10 Hz"),
            requirement: why.to_string(),
        }
    })?;
    Ok(())
}

fn unsupported(loc: &str, reason: String) -> MaterialError {
    MaterialError::UnsupportedStack {
        context: loc.to_string(),
        reason,
    }
}

/// Puts a parameter error at `loc` (the layer as the file names it), optionally renaming the
/// field (a constant modulus calls its value `storage_pa`; the file calls it `young_pa`).
fn relocate(e: MaterialError, loc: &str, rename_storage: Option<&str>) -> MaterialError {
    match e {
        MaterialError::InvalidParameter {
            field,
            value,
            requirement,
            ..
        } => {
            let field = match rename_storage {
                Some(name) if field == "storage_pa" => name.to_string(),
                _ => field,
            };
            MaterialError::InvalidParameter {
                context: loc.to_string(),
                field,
                value,
                requirement,
            }
        }
        other => other.context(loc),
    }
}

impl StackSpec {
    /// Total thickness Σ h_i, m, as written.
    pub fn thickness_m(&self) -> f64 {
        self.layers.iter().map(|l| l.thickness_m).sum()
    }

    /// Surface density, kg/m², as written: `surface_density_kg_m2` if given, else Σ ρ_i h_i
    /// (what [`LayerStack::surface_density_kg_m2`] gives for the built stack).
    pub fn surface_density_kg_m2(&self) -> f64 {
        self.surface_density_kg_m2.unwrap_or_else(|| {
            self.layers
                .iter()
                .map(|l| l.density_kg_m3 * l.thickness_m)
                .sum()
        })
    }
}

impl StackSpec {
    /// Builds the stack for forward computations: every layer needs a modulus.
    ///
    /// # Errors
    /// [`MaterialError`] naming the layer (`layers[1] ('PVB')`) and the field.
    pub fn to_layer_stack(&self) -> Result<LayerStack, MaterialError> {
        if self.layers.is_empty() {
            return Err(unsupported(
                "stack",
                "at least one [[layers]] table is needed".into(),
            ));
        }
        let layers = self
            .layers
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                let loc = spec.location(i);
                let (kind, law) = spec.modulus(&loc)?.ok_or_else(|| {
                    unsupported(
                        &loc,
                        "no modulus: give young_pa, shear_pa, young_law or shear_law".into(),
                    )
                })?;
                let name = spec.display_name(i);
                Layer::new(
                    name,
                    spec.thickness_m,
                    spec.density_kg_m3,
                    spec.poisson,
                    kind,
                    law,
                )
                .map_err(|e| relocate(e, &loc, None))
            })
            .collect::<Result<Vec<_>, _>>()?;
        LayerStack::new(layers, self.surface_density_kg_m2)
    }

    /// Builds the sandwich of an inverse: three layers, elastic faces (`young_pa`), and a core
    /// whose modulus, if given, is ignored (it is the unknown).
    ///
    /// # Errors
    /// [`MaterialError`] naming the layer and the field.
    pub fn to_sandwich(&self) -> Result<SandwichStack, MaterialError> {
        let [bottom, core, top] = self.layers.as_slice() else {
            return Err(unsupported(
                "stack",
                format!(
                    "the core inverse needs three layers (face, core, face), got {}",
                    self.layers.len()
                ),
            ));
        };
        let (b, t) = (face(bottom, 0)?, face(top, 2)?);
        let core_loc = core.location(1);
        core.modulus(&core_loc)?;
        let geometry = CoreGeometry {
            thickness_m: core.thickness_m,
            density_kg_m3: core.density_kg_m3,
            poisson: core.poisson,
        };
        SandwichStack::new(b, geometry, t, self.surface_density_kg_m2).map_err(|e| match e {
            MaterialError::InvalidParameter { ref context, .. } if context == "core" => {
                relocate(e, &core_loc, None)
            }
            e => e,
        })
    }
}

impl StackSpec {
    /// The viscoelastic (core) layers of a stack for the layered inverse, which finds one law
    /// shared by all of them: in a three-layer stack the middle one (its modulus, if given, is
    /// ignored, as in [`Self::to_sandwich`]); in any other stack the layers without `young_pa`
    /// (a five-layer glass/PVB/glass/PVB/glass laminate has two). Every other layer is an
    /// elastic face with `young_pa`, checked as the sandwich's faces are; every layer's
    /// thickness, density and Poisson's ratio are checked for SI units.
    ///
    /// # Errors
    /// [`MaterialError`] naming the layer and the field; a stack of fewer than two layers, or
    /// without a core or a face.
    pub fn layered_cores(&self) -> Result<Vec<usize>, MaterialError> {
        let n = self.layers.len();
        let cores: Vec<usize> = if n == 3 {
            vec![1]
        } else {
            (0..n)
                .filter(|&i| self.layers[i].young_pa.is_none())
                .collect()
        };
        if n < 2 || cores.is_empty() || cores.len() == n {
            return Err(unsupported(
                "stack",
                format!(
                    "the layered inverse needs elastic faces (with young_pa) and at least one core \
                     (without): {n} layers, {} without young_pa",
                    cores.len()
                ),
            ));
        }
        for (i, layer) in self.layers.iter().enumerate() {
            if cores.contains(&i) {
                let loc = layer.location(i);
                check::si(&loc, "thickness_m", layer.thickness_m, Quantity::Thickness)?;
                check::si(
                    &loc,
                    "density_kg_m3",
                    layer.density_kg_m3,
                    Quantity::Density,
                )?;
                check::poisson(&loc, "poisson", layer.poisson)?;
            } else {
                face(layer, i)?;
            }
        }
        Ok(cores)
    }
}

/// A face of the inverse: an elastic layer with `young_pa`.
fn face(spec: &LayerSpec, index: usize) -> Result<Face, MaterialError> {
    let loc = spec.location(index);
    let young_pa = spec.young_pa.ok_or_else(|| {
        unsupported(
            &loc,
            "a face of the inverse must be elastic: give young_pa (and loss_factor)".into(),
        )
    })?;
    spec.modulus(&loc)?;
    let f = Face {
        thickness_m: spec.thickness_m,
        density_kg_m3: spec.density_kg_m3,
        young_pa,
        poisson: spec.poisson,
        loss_factor: spec.loss_factor.unwrap_or(0.0),
    };
    f.validate(&loc)?;
    Ok(f)
}
