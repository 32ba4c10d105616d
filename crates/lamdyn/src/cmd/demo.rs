//! `lamdyn demo`: the virtual roof → its simulated impact test → the whole chain → the
//! recovered core against the truth ([`lamdyn_pipeline::demo`]).

use crate::Outcome;
use crate::cli::DemoArgs;
use crate::progress::Spinner;
use anyhow::{Result, bail};
use lamdyn_pipeline::RunOptions;
use lamdyn_pipeline::demo::{DemoSampling, demo_roof, run_demo};
use lamdyn_pipeline::job::MAX_SAMPLES;
use lamdyn_pipeline::output::OutputDir;
use lamdyn_testbench::description::Description;
use std::io::Write;

/// Runs `lamdyn demo`.
pub fn run(args: &DemoArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let t = std::time::Instant::now();
    let defaults = DemoSampling::default();
    let sampling = DemoSampling {
        samples: args.samples.unwrap_or(defaults.samples),
        seed: args.seed.unwrap_or(defaults.seed),
        temperature_k: None,
    };
    if sampling.samples > MAX_SAMPLES {
        bail!("--samples: {} is more than {MAX_SAMPLES}", sampling.samples);
    }
    // Both folders are checked before the simulation: a wrong --out fails at once.
    let inputs: Vec<std::path::PathBuf> = args.description.iter().cloned().collect();
    let input_dir = OutputDir::prepare(&args.out.join("input"), &inputs, args.force)?;
    let report_dir = OutputDir::prepare(&args.out.join("report"), &inputs, args.force)?;
    let desc = match &args.description {
        Some(p) => lamdyn_pipeline::io::read_toml::<Description>(p)?,
        None => demo_roof(),
    };
    let options = RunOptions {
        // The cache beside the job, where `lamdyn run DIR/input/job.toml` looks.
        cache_dir: Some(args.out.join("input").join(".lamdyn-cache")),
    };
    let spinner = Spinner::new();
    let (result, _job, simulate_s) = run_demo(&desc, &input_dir, sampling, &options, &spinner)?;
    super::run::write_report(&result, &report_dir, &spinner)?;
    spinner.finish();
    let dir = report_dir.path();
    let mut summary = super::run::summary(&result, dir);
    summary.input(
        "virtual test",
        format!(
            "{} ({:.1} s to simulate)",
            if args.description.is_some() {
                "the given description"
            } else {
                "built-in roof hanging free"
            },
            simulate_s
        ),
    );
    summary.input("total", format!("{:.1} s", t.elapsed().as_secs_f64()));
    summary.write(args.output.format(), out, err)?;
    writeln!(
        err,
        "lamdyn: report written to '{}'",
        dir.join("report.html").display()
    )?;
    Ok(super::run::outcome(&result))
}
