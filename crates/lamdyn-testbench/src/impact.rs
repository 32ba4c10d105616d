//! A simulated impact test on the layered model: a grid of triaxial accelerometers on the top
//! surface, a hammer at a fixed point hitting along the inward normal, accelerance FRFs over a
//! band from the reduced model with the core's law, and noise.
//!
//! **Sensors.** Each sensor sits on the top-surface node nearest its point; a point farther than
//! `tolerance_m` from every top node is an error (off the surface). Its axes are the surface's
//! local frame there: t₁ = the global x axis projected on the tangent plane, t₂ = n × t₁, and
//! the outward normal n; channels are named `S<row>.<col>:t1|t2|n`.
//!
//! **FRFs.** Accelerance A = −ω² dᵀ u with u the receptance to a unit force −n at the hammer
//! node (from [`ReducedModel::response`]), for each sensor axis d, at every line of the band
//! (0 Hz excluded: a free model has no static response). The core scale is
//! s(ω) = G*(ω)/G_a for the law's modulus G*(ω) and the assembled core shear modulus G_a.
//!
//! **Noise.** Complex Gaussian noise `snr_db` below each curve's RMS (seeded, reproducible).

use crate::error::BenchError;
use crate::frf::ReducedModel;
use crate::mesh::HexMesh;
use lamdyn_frf::{Channel, FrfSet, Quantity};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Settings of [`simulate`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactTest {
    /// Sensor points (x, y, z), m.
    pub sensors: Vec<[f64; 3]>,
    /// Names of the sensors (one per point).
    pub sensor_names: Vec<String>,
    /// Hammer point, m.
    pub hammer: [f64; 3],
    /// Largest distance from a point to the nearest top-surface node, m.
    pub tolerance_m: f64,
    /// Lines: `step_hz`, 2 `step_hz`, … up to `max_hz`.
    pub step_hz: f64,
    /// Highest line, Hz.
    pub max_hz: f64,
    /// Noise below each curve's RMS, dB (`None`: no noise).
    pub snr_db: Option<f64>,
    /// Seed of the noise.
    pub seed: u64,
}

impl ImpactTest {
    /// A `rows` × `cols` sensor grid over the top surface of `mesh` (its nodes nearest the
    /// points at (i + ½)/rows of the plan extent), hammer at the top node nearest
    /// `hammer_xy_fraction` of the extent, 0.25–80 Hz at 0.25 Hz, no noise.
    pub fn grid(mesh: &HexMesh, rows: usize, cols: usize, hammer_xy_fraction: [f64; 2]) -> Self {
        let (lo, hi) = plan_extent(mesh);
        let at = |fx: f64, fy: f64| {
            let (x, y) = (lo[0] + fx * (hi[0] - lo[0]), lo[1] + fy * (hi[1] - lo[1]));
            mesh.top
                .iter()
                .map(|(n, _)| mesh.nodes[*n])
                .min_by(|a, b| {
                    let d = |p: &[f64; 3]| (p[0] - x).powi(2) + (p[1] - y).powi(2);
                    d(a).total_cmp(&d(b))
                })
                .unwrap_or([x, y, 0.0])
        };
        let mut sensors = Vec::new();
        let mut names = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                sensors.push(at(
                    (c as f64 + 0.5) / cols as f64,
                    (r as f64 + 0.5) / rows as f64,
                ));
                names.push(format!("S{}.{}", r + 1, c + 1));
            }
        }
        Self {
            sensors,
            sensor_names: names,
            hammer: at(hammer_xy_fraction[0], hammer_xy_fraction[1]),
            tolerance_m: 1e-6,
            step_hz: 0.25,
            max_hz: 80.0,
            snr_db: None,
            seed: 1,
        }
    }
}

fn plan_extent(mesh: &HexMesh) -> ([f64; 2], [f64; 2]) {
    mesh.top.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), (n, _)| {
            let p = mesh.nodes[*n];
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

/// The top node nearest `p` and the surface normal there, or an error naming `what`.
fn on_surface(
    mesh: &HexMesh,
    p: [f64; 3],
    tol: f64,
    what: &str,
) -> Result<(usize, [f64; 3]), BenchError> {
    let d2 = |n: usize| {
        (0..3)
            .map(|c| (mesh.nodes[n][c] - p[c]).powi(2))
            .sum::<f64>()
    };
    let best = mesh
        .top
        .iter()
        .min_by(|a, b| d2(a.0).total_cmp(&d2(b.0)))
        .ok_or_else(|| BenchError::Invalid("the mesh has no top surface".into()))?;
    let d = d2(best.0).sqrt();
    if d.is_nan() || d > tol {
        return Err(BenchError::Invalid(format!(
            "{what} at ({:.4}, {:.4}, {:.4}) m is {d:.3e} m from the top surface's nearest node (tolerance {tol:.1e} m)",
            p[0], p[1], p[2]
        )));
    }
    Ok(*best)
}

/// The local frame (t₁, t₂, n) at a surface point with normal n (module docs).
pub fn surface_frame(n: [f64; 3]) -> [[f64; 3]; 3] {
    // t1 = x − (x·n) n, normalised.
    let t1 = [1.0 - n[0] * n[0], -n[0] * n[1], -n[0] * n[2]];
    let l = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
    let t1 = [t1[0] / l, t1[1] / l, t1[2] / l];
    let t2 = [
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ];
    [t1, t2, n]
}

/// Simulates the test (module docs): an accelerance FRF set, sensors × 3 axes by one hammer.
///
/// # Errors
/// [`BenchError::Invalid`] for sensors or the hammer off the surface, names that do not match
/// the sensors, or a band without lines.
pub fn simulate(
    mesh: &HexMesh,
    model: &ReducedModel,
    core_scale: &dyn Fn(f64) -> Complex64,
    test: &ImpactTest,
) -> Result<FrfSet, BenchError> {
    if test.sensor_names.len() != test.sensors.len() {
        return Err(BenchError::Invalid(format!(
            "{} sensor names for {} sensors",
            test.sensor_names.len(),
            test.sensors.len()
        )));
    }
    if !(test.step_hz > 0.0 && test.max_hz >= test.step_hz) {
        return Err(BenchError::Invalid(format!(
            "band: step {} Hz up to {} Hz has no line",
            test.step_hz, test.max_hz
        )));
    }
    let (hammer, hn) = on_surface(mesh, test.hammer, test.tolerance_m, "the hammer")?;
    let mut load = vec![0.0; 3 * mesh.nodes.len()];
    for c in 0..3 {
        load[3 * hammer + c] = -hn[c];
    }
    let mut responses = Vec::new();
    let mut axes: Vec<(usize, [f64; 3])> = Vec::new();
    for (p, name) in test.sensors.iter().zip(&test.sensor_names) {
        let (node, n) = on_surface(mesh, *p, test.tolerance_m, &format!("sensor {name}"))?;
        for (frame, tag) in surface_frame(n).iter().zip(["t1", "t2", "n"]) {
            responses.push(
                Channel::new(format!("{name}:{tag}"), mesh.nodes[node], *frame)
                    .map_err(|e| BenchError::Invalid(e.to_string()))?,
            );
            axes.push((node, *frame));
        }
    }
    let reference = Channel::new("hammer", mesh.nodes[hammer], [-hn[0], -hn[1], -hn[2]])
        .map_err(|e| BenchError::Invalid(e.to_string()))?;
    let lines = (test.max_hz / test.step_hz + 1e-9).floor() as usize;
    let freqs: Vec<f64> = (1..=lines).map(|k| k as f64 * test.step_hz).collect();
    let dofs: Vec<usize> = axes
        .iter()
        .flat_map(|(node, _)| (0..3).map(move |c| 3 * node + c))
        .collect();
    let load_r = model.project_load(&load);
    let mut curves = vec![Vec::with_capacity(freqs.len()); axes.len()];
    for &f in &freqs {
        let w = 2.0 * PI * f;
        let u = model.response(&load_r, w, core_scale(w), &dofs);
        for (a, (_, d)) in axes.iter().enumerate() {
            let r: Complex64 = (0..3).map(|c| u[3 * a + c] * d[c]).sum();
            curves[a].push(-w * w * r);
        }
    }
    if let Some(snr) = test.snr_db {
        let mut rng = Normal(test.seed.max(1));
        for c in &mut curves {
            let rms = (c.iter().map(|v| v.norm_sqr()).sum::<f64>() / c.len() as f64).sqrt();
            let sd = rms * 10f64.powf(-snr / 20.0) / 2f64.sqrt();
            for v in c.iter_mut() {
                *v += Complex64::new(sd * rng.sample(), sd * rng.sample());
            }
        }
    }
    FrfSet::new(
        freqs,
        responses,
        vec![reference],
        Quantity::Accelerance,
        curves.into_iter().flatten().collect(),
    )
    .map_err(|e| BenchError::Invalid(e.to_string()))
}

/// Seeded standard normal numbers (xorshift64*, Box–Muller).
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn sample(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
}
