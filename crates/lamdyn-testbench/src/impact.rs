//! A simulated impact test on the layered model: a grid of triaxial accelerometers on the top
//! surface, a hammer at a fixed point hitting along the inward normal, accelerance FRFs over a
//! band from the reduced model with the core's law, and noise.
//!
//! **Sensors.** Each sensor sits on the top-surface node nearest its point; a point farther than
//! `tolerance_m` from every top node is an error (off the surface). Its axes are the surface's
//! local frame there: t₁ = the global x axis projected on the tangent plane, t₂ = n × t₁, and
//! the outward normal n; channels are named `S<row>.<col>:t1|t2|n`.
//!
//! **FRFs.** Accelerance A = −ω² dᵀ u with u the receptance to a unit force at the hammer
//! node (along −n, or along a given direction such as the paper's global −Z, "1Z−") (from
//! [`ReducedModel::response`]), for each sensor axis d, at every line of the band (0 Hz excluded: a
//! free model has no static response). The core scale is s(ω) = G*(ω)/G_a for the law's modulus
//! G*(ω) and the assembled core shear modulus G_a.
//!
//! **Noise.** Complex Gaussian noise `snr_db` below each curve's RMS (seeded, reproducible).
//!
//! **Time signals.** [`simulate_hits`] turns the same model into sampled force and acceleration
//! signals of several hits (half-sine pulses of varying amplitude, noise on force and
//! responses), for the H1 estimator of lamdyn-ema.
//!
//! **Supports.** [`Support`] springs on the bottom surface make the part's rigid-body modes
//! resonances of a few Hz, as in a real test on soft supports.

use crate::error::BenchError;
use lamdyn_frf::csv::TimeRecord;
use lamdyn_frf::{Channel, FrfSet, Quantity};
use lamdyn_layered::mesh::HexMesh;
use lamdyn_layered::reduced::ReducedModel;
use num_complex::Complex64;
use rayon::prelude::*;
use realfft::RealFftPlanner;
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
    /// Direction of the hammer's force (unit vector; `None`: along the inward normal −n).
    pub hammer_direction: Option<[f64; 3]>,
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
            hammer_direction: None,
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
            "{what} at ({:.4}, {:.4}, {:.4}) m is {d:.3e} m from the top surface's nearest node \
             (tolerance {tol:.1e} m)",
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

/// Where a test measures: the channels, their node dofs and axes, and the hammer's load.
struct Layout {
    responses: Vec<Channel>,
    reference: Channel,
    /// Sensor axis per response channel.
    axes: Vec<[f64; 3]>,
    /// x, y, z dofs of each response channel's node.
    dofs: Vec<usize>,
    /// Unit force −n at the hammer node.
    load: Vec<f64>,
}

fn layout(mesh: &HexMesh, test: &ImpactTest) -> Result<Layout, BenchError> {
    if test.sensor_names.len() != test.sensors.len() {
        return Err(BenchError::Invalid(format!(
            "{} sensor names for {} sensors",
            test.sensor_names.len(),
            test.sensors.len()
        )));
    }
    let (hammer, dir) = hammer(mesh, test)?;
    let load = point_load(mesh, hammer, dir);
    let (mut responses, mut axes, mut dofs) = (Vec::new(), Vec::new(), Vec::new());
    for (p, name) in test.sensors.iter().zip(&test.sensor_names) {
        let (node, n) = on_surface(mesh, *p, test.tolerance_m, &format!("sensor {name}"))?;
        for (frame, tag) in surface_frame(n).iter().zip(["t1", "t2", "n"]) {
            responses.push(
                Channel::new(format!("{name}:{tag}"), mesh.nodes[node], *frame)
                    .map_err(|e| BenchError::Invalid(e.to_string()))?,
            );
            axes.push(*frame);
            dofs.extend((0..3).map(|c| 3 * node + c));
        }
    }
    let reference = Channel::new("hammer", mesh.nodes[hammer], dir)
        .map_err(|e| BenchError::Invalid(e.to_string()))?;
    Ok(Layout {
        responses,
        reference,
        axes,
        dofs,
        load,
    })
}

/// Checks that the sensors and the hammer of `test` lie on the surface of `mesh` and that the
/// names match the sensors.
///
/// # Errors
/// [`BenchError::Invalid`] naming the sensor or the hammer.
pub fn check_layout(mesh: &HexMesh, test: &ImpactTest) -> Result<(), BenchError> {
    layout(mesh, test).map(|_| ())
}

/// The load vector of the hammer of `test`: a unit force at its node along its direction (for
/// the reduced basis's residual vectors).
///
/// # Errors
/// [`BenchError::Invalid`] for a hammer off the surface or pointing out of it.
pub fn hammer_load(mesh: &HexMesh, test: &ImpactTest) -> Result<Vec<f64>, BenchError> {
    let (hammer, dir) = hammer(mesh, test)?;
    Ok(point_load(mesh, hammer, dir))
}

/// A unit force along `dir` at `node`, as a load vector over the mesh's dofs.
fn point_load(mesh: &HexMesh, node: usize, dir: [f64; 3]) -> Vec<f64> {
    let mut load = vec![0.0; 3 * mesh.nodes.len()];
    load[3 * node..3 * node + 3].copy_from_slice(&dir);
    load
}

/// The hammer's top node and unit force direction.
fn hammer(mesh: &HexMesh, test: &ImpactTest) -> Result<(usize, [f64; 3]), BenchError> {
    let (node, n) = on_surface(mesh, test.hammer, test.tolerance_m, "the hammer")?;
    Ok((node, hammer_direction(test, n)?))
}

/// The unit force direction of the hammer: `test.hammer_direction` normalised, or −n; a
/// direction pointing out of the surface (d·n ≥ 0) is an error.
fn hammer_direction(test: &ImpactTest, n: [f64; 3]) -> Result<[f64; 3], BenchError> {
    let Some(d) = test.hammer_direction else {
        return Ok([-n[0], -n[1], -n[2]]);
    };
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let dot = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / l;
    if !(l.is_finite() && l > 0.0) || dot.is_nan() || dot >= 0.0 {
        return Err(BenchError::Invalid(format!(
            "hammer direction {d:?}: must be a non-zero vector pushing into the surface (outward \
             normal {n:.3?})"
        )));
    }
    Ok([d[0] / l, d[1] / l, d[2] / l])
}

/// A triaxial FRF set of [`simulate`] (sensor frames, channels `NAME:t1|t2|n` in threes)
/// expressed in the global frame, as the paper's 429 FRFs: the responses of sensor k become
/// channels `k+X`, `k+Y`, `k+Z` (a_global = Fᵀ a_local, F the sensor frame's rows), and a
/// hammer along a global axis becomes `m±X|Y|Z`, m the label of the sensor at the hammer
/// point (or sensors + 1). The node-and-axis names are what UFF 58 can hold.
///
/// # Errors
/// [`BenchError::Invalid`] for a response count that is not a multiple of 3 or a hammer not
/// along a global axis.
pub fn to_global_frame(set: &FrfSet) -> Result<FrfSet, BenchError> {
    let resp = set.responses();
    if resp.len() % 3 != 0 || set.references().len() != 1 {
        return Err(BenchError::Invalid(format!(
            "{} responses and {} references: expected triaxial sensors and one hammer",
            resp.len(),
            set.references().len()
        )));
    }
    let hammer = &set.references()[0];
    let axis = (0..3)
        .find(|&c| (hammer.direction[c].abs() - 1.0).abs() < 1e-9)
        .ok_or_else(|| {
            BenchError::Invalid(format!(
                "the hammer's direction {:.4?} is not along a global axis: UFF 58 needs one (set \
                 test.hammer_direction = [0, 0, -1])",
                hammer.direction
            ))
        })?;
    let sensors = resp.len() / 3;
    let label = (0..sensors)
        .find(|&k| resp[3 * k].point_m == hammer.point_m)
        .unwrap_or(sensors)
        + 1;
    let sign = if hammer.direction[axis] < 0.0 {
        '-'
    } else {
        '+'
    };
    let names = ['X', 'Y', 'Z'];
    let reference = Channel::new(
        format!("{label}{sign}{}", names[axis]),
        hammer.point_m,
        hammer.direction,
    )
    .map_err(|e| BenchError::Invalid(e.to_string()))?;
    let mut channels = Vec::with_capacity(resp.len());
    let mut data = Vec::with_capacity(resp.len() * set.freqs_hz().len());
    for k in 0..sensors {
        let frame: [[f64; 3]; 3] = std::array::from_fn(|i| resp[3 * k + i].direction);
        for (g, name) in names.iter().enumerate() {
            let mut e = [0.0; 3];
            e[g] = 1.0;
            channels.push(
                Channel::new(format!("{}+{name}", k + 1), resp[3 * k].point_m, e)
                    .map_err(|e| BenchError::Invalid(e.to_string()))?,
            );
            let curves: [&[Complex64]; 3] = std::array::from_fn(|i| set.curve(3 * k + i, 0));
            data.extend((0..set.freqs_hz().len()).map(|l| {
                (0..3)
                    .map(|i| frame[i][g] * curves[i][l])
                    .sum::<Complex64>()
            }));
        }
    }
    FrfSet::new(
        set.freqs_hz().to_vec(),
        channels,
        vec![reference],
        set.quantity(),
        data,
    )
    .map_err(|e| BenchError::Invalid(e.to_string()))
}

/// Noise-free accelerance per response channel at `freqs_hz` (all > 0), lines in parallel.
fn accelerance(
    model: &ReducedModel,
    lay: &Layout,
    core_scale: &(dyn Fn(f64) -> Complex64 + Sync),
    freqs_hz: &[f64],
) -> Vec<Vec<Complex64>> {
    let load_r = model.project_load(&lay.load);
    let per_line: Vec<Vec<Complex64>> = freqs_hz
        .par_iter()
        .map(|&f| {
            let w = 2.0 * PI * f;
            let u = model.response(&load_r, w, core_scale(w), &lay.dofs);
            lay.axes
                .iter()
                .enumerate()
                .map(|(a, d)| -w * w * (0..3).map(|c| u[3 * a + c] * d[c]).sum::<Complex64>())
                .collect()
        })
        .collect();
    (0..lay.axes.len())
        .map(|a| per_line.iter().map(|l| l[a]).collect())
        .collect()
}

/// Simulates the test (module docs): an accelerance FRF set, sensors × 3 axes by one hammer.
///
/// # Errors
/// [`BenchError::Invalid`] for sensors or the hammer off the surface, names that do not match
/// the sensors, or a band without lines.
pub fn simulate(
    mesh: &HexMesh,
    model: &ReducedModel,
    core_scale: &(dyn Fn(f64) -> Complex64 + Sync),
    test: &ImpactTest,
) -> Result<FrfSet, BenchError> {
    if !(test.step_hz > 0.0 && test.max_hz >= test.step_hz) {
        return Err(BenchError::Invalid(format!(
            "band: step {} Hz up to {} Hz has no line",
            test.step_hz, test.max_hz
        )));
    }
    let lay = layout(mesh, test)?;
    let lines = (test.max_hz / test.step_hz + 1e-9).floor() as usize;
    let freqs: Vec<f64> = (1..=lines).map(|k| k as f64 * test.step_hz).collect();
    let mut curves = accelerance(model, &lay, core_scale, &freqs);
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
        lay.responses,
        vec![lay.reference],
        Quantity::Accelerance,
        curves.into_iter().flatten().collect(),
    )
    .map_err(|e| BenchError::Invalid(e.to_string()))
}

/// Settings of [`simulate_hits`]: the hammer hits as time signals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitSettings {
    /// Number of hits.
    pub count: usize,
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Record length after the pretrigger start, s (1/record = the FRF line step).
    pub record_s: f64,
    /// Time before the hit kept in each record, s.
    pub pretrigger_s: f64,
    /// Duration of the half-sine force pulse, s (hammer tip: ~1 ms hard to ~5 ms soft).
    pub pulse_s: f64,
    /// Peak force of the pulse, N.
    pub peak_force_n: f64,
    /// Hit-to-hit spread of the peak force, fraction (uniform ±).
    pub force_spread: f64,
    /// Force noise below the peak force, dB (`None`: none).
    pub force_snr_db: Option<f64>,
    /// Response noise below each channel's RMS over the record, dB (`None`: none).
    pub response_snr_db: Option<f64>,
    /// Seed of the spreads and noises.
    pub seed: u64,
}

impl Default for HitSettings {
    /// Five hits at 512 Hz, 4 s records (0.25 Hz lines), 10 ms pretrigger, a 3 ms pulse of
    /// 200 N ± 20 %, noise 60 dB below the peak force and 40 dB below each response's RMS.
    fn default() -> Self {
        Self {
            count: 5,
            rate_hz: 512.0,
            record_s: 4.0,
            pretrigger_s: 0.01,
            pulse_s: 0.003,
            peak_force_n: 200.0,
            force_spread: 0.2,
            force_snr_db: Some(60.0),
            response_snr_db: Some(40.0),
            seed: 1,
        }
    }
}

impl HitSettings {
    fn validate(&self) -> Result<(), BenchError> {
        let bad =
            |f: &str, v: f64, why: &str| Err(BenchError::Invalid(format!("hits.{f} = {v}: {why}")));
        if self.count == 0 {
            return bad("count", 0.0, "at least one hit");
        }
        for (f, v) in [
            ("rate_hz", self.rate_hz),
            ("record_s", self.record_s),
            ("pulse_s", self.pulse_s),
            ("peak_force_n", self.peak_force_n),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(f, v, "must be positive");
            }
        }
        if !(self.pretrigger_s.is_finite() && self.pretrigger_s >= 0.0) {
            return bad("pretrigger_s", self.pretrigger_s, "must be non-negative");
        }
        if !(self.force_spread.is_finite() && (0.0..1.0).contains(&self.force_spread)) {
            return bad("force_spread", self.force_spread, "must lie in [0, 1)");
        }
        if self.record_s * self.rate_hz < 16.0 {
            return bad(
                "record_s",
                self.record_s,
                "fewer than 16 samples per record",
            );
        }
        Ok(())
    }
}

/// The hits of [`simulate_hits`]: one [`TimeRecord`] per hit, over the channels of the FRFs.
#[derive(Debug, Clone, PartialEq)]
pub struct Hits {
    /// Response channels, in the order of each record's responses.
    pub responses: Vec<Channel>,
    /// The hammer.
    pub reference: Channel,
    /// The hits.
    pub records: Vec<TimeRecord>,
}

/// Fourier transform of a half-sine pulse of unit peak and duration τ at ω (rad/s), starting at
/// t = 0: with a = π/τ, P(ω) = ∫₀^τ sin(at) e^{−iωt} dt = a (1 + e^{−iωτ}) / (a² − ω²), and −iτ/2
/// at ω = a.
pub fn half_sine_spectrum(tau_s: f64, omega: f64) -> Complex64 {
    let a = PI / tau_s;
    let d = a * a - omega * omega;
    if d.abs() < 1e-9 * a * a {
        return Complex64::new(0.0, -0.5 * tau_s);
    }
    a * (Complex64::new(1.0, 0.0) + Complex64::from_polar(1.0, -omega * tau_s)) / d
}

/// Gain of the acquisition's anti-alias filter: a zero-phase Gaussian low-pass times the
/// [¼, ½, ¼] smoothing of three samples, G(f) = exp(−(f/f_g)²/2) cos²(π f/f_s) with
/// f_g = 0.15 f_s (digital filters run forward and backward). It acts on force and responses
/// alike, so it cancels in every FRF. It keeps the sampled pulse compact and positive (both
/// kernels are positive: no ringing that a double-hit check would take for a second hit) and
/// makes the spectrum vanish smoothly at Nyquist, so the signals have no slowly decaying
/// Nyquist tails for the record and the force window to cut.
fn anti_alias(rate_hz: f64, f_hz: f64) -> Complex64 {
    let x = f_hz / (0.15 * rate_hz);
    let c = (PI * f_hz / rate_hz).cos();
    Complex64::new((-0.5 * x * x).exp() * c * c, 0.0)
}

/// Simulates hammer hits as sampled time signals (force, N; accelerations, m/s²) at the
/// channels of [`simulate`].
///
/// **Synthesis.** Each record is one period of a periodic signal of length N = 2 × the samples
/// kept, so the previous period's response has decayed (over a full record) before the hit: with
/// lines f_k = k f_s/N, force F_k = A P(2πf_k) e^{−2πi f_k t₀} G(f_k) ([`half_sine_spectrum`], hit
/// at t₀, anti-alias gain G) and response Y_k = H(f_k) F_k with the model's accelerance H; the
/// samples are the inverse real FFT of F_k/T and Y_k/T (T = N/f_s, the Fourier series of the
/// periodic signal). At 0 Hz the force keeps its mean (a pulse on a zero baseline) and the
/// accelerance takes Re H(f_1), the first line's (the mass line of a free part, ≈ 0 on supports:
/// a constant error there shifts only the mean); the Nyquist line is dropped.
/// The hit starts at `pretrigger_s` + 10 ms plus a random fraction of a sample; the amplitude A
/// varies by `force_spread`; noise is added in the time domain.
///
/// # Errors
/// [`BenchError::Invalid`] for non-physical settings or sensors off the surface.
pub fn simulate_hits(
    mesh: &HexMesh,
    model: &ReducedModel,
    core_scale: &(dyn Fn(f64) -> Complex64 + Sync),
    test: &ImpactTest,
    hits: &HitSettings,
) -> Result<Hits, BenchError> {
    hits.validate()?;
    let lay = layout(mesh, test)?;
    let fs = hits.rate_hz;
    let lead = hits.pretrigger_s + 0.01;
    let kept = ((lead + hits.record_s) * fs).ceil() as usize + (0.05 * fs).ceil() as usize;
    let n = 2 * kept;
    let period = n as f64 / fs;
    let freqs: Vec<f64> = (1..n / 2).map(|k| k as f64 / period).collect();
    let h = accelerance(model, &lay, core_scale, &freqs);
    let mut planner = RealFftPlanner::<f64>::new();
    let inverse = planner.plan_fft_inverse(n);
    let to_time = |spectrum: &mut Vec<Complex64>| -> Vec<f64> {
        let mut out = vec![0.0; n];
        // The plan's lengths match by construction; an error here would be a bug.
        inverse
            .process(spectrum, &mut out)
            .expect("inverse FFT of a spectrum of length n/2 + 1");
        out.truncate(kept);
        out
    };
    let mut rng = Normal(hits.seed.max(1));
    let mut records = Vec::with_capacity(hits.count);
    for _ in 0..hits.count {
        let amp = hits.peak_force_n * (1.0 + hits.force_spread * (2.0 * rng.uniform() - 1.0));
        let t0 = lead + rng.uniform() / fs;
        let force_line = |f: f64| {
            let w = 2.0 * PI * f;
            amp * half_sine_spectrum(hits.pulse_s, w)
                * Complex64::from_polar(1.0, -w * t0)
                * anti_alias(fs, f)
                / period
        };
        let mut fk = vec![Complex64::new(0.0, 0.0); n / 2 + 1];
        fk[0] = force_line(0.0);
        for (k, f) in freqs.iter().enumerate() {
            fk[k + 1] = force_line(*f);
        }
        let mut force = to_time(&mut fk.clone());
        let mut responses: Vec<Vec<f64>> = h
            .iter()
            .map(|hc| {
                let mut yk = vec![Complex64::new(0.0, 0.0); n / 2 + 1];
                yk[0] = hc[0].re * fk[0];
                for k in 0..freqs.len() {
                    yk[k + 1] = hc[k] * fk[k + 1];
                }
                to_time(&mut yk)
            })
            .collect();
        if let Some(db) = hits.force_snr_db {
            let sd = amp * 10f64.powf(-db / 20.0);
            force.iter_mut().for_each(|v| *v += sd * rng.sample());
        }
        if let Some(db) = hits.response_snr_db {
            for r in &mut responses {
                let rms = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
                let sd = rms * 10f64.powf(-db / 20.0);
                r.iter_mut().for_each(|v| *v += sd * rng.sample());
            }
        }
        records.push(TimeRecord {
            rate_hz: fs,
            quantity: Quantity::Accelerance,
            force,
            responses,
        });
    }
    Ok(Hits {
        responses: lay.responses,
        reference: lay.reference,
        records,
    })
}

/// An elastic support of the tested part ([`lamdyn_layered::supports`]): its springs give the
/// part's rigid-body modes on the supports, the support resonances of a real test.
pub use lamdyn_layered::supports::PointSupport as Support;

/// The springs and dashpots of `supports` on the bottom surface of `mesh`, through the shape
/// functions of the face holding each point ([`lamdyn_layered::supports::support_terms`]).
///
/// # Errors
/// [`BenchError::Invalid`] naming the support for a position outside the plan or a negative
/// or non-finite stiffness.
pub fn support_terms(
    mesh: &HexMesh,
    supports: &[Support],
) -> Result<Vec<lamdyn_layered::supports::SupportTerm>, BenchError> {
    lamdyn_layered::supports::support_terms(mesh, supports)
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
