//! Synthetic test data: measurement grids on a mesh, seeded noise, and the paper's plate as a
//! ready-made identification case (the recovery study of docs/fit.md, `lamdyn fit --example`).

use crate::error::FitError;
use crate::probe::{Probe, probes};
use crate::synthesis::{ModalModel, ResidualTerm};
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fem::element::{ElementOrder, ShellMaterial};
use lamdyn_fem::mesh::Mesh;
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_frf::Quantity;
use lamdyn_frf::{Channel, FrfSet};
use num_complex::Complex64;
use std::time::Instant;

/// Standard normal deviates from a seed (SplitMix64 and Box–Muller): reproducible.
pub struct Normal {
    state: u64,
    spare: Option<f64>,
}

impl Normal {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed ^ 0x5DEE_CE66_D1CE_4E5B,
            spare: None,
        }
    }

    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// The next N(0, 1) deviate.
    pub fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let t = 2.0 * std::f64::consts::PI * u2;
        self.spare = Some(r * t.sin());
        r * t.cos()
    }
}

/// The set with multiplicative complex Gaussian noise: H (1 + ε), ε complex normal with
/// E|ε|² = `relative`² (each part with standard deviation relative/√2).
pub fn add_noise(set: &FrfSet, relative: f64, seed: u64) -> FrfSet {
    let mut g = Normal::new(seed);
    let s = relative / std::f64::consts::SQRT_2;
    let data: Vec<Complex64> = set
        .data()
        .iter()
        .map(|h| h * Complex64::new(1.0 + s * g.sample(), s * g.sample()))
        .collect();
    FrfSet::new(
        set.freqs_hz().to_vec(),
        set.responses().to_vec(),
        set.references().to_vec(),
        set.quantity(),
        data,
    )
    .expect("same shape as a valid set")
}

/// Triaxial sensors (+X, +Y, +Z) at the nodes nearest an `nx` × `ny` grid spanning the mesh's
/// bounding box in x and y (edges included): the paper's 81 points × 3 directions for 9 × 9.
pub fn triaxial_grid(mesh: &Mesh, nx: usize, ny: usize) -> Vec<Channel> {
    let xs = mesh.nodes().iter().map(|p| p[0]);
    let ys = mesh.nodes().iter().map(|p| p[1]);
    let (x0, x1) = (
        xs.clone().fold(f64::INFINITY, f64::min),
        xs.fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) = (
        ys.clone().fold(f64::INFINITY, f64::min),
        ys.fold(f64::NEG_INFINITY, f64::max),
    );
    let mut out = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let x = x0 + (x1 - x0) * i as f64 / (nx - 1).max(1) as f64;
            let y = y0 + (y1 - y0) * j as f64 / (ny - 1).max(1) as f64;
            // Nearest node in plan view: search with the node's own height.
            let near = mesh.nodes().iter().enumerate().min_by(|a, b| {
                let d = |p: &[f64; 3]| (p[0] - x).powi(2) + (p[1] - y).powi(2);
                d(a.1).total_cmp(&d(b.1))
            });
            let p = near.map(|(_, p)| *p).unwrap_or([x, y, 0.0]);
            let k = j * nx + i + 1;
            for (axis, dir) in [
                ("X", [1.0, 0.0, 0.0]),
                ("Y", [0.0, 1.0, 0.0]),
                ("Z", [0.0, 0.0, 1.0]),
            ] {
                out.push(
                    Channel::new(format!("{k}+{axis}"), p, dir)
                        .expect("finite point, unit direction"),
                );
            }
        }
    }
    out
}

/// The paper's plate as a synthetic identification case: the Table 1 footprint
/// (0.923 × 0.8632 m) and glass thickness (3.85 mm), flat, free, meshed with MITC9 (or MITC4)
/// shells and geometric edge layers at E_ref = 67.45 GPa (ν = 0.22, ρ = 2702 kg/m³); triaxial
/// sensors on a grid of nodes; one hammer hit along −z at the node nearest (−0.346, −0.216) m
/// (off both symmetry lines, so every mode is excited); lines every `step_hz` up to `max_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct PaperPlateCase {
    /// Elements along each side (edge layers included).
    pub elements: usize,
    /// The element.
    pub element: ElementOrder,
    /// Geometric edge layers at each edge, the outermost half the glass's thickness wide
    /// (0: a uniform mesh).
    pub edge_layers: usize,
    /// FE modes kept in the synthesis (rigid included); the residual term adds the rest.
    pub modes: usize,
    /// Sensor grid (the paper: 9 × 9 points × 3 directions).
    pub grid: (usize, usize),
    /// Line spacing, Hz.
    pub step_hz: f64,
    /// Highest line, Hz.
    pub max_hz: f64,
    /// Relative complex noise (see [`add_noise`]).
    pub noise: f64,
    /// Noise seed.
    pub seed: u64,
    /// Measured quantity.
    pub quantity: Quantity,
}

impl Default for PaperPlateCase {
    /// 12 × 12 MITC9 elements with 2 edge layers (3750 dofs, as many as 24 × 24 MITC4, and
    /// 7e-5 to 1.5e-3 from the Reissner–Mindlin plate in the first six elastic modes where
    /// 24 × 24 MITC4 is 2.3e-3 to 1.0e-2: docs/fem.md), 24 modes, 9 × 9 × 3 sensors,
    /// 0.25–80 Hz every 0.25 Hz, 1 % noise, accelerance: the recovery study.
    fn default() -> Self {
        Self {
            elements: 12,
            element: ElementOrder::Quadratic,
            edge_layers: 2,
            modes: 24,
            grid: (9, 9),
            step_hz: 0.25,
            max_hz: 80.0,
            noise: 0.01,
            seed: 1,
            quantity: Quantity::Accelerance,
        }
    }
}

/// A built synthetic case.
#[derive(Debug, Clone)]
pub struct SyntheticCase {
    /// The mesh.
    pub mesh: Mesh,
    /// The shell material (E_ref = its Young's modulus).
    pub material: ShellMaterial,
    /// K0 and M (for direct solves).
    pub assembly: Assembly,
    /// The sensors on the mesh.
    pub response_probes: Vec<Probe>,
    /// The hammer on the mesh.
    pub reference_probes: Vec<Probe>,
    /// The modal model used both to make and to fit the data.
    pub model: ModalModel,
    /// FRFs from the truth, without noise.
    pub clean: FrfSet,
    /// FRFs with noise: the "measurement".
    pub measured: FrfSet,
    /// Wall time of the eigen solve and the model's projections, s.
    pub model_seconds: f64,
}

impl PaperPlateCase {
    /// The glass of the paper's Table 1 with the Table 2 modulus E0 as E_ref.
    pub const GLASS: ShellMaterial = ShellMaterial {
        young_pa: 67.45e9,
        poisson: 0.22,
        density_kg_m3: 2702.0,
        thickness_m: 0.00385,
    };

    /// The plate's mesh.
    pub fn mesh_spec(&self) -> RectangleSpec {
        RectangleSpec::flat(0.923, 0.8632, self.elements, self.elements)
            .with_order(self.element)
            .with_edge_layers(self.edge_layers, 0.5 * Self::GLASS.thickness_m)
    }

    /// The mesh in words, e.g. "12 x 12 MITC9, 2 edge layers".
    pub fn mesh_line(&self) -> String {
        let layers = match self.edge_layers {
            0 => String::new(),
            n => format!(", {n} edge layers"),
        };
        format!("{0} x {0} {1}{layers}", self.elements, self.element.name())
    }

    /// Builds the mesh and modal model and synthesizes the measurement from `truth` (E*(ω) in
    /// Pa, ω in rad/s).
    ///
    /// # Errors
    /// [`FitError`] from the mesh, the eigen solve or the FRF set (e.g. zero elements, a
    /// non-positive step).
    pub fn build(
        &self,
        truth: &(dyn Fn(f64) -> Complex64 + Sync),
    ) -> Result<SyntheticCase, FitError> {
        if !(self.step_hz.is_finite()
            && self.step_hz > 0.0
            && self.max_hz.is_finite()
            && self.max_hz >= self.step_hz)
        {
            return Err(crate::error::inconsistent(
                "synthetic case",
                format!(
                    "lines every {} Hz up to {} Hz: both must be positive and finite",
                    self.step_hz, self.max_hz
                ),
            ));
        }
        let clock = Instant::now();
        let mesh = self.mesh_spec().build()?;
        let asm = Assembly::new(&mesh, &Self::GLASS, &[])?;
        let sol = solve_modes(&asm, &ModalParams::lowest(self.modes), &Silent)?;
        let responses = triaxial_grid(&mesh, self.grid.0, self.grid.1);
        let hit = mesh.nodes().iter().min_by(|a, b| {
            let d = |q: &[f64; 3]| (q[0] + 0.346).powi(2) + (q[1] + 0.216).powi(2);
            d(a).total_cmp(&d(b))
        });
        let point = hit.copied().unwrap_or([0.0; 3]);
        let hammer = vec![Channel::new("hammer", point, [0.0, 0.0, -1.0])?];
        let (response_probes, reference_probes) = (
            probes(&mesh, &responses, 1e-9)?,
            probes(&mesh, &hammer, 1e-9)?,
        );
        let model = ModalModel::new(
            &asm,
            &sol,
            &response_probes,
            &reference_probes,
            Self::GLASS.young_pa,
            ResidualTerm::Static,
        )?;
        let model_seconds = clock.elapsed().as_secs_f64();
        let n = (self.max_hz / self.step_hz + 1e-9).floor() as usize;
        let freqs: Vec<f64> = (1..=n).map(|k| self.step_hz * k as f64).collect();
        let clean = model.frf_set(&freqs, truth, self.quantity, responses, hammer)?;
        let measured = add_noise(&clean, self.noise, self.seed);
        Ok(SyntheticCase {
            mesh,
            material: Self::GLASS,
            assembly: asm,
            response_probes,
            reference_probes,
            model,
            clean,
            measured,
            model_seconds,
        })
    }
}

/// Four 5 × 5 cm foam blocks near the corners of a plate's plan (fractions 0.15 and 0.85):
/// 20 kN/m and 20 N·s/m normal, 5 kN/m in plane each. On the paper's plate (8.3 kg) they bounce
/// at about 15 Hz, among its first elastic modes.
pub fn corner_foam_blocks() -> Vec<lamdyn_layered::supports::PointSupport> {
    [[0.15, 0.15], [0.85, 0.15], [0.85, 0.85], [0.15, 0.85]]
        .into_iter()
        .map(|xy_fraction| lamdyn_layered::supports::PointSupport {
            xy_fraction,
            stiffness_n_m: [5e3, 5e3, 2e4],
            damping_n_s_m: [0.0, 0.0, 20.0],
            patch_m: [0.05, 0.05],
        })
        .collect()
}
