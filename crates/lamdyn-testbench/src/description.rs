//! The TOML description of a virtual test (`lamdyn simulate`), and the bench it builds.
//!
//! A description names the part (`[plate]`: footprint and radii of curvature), its mesh
//! (`[mesh]`), the layer stack (`[[layers]]`, the material crate's layer format: the layers
//! with a frequency-dependent `shear_law` or `young_law` are the core — one or several, all with
//! the same law, as the two PVB interlayers of a five-layer laminate; the others are elastic
//! with `young_pa` or `shear_pa` and one common optional `loss_factor`), optional elastic
//! supports (`[supports]`), the measurement (`[test]`: sensor grid or explicit sensors, hammer,
//! band, noise on the FRFs), optional hammer hits as time signals (`[hits]`), and the reduced
//! basis (`[basis]`). `examples/roof.toml` ([`ROOF_TOML`]) is the built-in example: the paper's
//! roof (Table 1 footprint and thicknesses), doubly curved, with a PVB-like core at room
//! temperature. Unknown keys, unknown law kinds and missing fields are errors naming the key
//! and line; non-physical values are errors naming the field.
//!
//! **Core scale.** The core is assembled with the real shear modulus G_a = Re G*(2π f_a) at the
//! basis's first reference frequency f_a (Young's modulus 2 G_a (1 + ν)); the FRFs use s(ω) =
//! G*(ω)/G_a ([`lamdyn_layered::reduced`]). A `young_law` core is scaled the same way by E*(ω)/E_a.

use crate::error::BenchError;
use crate::impact::{HitSettings, Hits, ImpactTest, Support, simulate, simulate_hits};
use crate::impact::{check_layout, hammer_load, support_terms};
use lamdyn_frf::FrfSet;
use lamdyn_layered::hex20::Elastic;
use lamdyn_layered::mesh::{HexMesh, LayerMesh, LayeredPlateSpec};
use lamdyn_layered::reduced::ReducedModel;
use lamdyn_layered::system::LayeredSystem;
use lamdyn_material::laminate::LayerSpec;
use lamdyn_material::law::ViscoelasticLaw;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The built-in example `roof` (module docs).
pub const ROOF_TOML: &str = include_str!("../examples/roof.toml");

/// A virtual test as written in a TOML file (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Description {
    /// The part's geometry.
    pub plate: PlateSpec,
    /// Its mesh.
    pub mesh: MeshSpec,
    /// The layers, bottom to top.
    pub layers: Vec<LayerSpec>,
    /// Elastic supports (none: free-free).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub supports: Option<SupportsSpec>,
    /// The measurement.
    pub test: TestSpec,
    /// Hammer hits as time signals (none: FRFs only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hits: Option<HitsSpec>,
    /// The reduced basis.
    #[serde(default)]
    pub basis: BasisSpec,
}

/// `[plate]`: a shallow doubly curved plate over a rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSpec {
    /// Length along x, m.
    pub length_m: f64,
    /// Width along y, m.
    pub width_m: f64,
    /// Radius of curvature along x, m (`inf` or absent: straight; negative: a bowl, curved
    /// towards +z).
    #[serde(default = "infinite")]
    pub radius_x_m: f64,
    /// Radius of curvature along y, m (`inf` or absent: straight; negative: curved towards +z).
    #[serde(default = "infinite")]
    pub radius_y_m: f64,
}

fn infinite() -> f64 {
    f64::INFINITY
}

/// `[mesh]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Elements along x and y.
    pub elements: [usize; 2],
    /// Elements through each layer's thickness (default one per layer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub through_thickness: Option<Vec<usize>>,
    /// Edge grading of the in-plane element widths in [0, 1) (lamdyn_layered::mesh; default
    /// 0: uniform).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub edge_grading: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// `[supports]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportsSpec {
    /// The supports.
    pub points: Vec<SupportPoint>,
}

/// One support: `[[supports.points]]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportPoint {
    /// Position as fractions of the plan extent.
    pub xy_fraction: [f64; 2],
    /// Stiffness along global x, y, z, N/m.
    pub stiffness_n_m: [f64; 3],
    /// Viscous damping along global x, y, z, N·s/m (default none).
    #[serde(default)]
    pub damping_n_s_m: [f64; 3],
    /// Size of the contact patch along x and y, m (default a point; lamdyn_layered::supports).
    #[serde(default)]
    pub patch_m: [f64; 2],
}

/// `[test]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestSpec {
    /// Sensor grid rows × columns over the top surface (ignored with `sensors`).
    #[serde(default = "default_grid")]
    pub grid: [usize; 2],
    /// Explicit sensors instead of the grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensors: Option<Vec<SensorSpec>>,
    /// Hammer position as fractions of the plan extent (the top node nearest it).
    #[serde(default = "default_hammer")]
    pub hammer_xy_fraction: [f64; 2],
    /// Direction of the hammer's force (absent: along the inward normal; the paper's "1Z−" is
    /// `[0, 0, -1]`, which UFF output needs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hammer_direction: Option<[f64; 3]>,
    /// Line step, Hz.
    #[serde(default = "default_step")]
    pub step_hz: f64,
    /// Highest line, Hz.
    #[serde(default = "default_max")]
    pub max_hz: f64,
    /// Noise on the FRFs, dB below each curve's RMS (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frf_snr_db: Option<f64>,
    /// Seed of every random draw.
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_grid() -> [usize; 2] {
    [9, 9]
}
fn default_hammer() -> [f64; 2] {
    [0.3, 0.35]
}
fn default_step() -> f64 {
    0.25
}
fn default_max() -> f64 {
    80.0
}
fn default_seed() -> u64 {
    1
}

/// One explicit sensor: `[[test.sensors]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Name (channels are `NAME:t1`, `NAME:t2`, `NAME:n`).
    pub name: String,
    /// Position on the top surface, m (within 0.1 mm of a top node).
    pub point_m: [f64; 3],
}

/// `[hits]`: the fields of [`HitSettings`]; the record length is 1/`step_hz`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HitsSpec {
    /// Number of hits.
    pub count: usize,
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Time kept before each hit, s.
    #[serde(default = "default_pretrigger")]
    pub pretrigger_s: f64,
    /// Half-sine pulse duration, s.
    pub pulse_s: f64,
    /// Peak force, N.
    pub peak_force_n: f64,
    /// Hit-to-hit spread of the peak force, fraction.
    #[serde(default)]
    pub force_spread: f64,
    /// Force noise below the peak, dB (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_snr_db: Option<f64>,
    /// Response noise below each channel's RMS, dB (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub response_snr_db: Option<f64>,
}

fn default_pretrigger() -> f64 {
    0.01
}

/// `[basis]`: modes at reference core moduli plus residual and core-sensitivity vectors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BasisSpec {
    /// Real modes per reference modulus.
    #[serde(default = "default_modes")]
    pub modes: usize,
    /// Frequencies at which the core's modulus gives the reference moduli, Hz.
    #[serde(default = "default_reference")]
    pub reference_hz: Vec<f64>,
}

fn default_modes() -> usize {
    40
}
fn default_reference() -> Vec<f64> {
    vec![10.0, 80.0]
}

impl Default for BasisSpec {
    fn default() -> Self {
        Self {
            modes: default_modes(),
            reference_hz: default_reference(),
        }
    }
}

/// A built bench: the mesh, the assembled system, the reduced model and the test.
pub struct Bench {
    /// The mesh.
    pub mesh: HexMesh,
    /// The assembled layered system (supports included).
    pub system: LayeredSystem,
    /// The reduced model.
    pub model: ReducedModel,
    /// Indices of the core layers (one law), bottom to top.
    pub core_layers: Vec<usize>,
    /// The core's law (shear or Young's modulus, as described).
    pub core_law: Box<dyn ViscoelasticLaw>,
    /// Whether the law is of the shear modulus (else Young's).
    pub core_law_is_shear: bool,
    /// Modulus the core was assembled with, Pa.
    pub assembled_modulus_pa: f64,
    /// The measurement.
    pub test: ImpactTest,
    /// The hits, if described.
    pub hits: Option<HitSettings>,
}

impl Bench {
    /// The core's true law at `freqs_hz` as CSV (`f_hz,storage_pa,loss_pa,loss_factor`, Pa),
    /// under a comment naming the law: the table `lamdyn simulate` writes as truth.csv and the
    /// chain reads back to state its errors.
    pub fn truth_table(&self, freqs_hz: &[f64]) -> String {
        let which = if self.core_law_is_shear { "G" } else { "E" };
        let mut s = format!(
            "# the core's law ({which}*), layers {:?}: {}\nf_hz,storage_pa,loss_pa,loss_factor\n",
            self.core_layers,
            self.core_law.describe()
        );
        for f in freqs_hz {
            let m = self.core_law.modulus(2.0 * std::f64::consts::PI * f);
            s += &format!("{f},{:e},{:e},{:e}\n", m.re, m.im, m.im / m.re);
        }
        s
    }

    /// s(ω) = M*(ω)/M_a (module docs).
    pub fn core_scale(&self, omega: f64) -> Complex64 {
        self.core_law.modulus(omega) / self.assembled_modulus_pa
    }

    /// The simulated accelerance FRFs ([`simulate`]).
    ///
    /// # Errors
    /// As [`simulate`].
    pub fn frfs(&self) -> Result<FrfSet, BenchError> {
        simulate(&self.mesh, &self.model, &|w| self.core_scale(w), &self.test)
    }

    /// The simulated hits ([`simulate_hits`]), if the description has `[hits]`.
    ///
    /// # Errors
    /// As [`simulate_hits`].
    pub fn hit_records(&self) -> Result<Option<Hits>, BenchError> {
        self.hits
            .as_ref()
            .map(|h| {
                simulate_hits(
                    &self.mesh,
                    &self.model,
                    &|w| self.core_scale(w),
                    &self.test,
                    h,
                )
            })
            .transpose()
    }

    /// Number of degrees of freedom.
    pub fn dofs(&self) -> usize {
        self.system.n_dofs
    }
}

fn invalid(field: &str, why: String) -> BenchError {
    BenchError::Invalid(format!("{field}: {why}"))
}

fn positive(field: &str, v: f64) -> Result<(), BenchError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("{v} must be positive")))
    }
}

/// The material description of one layer, after its checks.
enum LayerMaterial {
    Elastic(Elastic, f64),
    Core(Box<dyn ViscoelasticLaw>, bool, f64, f64),
}

fn layer_name(l: &LayerSpec, i: usize) -> String {
    match &l.name {
        Some(n) => format!("layers[{i}] ('{n}')"),
        None => format!("layers[{i}]"),
    }
}

fn layer_material(l: &LayerSpec, i: usize) -> Result<LayerMaterial, BenchError> {
    let at = layer_name(l, i);
    positive(&format!("{at}.thickness_m"), l.thickness_m)?;
    positive(&format!("{at}.density_kg_m3"), l.density_kg_m3)?;
    if !(l.poisson.is_finite() && l.poisson > -1.0 && l.poisson < 0.5) {
        return Err(invalid(
            &format!("{at}.poisson"),
            format!("{} must lie in (-1, 0.5)", l.poisson),
        ));
    }
    let given = [
        l.young_pa.is_some(),
        l.shear_pa.is_some(),
        l.young_law.is_some(),
        l.shear_law.is_some(),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(invalid(
            &at,
            "give exactly one of young_pa, shear_pa, young_law, shear_law".into(),
        ));
    }
    let elastic = |young: f64, eta: f64| {
        LayerMaterial::Elastic(
            Elastic {
                young_pa: young,
                poisson: l.poisson,
                density_kg_m3: l.density_kg_m3,
            },
            eta,
        )
    };
    let eta = l.loss_factor.unwrap_or(0.0);
    if !(eta.is_finite() && eta >= 0.0) {
        return Err(invalid(
            &format!("{at}.loss_factor"),
            format!("{eta} must be non-negative"),
        ));
    }
    if let Some(e) = l.young_pa {
        positive(&format!("{at}.young_pa"), e)?;
        return Ok(elastic(e, eta));
    }
    if let Some(g) = l.shear_pa {
        positive(&format!("{at}.shear_pa"), g)?;
        return Ok(elastic(2.0 * g * (1.0 + l.poisson), eta));
    }
    if l.loss_factor.is_some() {
        return Err(invalid(
            &format!("{at}.loss_factor"),
            "goes with young_pa or shear_pa; a law carries its own loss".into(),
        ));
    }
    let (spec, shear, field) = match (&l.shear_law, &l.young_law) {
        (Some(s), _) => (s, true, "shear_law"),
        (None, Some(y)) => (y, false, "young_law"),
        (None, None) => unreachable!("one modulus is given (checked above)"),
    };
    let law = spec
        .build()
        .map_err(|e| invalid(&format!("{at}.{field}"), e.to_string()))?;
    Ok(LayerMaterial::Core(law, shear, l.poisson, l.density_kg_m3))
}

impl Description {
    /// Parses a TOML description; `origin` (a file name) prefixes the errors.
    ///
    /// # Errors
    /// [`BenchError::Invalid`] with the parser's message: the key, line and column.
    pub fn parse(origin: &str, text: &str) -> Result<Self, BenchError> {
        toml::from_str(text).map_err(|e| BenchError::Invalid(format!("'{origin}': {e}")))
    }

    /// The built-in `roof` ([`ROOF_TOML`]).
    pub fn roof() -> Self {
        // The embedded file is checked by this crate's tests.
        Self::parse("roof.toml", ROOF_TOML).expect("the built-in roof description parses")
    }

    /// Checks the description and builds the bench: mesh, assembly, supports, reduced basis.
    /// `progress` hears each stage's name before it starts.
    ///
    /// # Errors
    /// [`BenchError::Invalid`] naming the field for non-physical values, no or several
    /// frequency-dependent layers, sensors off the surface; [`BenchError::Solver`] from the
    /// eigen and static solves.
    pub fn build(&self, progress: &mut dyn FnMut(&str)) -> Result<Bench, BenchError> {
        let (materials, core) = self.materials()?;
        let (core_layers, law, shear, core_materials) = core;
        let f_a = self.check_basis()?;
        let m_a = law.modulus(2.0 * PI * f_a).re;
        positive("the core's storage modulus at basis.reference_hz[0]", m_a)?;
        let eta_e = materials.first().map_or(0.0, |m| m.1);
        if materials.iter().any(|m| m.1 != eta_e) {
            return Err(invalid(
                "layers",
                "the elastic layers must share one loss_factor (the bench scales them together)"
                    .into(),
            ));
        }
        // Every layer's material, bottom to top: the cores assembled at the reference modulus.
        let mut elastic: Vec<Elastic> = materials.iter().map(|m| m.0).collect();
        for (&at, &(poisson, density)) in core_layers.iter().zip(&core_materials) {
            let young_a = if shear {
                2.0 * m_a * (1.0 + poisson)
            } else {
                m_a
            };
            elastic.insert(
                at,
                Elastic {
                    young_pa: young_a,
                    poisson,
                    density_kg_m3: density,
                },
            );
        }
        progress("mesh");
        let mesh = self.mesh_spec()?.build()?;
        progress("assembly");
        let mut system = LayeredSystem::assemble(&mesh, &elastic)?;
        if let Some(s) = &self.supports {
            let pts: Vec<Support> = s
                .points
                .iter()
                .map(|p| Support {
                    xy_fraction: p.xy_fraction,
                    stiffness_n_m: p.stiffness_n_m,
                    damping_n_s_m: p.damping_n_s_m,
                    patch_m: p.patch_m,
                })
                .collect();
            system.add_supports(&support_terms(&mesh, &pts)?)?;
        }
        let test = self.impact_test(&mesh)?;
        check_layout(&mesh, &test)?;
        let hits = self.hit_settings()?;
        progress("reduced basis");
        let ratios: Vec<f64> = self
            .basis
            .reference_hz
            .iter()
            .map(|f| law.modulus(2.0 * PI * f).norm() / m_a)
            .collect();
        let load = hammer_load(&mesh, &test)?;
        // Free-free: shift below the rigid-body modes; supported: still below every mode.
        let shift = -(2.0 * PI).powi(2);
        let mut model = ReducedModel::new(
            &system,
            &core_layers,
            &ratios,
            self.basis.modes,
            &[load],
            shift,
        )?;
        model.set_elastic_loss(eta_e)?;
        Ok(Bench {
            mesh,
            system,
            model,
            core_layers,
            core_law: law,
            core_law_is_shear: shear,
            assembled_modulus_pa: m_a,
            test,
            hits,
        })
    }

    /// The elastic layers (material, loss) in order without the cores, and the cores'
    /// (indices, law, is-shear, (Poisson, density) per core layer).
    #[allow(clippy::type_complexity)]
    fn materials(
        &self,
    ) -> Result<
        (
            Vec<(Elastic, f64)>,
            (Vec<usize>, Box<dyn ViscoelasticLaw>, bool, Vec<(f64, f64)>),
        ),
        BenchError,
    > {
        if self.layers.len() < 2 {
            return Err(invalid(
                "layers",
                format!(
                    "{} layer(s): a laminate needs a core and a face",
                    self.layers.len()
                ),
            ));
        }
        let mut elastic = Vec::new();
        let mut core: Option<(Vec<usize>, Box<dyn ViscoelasticLaw>, bool, Vec<(f64, f64)>)> = None;
        for (i, l) in self.layers.iter().enumerate() {
            match layer_material(l, i)? {
                LayerMaterial::Elastic(e, eta) => elastic.push((e, eta)),
                LayerMaterial::Core(law, shear, nu, rho) => match &mut core {
                    None => core = Some((vec![i], law, shear, vec![(nu, rho)])),
                    Some((at, _, _, own)) => {
                        let first = &self.layers[at[0]];
                        if (l.shear_law.as_ref(), l.young_law.as_ref())
                            != (first.shear_law.as_ref(), first.young_law.as_ref())
                        {
                            return Err(invalid(
                                &layer_name(l, i),
                                format!(
                                    "its law differs from {}'s: the core layers share one law (one \
                                     material)",
                                    layer_name(first, at[0])
                                ),
                            ));
                        }
                        at.push(i);
                        own.push((nu, rho));
                    }
                },
            }
        }
        let core = core.ok_or_else(|| {
            invalid(
                "layers",
                "no layer has a shear_law or young_law: the core must have one".into(),
            )
        })?;
        if elastic.is_empty() {
            return Err(invalid(
                "layers",
                "every layer has a law: a laminate needs an elastic face".into(),
            ));
        }
        Ok((elastic, core))
    }

    /// The first reference frequency, after checking the basis.
    fn check_basis(&self) -> Result<f64, BenchError> {
        if self.basis.modes == 0 {
            return Err(invalid("basis.modes", "0: at least one mode".into()));
        }
        if self.basis.reference_hz.is_empty() {
            return Err(invalid("basis.reference_hz", "empty".into()));
        }
        for (i, f) in self.basis.reference_hz.iter().enumerate() {
            positive(&format!("basis.reference_hz[{i}]"), *f)?;
        }
        Ok(self.basis.reference_hz[0])
    }

    fn mesh_spec(&self) -> Result<LayeredPlateSpec, BenchError> {
        let through = match &self.mesh.through_thickness {
            Some(t) if t.len() != self.layers.len() => {
                return Err(invalid(
                    "mesh.through_thickness",
                    format!("{} counts for {} layers", t.len(), self.layers.len()),
                ));
            }
            Some(t) => t.clone(),
            None => vec![1; self.layers.len()],
        };
        positive("plate.length_m", self.plate.length_m)?;
        positive("plate.width_m", self.plate.width_m)?;
        for (name, r) in [
            ("plate.radius_x_m", self.plate.radius_x_m),
            ("plate.radius_y_m", self.plate.radius_y_m),
        ] {
            if r.is_nan() || r == 0.0 {
                return Err(invalid(
                    name,
                    format!("{r} must be non-zero (inf: straight, negative: a bowl)"),
                ));
            }
        }
        if self.mesh.elements.contains(&0) || through.contains(&0) {
            return Err(invalid(
                "mesh",
                format!(
                    "elements {:?}, through_thickness {through:?}: every count must be at least 1",
                    self.mesh.elements
                ),
            ));
        }
        Ok(LayeredPlateSpec {
            length_m: self.plate.length_m,
            width_m: self.plate.width_m,
            nx: self.mesh.elements[0],
            ny: self.mesh.elements[1],
            radius_x_m: self.plate.radius_x_m,
            radius_y_m: self.plate.radius_y_m,
            edge_grading: self.mesh.edge_grading,
            layers: self
                .layers
                .iter()
                .zip(&through)
                .map(|(l, &e)| LayerMesh {
                    thickness_m: l.thickness_m,
                    elements: e,
                })
                .collect(),
        })
    }

    fn impact_test(&self, mesh: &HexMesh) -> Result<ImpactTest, BenchError> {
        let t = &self.test;
        let [hx, hy] = t.hammer_xy_fraction;
        if !(0.0..=1.0).contains(&hx) || !(0.0..=1.0).contains(&hy) {
            return Err(invalid(
                "test.hammer_xy_fraction",
                format!("[{hx}, {hy}] must lie in [0, 1]"),
            ));
        }
        positive("test.step_hz", t.step_hz)?;
        if !(t.max_hz.is_finite() && t.max_hz >= t.step_hz) {
            return Err(invalid(
                "test.max_hz",
                format!("{} must be at least step_hz = {}", t.max_hz, t.step_hz),
            ));
        }
        if t.grid.contains(&0) {
            return Err(invalid(
                "test.grid",
                format!("{:?}: at least 1 x 1", t.grid),
            ));
        }
        let mut test = ImpactTest::grid(mesh, t.grid[0], t.grid[1], [hx, hy]);
        if let Some(sensors) = &t.sensors {
            if sensors.is_empty() {
                return Err(invalid("test.sensors", "empty".into()));
            }
            test.sensors = sensors.iter().map(|s| s.point_m).collect();
            test.sensor_names = sensors.iter().map(|s| s.name.clone()).collect();
            test.tolerance_m = 1e-4;
        }
        test.hammer_direction = t.hammer_direction;
        test.step_hz = t.step_hz;
        test.max_hz = t.max_hz;
        test.snr_db = t.frf_snr_db;
        test.seed = t.seed;
        Ok(test)
    }

    fn hit_settings(&self) -> Result<Option<HitSettings>, BenchError> {
        let Some(h) = &self.hits else {
            return Ok(None);
        };
        let s = HitSettings {
            count: h.count,
            rate_hz: h.rate_hz,
            record_s: 1.0 / self.test.step_hz,
            pretrigger_s: h.pretrigger_s,
            pulse_s: h.pulse_s,
            peak_force_n: h.peak_force_n,
            force_spread: h.force_spread,
            force_snr_db: h.force_snr_db,
            response_snr_db: h.response_snr_db,
            seed: self.test.seed,
        };
        if s.rate_hz < 4.0 * self.test.max_hz {
            return Err(invalid(
                "hits.rate_hz",
                format!(
                    "{} Hz: at least 4 x test.max_hz = {} Hz (the anti-alias filter's corner is \
                     0.15 x the rate)",
                    s.rate_hz,
                    4.0 * self.test.max_hz
                ),
            ));
        }
        Ok(Some(s))
    }
}
