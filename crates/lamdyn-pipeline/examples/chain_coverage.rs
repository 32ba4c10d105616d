//! Coverage of the layered route's 95 % bands through the whole chain: the test
//! bench's small laminate (0.6 × 0.5 m, glass 3 / PVB-like 0.76 / glass 3 mm, free, 5 × 5
//! sensors, FRFs to 240 Hz with noise at `snr_db`, a new noise seed each time, truth on a
//! 36 × 36 graded mesh), its faces' modulus, thicknesses and densities drawn from the job's
//! priors (1 % on the faces' modulus, 0.01 mm on each thickness, 0.5 % on each density; faces
//! by one factor, the core by its own), identified with the nominal values in the job. Per
//! (mode, seed) pair it counts whether the truth lies inside the per-mode band and inside the
//! law's band, and prints the median half-widths.
//!
//! Unlike the layered route's coverage tests (reduced model, no EMA, no ladder),
//! every stage runs: simulation, EMA, shell fit, ladder, joint law.
//!
//! `cargo run --release -p lamdyn-pipeline --example chain_coverage -- [seeds = 20] [snr_db = 40]`
//!
//! Environment: `CHAIN_COVERAGE_VERBOSE` prints each mode's band sources, the inputs the law
//! found and what the first and second order leave of each point's error at the true inputs;
//! `CHAIN_COVERAGE_TRUE_INPUTS` gives the job the drawn inputs instead of the nominal ones (what
//! is left is the identification's own error); `CHAIN_COVERAGE_TRUTH_ELEMENTS` sets the
//! truth's mesh (default 36 per side: on 18 × 18 the truth's own discretization error puts η
//! 0.6–2.2 % off at the true inputs, against 0.1–0.6 % on 36 × 36);
//! `CHAIN_COVERAGE_SUPPORTS` puts the laminate on four foam blocks near its corners (4 × 4 cm,
//! 2.5 / 2.5 / 12.5 kN/m and 5 / 5 / 10 N s/m each: by its mass and the springs the 4.75 kg
//! plate bounces at 16 Hz and rocks near 20 Hz, inside the measured band), their stiffness and
//! damping drawn from the job's priors (20 % and 30 %, all blocks by one factor) and told to
//! the job at nominal. `CHAIN_COVERAGE_FIRST_SEED` starts the seeds there (default 1).
//! `CHAIN_COVERAGE_ROOF` runs the demo roof in place of the small
//! laminate (the "same roof": 0.92 × 0.86 m, curved, glass 1.715 / PVB 0.42 / glass
//! 1.715 mm, free, five hammer hits with the demo's noise, a new noise seed each time, truth on
//! the demo's 36 × 36 graded mesh); `snr_db` does not apply to it.

use lamdyn_fit::synthetic::Normal;
use lamdyn_pipeline::demo::{DemoSampling, write_virtual_test};
use lamdyn_pipeline::{Job, OutputDir, RunOptions, Silent, run_job};
use lamdyn_testbench::description::Description;

/// The small laminate's description with `snr_db` noise on the FRFs, seed `seed`.
fn small(snr_db: f64, seed: u64) -> Description {
    // The truth's mesh (CHAIN_COVERAGE_TRUTH_ELEMENTS, default 36 per side).
    let n: usize = std::env::var("CHAIN_COVERAGE_TRUTH_ELEMENTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(36);
    let laminate = include_str!("../../lamdyn-testbench/tests/data/small_laminate.toml").replace(
        "elements = [6, 6]",
        &format!("elements = [{n}, {n}]\nedge_grading = 0.2"),
    );
    let text = format!(
        "{laminate}\n[test]\ngrid = [5, 5]\nhammer_xy_fraction = [0.3, 0.35]\nhammer_direction = \
         [0.0, 0.0, -1.0]\nmax_hz = 240.0\nstep_hz = 0.5\nfrf_snr_db = {snr_db}\nseed = {seed}\n"
    );
    Description::parse("small.toml", &text).expect("the small laminate parses")
}

/// Four foam blocks near the corners (`CHAIN_COVERAGE_SUPPORTS`, module docs), stiffness and
/// damping times `k` and `c`.
fn foam_blocks(k: f64, c: f64) -> lamdyn_testbench::description::SupportsSpec {
    let block = |xy_fraction: [f64; 2]| lamdyn_testbench::description::SupportPoint {
        xy_fraction,
        stiffness_n_m: [2.5e3 * k, 2.5e3 * k, 12.5e3 * k],
        damping_n_s_m: [5.0 * c, 5.0 * c, 10.0 * c],
        patch_m: [0.04, 0.04],
    };
    lamdyn_testbench::description::SupportsSpec {
        points: [[0.15, 0.15], [0.85, 0.15], [0.15, 0.85], [0.85, 0.85]]
            .map(block)
            .to_vec(),
    }
}

/// The demo roof with its hits' noise seed `seed` (`CHAIN_COVERAGE_ROOF`).
fn roof(seed: u64) -> Description {
    let mut d = lamdyn_pipeline::demo::demo_roof();
    d.test.seed = seed;
    d
}

/// The inputs of one seed: the faces' modulus and densities as factors, the thicknesses as
/// changes in m (faces by one draw, the core by its own), and the nominal thicknesses (m).
#[derive(Clone, Copy)]
struct Drawn {
    nominal_face_m: f64,
    nominal_core_m: f64,
    face_modulus: f64,
    face_thickness_m: f64,
    core_thickness_m: f64,
    face_density: f64,
    core_density: f64,
    support_stiffness: f64,
    support_damping: f64,
}

impl Drawn {
    /// ln(θ/θ_nominal) of the input the band names `name`.
    fn delta(&self, name: &str) -> f64 {
        match name {
            "face modulus" => self.face_modulus.ln(),
            "face thickness" => (1.0 + self.face_thickness_m / self.nominal_face_m).ln(),
            "core thickness" => (1.0 + self.core_thickness_m / self.nominal_core_m).ln(),
            "face density" => self.face_density.ln(),
            "core density" => self.core_density.ln(),
            "support stiffness" => self.support_stiffness.ln(),
            "support damping" => self.support_damping.ln(),
            _ => 0.0,
        }
    }
}

/// With `CHAIN_COVERAGE_VERBOSE` set: a mode's band sources, and what its point's first order
/// leaves of the error `err` (ln G', ln η against the truth) at the true inputs.
fn explain(band: &lamdyn_pipeline::band::LayeredBand, freq_hz: f64, err: [f64; 2], drawn: &Drawn) {
    let s: Vec<String> = band
        .sources
        .iter()
        .map(|(n, v)| format!("{n} {:.2}/{:.2} %", 100.0 * v.storage, 100.0 * v.loss))
        .collect();
    println!("  {freq_hz:.0} Hz sources: {}", s.join(", "));
    let shift: [f64; 2] = [0, 1].map(|c| {
        band.inputs
            .iter()
            .map(|i| i.effect.to_array()[c] * drawn.delta(i.input.name()))
            .sum::<f64>()
    });
    // The second order as the joint fit models it: one curvature along the combined shift.
    let effects: Vec<[f64; 2]> = band.inputs.iter().map(|i| i.effect.to_array()).collect();
    let second_order: Vec<[f64; 2]> = band.second_order.iter().map(|s| s.to_array()).collect();
    let sds: Vec<f64> = band.inputs.iter().map(|i| i.rel_sd).collect();
    let kappa = lamdyn_fit::joint::shared_curvature(&effects, &second_order, &sds);
    let second: [f64; 2] = [0, 1].map(|c| {
        let u: f64 = band
            .inputs
            .iter()
            .zip(&second_order)
            .filter(|(_, s)| **s != [0.0, 0.0])
            .map(|(i, _)| i.effect.to_array()[c] * drawn.delta(i.input.name()))
            .sum();
        0.5 * kappa[c] * u * u
    });
    println!(
        "  at the true inputs, first order {:+.2}/{:+.2} % -> left {:+.2}/{:+.2} %; with the \
         second order left {:+.2}/{:+.2} %",
        100.0 * shift[0],
        100.0 * shift[1],
        100.0 * (err[0] + shift[0]),
        100.0 * (err[1] + shift[1]),
        100.0 * (err[0] + shift[0] + second[0]),
        100.0 * (err[1] + shift[1] + second[1])
    );
}

/// Median of `v` (NaN when empty).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let snr_db: f64 = args.get(2).map_or(Ok(40.0), |s| s.parse())?;
    let root = std::env::temp_dir().join(format!("lamdyn-chain-coverage-{}", std::process::id()));
    let (mut pairs, mut in_mode, mut in_law) = (0, [0, 0], [0, 0]);
    let (mut half_mode, mut half_law) = (vec![Vec::new(); 2], vec![Vec::new(); 2]);
    let started = std::time::Instant::now();
    let verbose = std::env::var_os("CHAIN_COVERAGE_VERBOSE").is_some();
    let supported = std::env::var_os("CHAIN_COVERAGE_SUPPORTS").is_some();
    let on_the_roof = std::env::var_os("CHAIN_COVERAGE_ROOF").is_some();
    // CHAIN_COVERAGE_FIRST_SEED: start there (one seed again, verbose, without the others).
    let first: u64 = std::env::var("CHAIN_COVERAGE_FIRST_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    for seed in first..first + seeds {
        let mut nominal = if on_the_roof {
            roof(seed)
        } else {
            small(snr_db, seed)
        };
        if supported {
            nominal.supports = Some(foam_blocks(1.0, 1.0));
        }
        let mut truth = nominal.clone();
        // The drawn inputs: faces' modulus, faces' and core's thickness and density (and the
        // supports' stiffness and damping, drawn after them so that the faces' draws are the
        // free runs').
        let mut draw = Normal::new(1000 + seed);
        let thickness = |face: bool| {
            nominal
                .layers
                .iter()
                .find(|l| l.young_pa.is_some() == face)
                .map_or(f64::NAN, |l| l.thickness_m)
        };
        let mut drawn = Drawn {
            nominal_face_m: thickness(true),
            nominal_core_m: thickness(false),
            face_modulus: 1.0 + 0.01 * draw.sample(),
            face_thickness_m: 1e-5 * draw.sample(),
            core_thickness_m: 1e-5 * draw.sample(),
            face_density: 1.0 + 0.005 * draw.sample(),
            core_density: 1.0 + 0.005 * draw.sample(),
            support_stiffness: 1.0,
            support_damping: 1.0,
        };
        if supported {
            drawn.support_stiffness = (0.2 * draw.sample()).exp();
            drawn.support_damping = (0.3 * draw.sample()).exp();
            truth.supports = Some(foam_blocks(drawn.support_stiffness, drawn.support_damping));
        }
        let Drawn {
            face_modulus: e,
            face_thickness_m: tf,
            core_thickness_m: tc,
            face_density: rf,
            core_density: rc,
            ..
        } = drawn;
        for l in &mut truth.layers {
            if let Some(y) = l.young_pa.as_mut() {
                *y *= e;
                l.thickness_m += tf;
                l.density_kg_m3 *= rf;
            } else {
                l.thickness_m += tc;
                l.density_kg_m3 *= rc;
            }
        }
        let dir = root.join(format!("seed{seed}"));
        let input = OutputDir::prepare(&dir, &[], false)?;
        let sampling = DemoSampling {
            samples: 0,
            seed,
            temperature_k: None,
        };
        let path = write_virtual_test(&truth, &input, sampling, &Silent)?;
        // The job knows the nominal laminate only (the drawn one with
        // CHAIN_COVERAGE_TRUE_INPUTS set: what the identification gives with exact inputs).
        let mut job = Job::read(&path)?;
        let told = if std::env::var_os("CHAIN_COVERAGE_TRUE_INPUTS").is_some() {
            &truth
        } else {
            &nominal
        };
        if supported && told.supports != truth.supports {
            // The job's supports are the truth's as written: put back the nominal ones.
            let nominal_blocks = foam_blocks(1.0, 1.0);
            for (spec, block) in job.inverse.supports.iter_mut().zip(&nominal_blocks.points) {
                spec.stiffness_n_m = block.stiffness_n_m;
                spec.damping_n_s_m = block.damping_n_s_m;
            }
        }
        for (spec, l) in job.stack.layers.iter_mut().zip(&told.layers) {
            spec.thickness_m = l.thickness_m;
            spec.density_kg_m3 = l.density_kg_m3;
            if spec.young_pa.is_some() {
                spec.young_pa = l.young_pa;
            }
        }
        let options = RunOptions {
            cache_dir: Some(dir.join(".lamdyn-cache")),
        };
        let result = run_job(job, &path, &options, &Silent)?;
        let truth_g = result.truth.as_ref().ok_or("the job names its truth")?;
        let law = result.core_law.as_ref().and_then(|l| l.as_ref().ok());
        let mut line = format!(
            "seed {seed:2}: E x{e:.4}, t_f {:+.1} um, t_c {:+.1} um, rho x{rf:.4} / x{rc:.4}{}:",
            tf * 1e6,
            tc * 1e6,
            if supported {
                format!(
                    ", supports k x{:.3} c x{:.3}",
                    drawn.support_stiffness, drawn.support_damping
                )
            } else {
                String::new()
            }
        );
        for p in &result.modal {
            let (Some(g), Some(t)) = (p.layered_g(), truth_g.at(p.freq_hz)) else {
                continue;
            };
            let Some(Ok(band)) = p.layered_band.as_ref() else {
                continue;
            };
            pairs += 1;
            let err = [(g.re / t.re).ln(), ((g.im / g.re) / (t.im / t.re)).ln()];
            if verbose {
                explain(band, p.freq_hz, err, &drawn);
            }
            for c in 0..2 {
                let half_width = band.half_width.to_array()[c];
                in_mode[c] += usize::from(err[c].abs() <= half_width);
                half_mode[c].push(half_width);
            }
            let mut mark = String::new();
            if let Some(l) = law.and_then(|l| l.at(p.freq_hz)) {
                let inside = [
                    (l.storage_ci95[0]..=l.storage_ci95[1]).contains(&t.re),
                    (l.loss_factor_ci95[0]..=l.loss_factor_ci95[1]).contains(&(t.im / t.re)),
                ];
                for c in 0..2 {
                    in_law[c] += usize::from(inside[c]);
                }
                half_law[0].push(0.5 * (l.storage_ci95[1] / l.storage_ci95[0]).ln());
                half_law[1].push(0.5 * (l.loss_factor_ci95[1] / l.loss_factor_ci95[0]).ln());
                mark = format!(
                    " law {:+.2}/{:+.2} % {}{}",
                    100.0 * (l.storage_pa / t.re).ln(),
                    100.0 * (l.loss_factor / (t.im / t.re)).ln(),
                    if inside[0] { "+" } else { "-" },
                    if inside[1] { "+" } else { "-" }
                );
            }
            line += &format!(
                " [{:.0} Hz {:+.2}/{:+.2} % in {:.1}/{:.1} %{mark}]",
                p.freq_hz,
                100.0 * err[0],
                100.0 * err[1],
                100.0 * band.half_width.storage,
                100.0 * band.half_width.loss
            );
        }
        println!("{line}");
        if verbose {
            if let Some(l) = law {
                println!("  {}", l.describe());
                for i in l.inputs() {
                    println!(
                        "  input {}: {:+.4} [{:+.4}, {:+.4}]",
                        i.name, i.value, i.ci95[0], i.ci95[1]
                    );
                }
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
    let pct = |n: usize| 100.0 * n as f64 / pairs.max(1) as f64;
    println!(
        "{pairs} (mode, seed) pairs, {:.0} s on {} threads",
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    for (which, inside, halves) in [("per-mode", in_mode, half_mode), ("law", in_law, half_law)] {
        println!(
            "{which} band holds the truth: G' {:.1} %, eta {:.1} %; median half-width {:.2} % / \
             {:.2} %",
            pct(inside[0]),
            pct(inside[1]),
            100.0 * median(halves[0].clone()),
            100.0 * median(halves[1].clone())
        );
    }
    std::fs::remove_dir_all(&root).ok();
    Ok(())
}
