//! `lamdyn demo`: the virtual roof → its simulated impact test → the whole chain → the
//! recovered core against the truth ([`crate::chain::demo`]).

use crate::Outcome;
use crate::chain::RunOptions;
use crate::chain::demo::{demo_roof, run_demo};
use crate::cli::DemoArgs;
use crate::progress::Spinner;
use anyhow::{Context, Result};
use lamdyn_testbench::description::Description;
use std::io::Write;

/// Runs `lamdyn demo`.
pub fn run(args: &DemoArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let t = std::time::Instant::now();
    let desc = match &args.description {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read '{}'", p.display()))?;
            Description::parse(&p.display().to_string(), &text)?
        }
        None => demo_roof(),
    };
    let options = RunOptions {
        // The cache beside the job, where `lamdyn run DIR/input/job.toml` looks.
        cache_dir: Some(args.out.join("input").join(".lamdyn-cache")),
        samples: args.samples,
        seed: args.seed,
    };
    let spinner = Spinner::new();
    let (result, _job, simulate_s) = run_demo(&desc, &args.out, &options, &spinner)?;
    let dir = args.out.join("report");
    super::run::write_report(&result, &dir, &spinner)?;
    spinner.finish();
    let mut summary = super::run::summary(&result, &dir);
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
    Ok(Outcome::Done)
}
