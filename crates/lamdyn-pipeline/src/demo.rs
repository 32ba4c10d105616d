//! `lamdyn demo`: the virtual roof of the test bench (lamdyn-testbench's built-in `roof`, on
//! softer supports), its simulated impact test (hammer hits as time signals), then the whole
//! chain of `lamdyn run` on those files, and the recovered core compared with the true one at
//! each modal frequency.
//!
//! The results folder holds `input/` (the simulated test: channels, hit files, the true core,
//! the description, and `job.toml`, which `lamdyn run` re-runs) and `report/` (the report).
//! Each is written whole, only when its stage worked.
//!
//! Why the demo roof hangs free (the bench's roof stands on four foam blocks): the chain's FE
//! model is free (the stiffness scales with one modulus, paper eq. 4), as the paper's test
//! was meant to be, and a laminate's core is read from frequency shifts of a fraction of a per
//! cent, so supports matter far more than their size suggests. Measured with this demo: on
//! the bench's 2 kN/m blocks the first elastic mode rises 10 % (17.2 → 18.8 Hz) and a free
//! model can only explain it by a laminate stiffer than bonded glass (no core at all); at
//! 1/25 of that stiffness (80 N/m, dashpots scaled to the same damping ratio) the layered
//! inverse's G' of the first (twisting, corner-driven) mode is still 32 % low and its loss
//! factor 128 % high, the dashpots doubling that mode's tiny damping. Free, it recovers every
//! mode within 1 % (G') and 2 % (η).

use crate::Reporter;
use crate::error::{Context, Result};
use crate::job::Job;
use crate::output::OutputDir;
use crate::{ChainResult, RunOptions, run_job};
use lamdyn_fem::element::{ElementOrder, ShellMaterial};
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fem::model::{MeshSpec, ModelSpec, SolverSpec};
use lamdyn_frf::FrfSet;
use lamdyn_testbench::description::{Bench, Description};
use std::path::PathBuf;

/// The built-in roof hanging free (module docs).
pub fn demo_roof() -> Description {
    let mut d = Description::roof();
    d.supports = None;
    d.mesh.elements = DEMO_TRUTH_ELEMENTS;
    d.mesh.edge_grading = DEMO_TRUTH_GRADING;
    d
}

/// The demo roof's truth mesh: finer than the layered ladder's finest (28 x 28 from the
/// default 12 x 12) and graded towards the free edges, so the recovery tests a converged
/// identification against a truth closer to the continuum than the model (docs/run.md: the
/// 18 x 18 roof of `lamdyn simulate --example roof` is itself 0.18 % stiff in its second mode,
/// which moves that mode's G' by about 12 %).
pub const DEMO_TRUTH_ELEMENTS: [usize; 2] = [36, 36];

/// Edge grading of the demo roof's truth mesh.
pub const DEMO_TRUTH_GRADING: f64 = 0.2;

/// The demo roof at `temperature_k` (K): its core's law (given at 20 °C = 293.15 K) moved there
/// by a WLF shift with `c1` and `c2_k` (K), M*(ω; T) = M*_ref(a_T ω)
/// ([`lamdyn_material::law::TemperatureShifted`]); everything else as [`demo_roof`]. The
/// virtual tests of a master curve.
///
/// # Errors
/// Non-physical WLF constants, or a temperature at or below the WLF pole.
pub fn demo_roof_at(temperature_k: f64, c1: f64, c2_k: f64) -> Result<Description> {
    use lamdyn_material::law::{LawSpec, WlfShift};
    let reference_temperature_k = 293.15;
    WlfShift::new(c1, c2_k, reference_temperature_k)?.shift_factor(temperature_k)?;
    let mut d = demo_roof();
    for l in &mut d.layers {
        if let Some(law) = l.shear_law.take() {
            l.shear_law = Some(LawSpec::Wlf {
                c1,
                c2_k,
                reference_temperature_k,
                temperature_k,
                law: Box::new(law),
            });
        }
    }
    Ok(d)
}

/// Geometric edge layers of the chain's shell model at each free edge.
pub const SHELL_EDGE_LAYERS: usize = 3;

/// The shell model of the chain for a bench description: the same plan and dome, MITC9 at the
/// bench's in-plane division with [`SHELL_EDGE_LAYERS`] geometric layers at the free edges
/// (the outermost half the laminate's thickness wide), the laminate's thickness and mean
/// density, the faces' modulus as E_ref. At the dofs of MITC4 at twice the division, its
/// frequencies in the demo's band are 20–100 times closer to the converged shell's (docs/fem.md);
/// the sensors fall between its nodes and are placed with the element's shape functions.
pub fn shell_model(d: &Description) -> ModelSpec {
    let h: f64 = d.layers.iter().map(|l| l.thickness_m).sum();
    let mass: f64 = d
        .layers
        .iter()
        .map(|l| l.thickness_m * l.density_kg_m3)
        .sum();
    let e_ref = d
        .layers
        .iter()
        .filter_map(|l| l.young_pa)
        .fold(0.0, f64::max);
    ModelSpec {
        mesh: MeshSpec::Rectangle(
            RectangleSpec::flat(
                d.plate.length_m,
                d.plate.width_m,
                d.mesh.elements[0].max(2 * SHELL_EDGE_LAYERS + 1),
                d.mesh.elements[1].max(2 * SHELL_EDGE_LAYERS + 1),
            )
            .with_order(ElementOrder::Quadratic)
            .with_edge_layers(SHELL_EDGE_LAYERS, 0.5 * h)
            .curved(d.plate.radius_x_m, d.plate.radius_y_m),
        ),
        material: ShellMaterial {
            young_pa: e_ref,
            poisson: d.layers[0].poisson,
            density_kg_m3: mass / h,
            thickness_m: h,
        },
        supports: vec![],
        solver: SolverSpec {
            modes: 30,
            shift_hz: None,
        },
    }
}

/// TOML of a value, with infinite radii (a flat plate) left out: TOML cannot say infinity in
/// every reader, and absent radii mean flat.
fn toml_text<T: serde::Serialize>(v: &T) -> Result<String> {
    Ok(toml::to_string(v)?
        .lines()
        .filter(|l| !(l.starts_with("radius_") && l.contains("inf")))
        .collect::<Vec<_>>()
        .join("\n"))
}

/// The job of the demo (paths relative to `input/`).
fn job_text(d: &Description, hits: usize, sampling: DemoSampling) -> Result<String> {
    let DemoSampling {
        samples,
        seed,
        temperature_k,
    } = sampling;
    let mut stack = lamdyn_material::laminate::StackSpec {
        surface_density_kg_m2: None,
        layers: d.layers.clone(),
    };
    // The core's modulus is what the chain recovers: the job does not know it.
    for l in &mut stack.layers {
        if l.young_pa.is_none() {
            l.shear_law = None;
            l.shear_pa = None;
            l.young_law = None;
            l.loss_factor = None;
        }
    }
    let h: f64 = d.layers.iter().map(|l| l.thickness_m).sum();
    let lo = (d.test.max_hz / 8.0).max(d.test.step_hz * 4.0);
    let measurement = if hits > 0 {
        let files: Vec<String> = (1..=hits).map(|k| format!("\"hit{k}.csv\"")).collect();
        format!("time = [{}]", files.join(", "))
    } else {
        "frf = \"frf.csv\"".into()
    };
    let model = toml_text(&shell_model(d))?;
    let model = model
        .replace("[mesh]", "[model.spec.mesh]")
        .replace("[material]", "[model.spec.material]")
        .replace("[solver]", "[model.spec.solver]");
    Ok(format!(
        "# lamdyn run job written by `lamdyn demo`: the virtual roof's impact test.\n\
         # Re-run with `lamdyn run input/job.toml --out report` from the demo folder.\n\
         title = \"lamdyn demo: the core of a virtual laminated roof, recovered from its impact test\"\n\
         truth = \"truth.csv\"\n{temperature}\n\
         [measurement]\nchannels = \"channels.csv\"\n{measurement}\ntolerance_m = {tol:e}\n\n\
         [model]\nmodes = 30\nresidual = true\n{model}\n\n\
         [fit]\nlaw = \"per_mode\"\ncovariance = \"robust_hc3\"\n\n\
         [fit.misfit]\nkind = \"log_rms\"\nband_hz = [{lo}, {hi}]\n\n\
         [inverse]\nkinematics = \"plate\"\n\
         # The layered model: meshes from 12 x 12 refined by 4/3 until the extrapolated frequency\n\
         # error is below the tolerance (the bench's truth is an {ex} x {ey} mesh of its own).\n\
         layered_elements = [12, 12]\ntolerance = 1e-4\n{supports}\n\
         [uncertainty]\nsamples = {samples}\nseed = {seed}\n\n{stack}\n",
        tol = h,
        temperature = temperature_k.map_or(String::new(), |t| format!("temperature_k = {t}\n")),
        ex = d.mesh.elements[0],
        ey = d.mesh.elements[1],
        hi = d.test.max_hz,
        supports = supports_text(d),
        stack = toml_text(&stack)?.replace("[[layers]]", "[[stack.layers]]"),
    ))
}

/// The bench's supports as the job's `[[inverse.supports]]` (the layered model is told what
/// the part rested on; empty when it hung free).
fn supports_text(d: &Description) -> String {
    d.supports.as_ref().map_or(String::new(), |s| {
        s.points
            .iter()
            .map(|p| {
                format!(
                    "\n[[inverse.supports]]\nxy_fraction = {:?}\nstiffness_n_m = \
                     {:?}\ndamping_n_s_m = {:?}\npatch_m = {:?}\n",
                    p.xy_fraction, p.stiffness_n_m, p.damping_n_s_m, p.patch_m
                )
            })
            .collect()
    })
}

/// The input files of the chain from the simulated test.
fn input_files(
    bench: &Bench,
    d: &Description,
    frfs: &FrfSet,
    hits: Option<&lamdyn_testbench::impact::Hits>,
    sampling: DemoSampling,
) -> Result<Vec<(String, Vec<u8>)>> {
    let mut files = vec![
        ("description.toml".to_string(), toml_text(d)?.into_bytes()),
        (
            "channels.csv".to_string(),
            lamdyn_frf::csv::write_channels(frfs).into_bytes(),
        ),
        (
            "truth.csv".to_string(),
            bench.truth_table(frfs.freqs_hz()).into_bytes(),
        ),
    ];
    match hits {
        Some(h) => {
            for (k, r) in h.records.iter().enumerate() {
                let text = lamdyn_frf::csv::write_time(r, &h.responses, &h.reference)?;
                files.push((format!("hit{}.csv", k + 1), text.into_bytes()));
            }
        }
        None => files.push((
            "frf.csv".to_string(),
            lamdyn_frf::csv::write_frf(frfs).into_bytes(),
        )),
    }
    let n_hits = hits.map_or(0, |h| h.records.len());
    files.push((
        "job.toml".to_string(),
        job_text(d, n_hits, sampling)?.into_bytes(),
    ));
    Ok(files)
}

/// What the demo's job says beside the test: the Monte Carlo's samples and seed, and the
/// test's temperature.
#[derive(Debug, Clone, Copy)]
pub struct DemoSampling {
    /// Monte Carlo samples.
    pub samples: usize,
    /// Seed.
    pub seed: u64,
    /// The test's temperature, K (the job's `temperature_k`), if stated.
    pub temperature_k: Option<f64>,
}

impl Default for DemoSampling {
    fn default() -> Self {
        Self {
            samples: 400,
            seed: 1,
            temperature_k: None,
        }
    }
}

/// Simulates the test of `d` into the folder `input` (prepared by the caller), then runs the
/// chain on the job written there; returns the result, the job's path and the simulation's
/// time in s.
pub fn run_demo(
    d: &Description,
    input: &OutputDir,
    sampling: DemoSampling,
    options: &RunOptions,
    spinner: &dyn Reporter,
) -> Result<(ChainResult, PathBuf, f64)> {
    let t = std::time::Instant::now();
    let path = write_virtual_test(d, input, sampling, spinner)?;
    let simulate_s = t.elapsed().as_secs_f64();
    let job = Job::read(&path)?;
    let result = run_job(job, &path, options, spinner)?;
    Ok((result, path, simulate_s))
}

/// Simulates the test of `d` and writes its files into the folder `input` (prepared by the
/// caller): the channels, the hits (or FRFs), the true core, the description and `job.toml`,
/// whose path it returns.
///
/// # Errors
/// The bench's and the writing's errors.
pub fn write_virtual_test(
    d: &Description,
    input: &OutputDir,
    sampling: DemoSampling,
    spinner: &dyn Reporter,
) -> Result<PathBuf> {
    spinner.stage("stage 'virtual test': building the layered roof");
    let bench = d
        .build(&mut |s: &str| spinner.stage(&format!("stage 'virtual test': {s}")))
        .context("stage 'virtual test' failed")?;
    spinner.stage("stage 'virtual test': FRFs and hammer hits");
    let frfs = bench.frfs().context("stage 'virtual test' failed")?;
    let hits = bench.hit_records().context("stage 'virtual test' failed")?;
    let files = input_files(&bench, d, &frfs, hits.as_ref(), sampling)?;
    input.write(&files)?;
    Ok(input.path().join("job.toml"))
}
