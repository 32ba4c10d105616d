//! `lamdyn run`: the whole chain on a job file ([`lamdyn_pipeline`]), the report written to a
//! folder, a summary of the core at the modal frequencies printed.

use crate::Outcome;
use crate::cli::RunArgs;
use crate::progress::Spinner;
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result};
use lamdyn_pipeline::Reporter;
use lamdyn_pipeline::job::{Job, base_of};
use lamdyn_pipeline::output::OutputDir;
use lamdyn_pipeline::report::core_table::core_table;
use lamdyn_pipeline::{ChainResult, RunOptions, report, run_job};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Runs `lamdyn run`.
pub fn run(args: &RunArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    lamdyn_pipeline::check_job_path(&args.job)?;
    let job = Job::read(&args.job)?.with_overrides(args.samples, args.seed)?;
    let base = base_of(&args.job);
    let mut inputs: Vec<PathBuf> = job.input_files(&base).into_iter().map(|(_, p)| p).collect();
    inputs.push(args.job.clone());
    let dir = args.out.clone().unwrap_or_else(|| base.join("report"));
    // Checked before any work: an unwritable folder or one holding the inputs fails at once.
    let out_dir = OutputDir::prepare(&dir, &inputs, args.force)?;
    let options = RunOptions {
        cache_dir: if args.no_cache {
            None
        } else {
            Some(
                args.cache
                    .clone()
                    .unwrap_or_else(|| base.join(".lamdyn-cache")),
            )
        },
    };
    let spinner = Spinner::new();
    let result = run_job(job, &args.job, &options, &spinner)?;
    write_report(&result, &out_dir, &spinner)?;
    spinner.finish();
    summary(&result, &dir).write(args.output.format(), out, err)?;
    Ok(outcome(&result))
}

/// Exit 1 when some mode has no core by any inverse (the README's exit-code promise).
pub(crate) fn outcome(result: &ChainResult) -> Outcome {
    if result.modes_without_core().is_empty() {
        Outcome::Done
    } else {
        Outcome::ChecksFailed
    }
}

/// Renders the report and writes the folder atomically.
pub(crate) fn write_report(result: &ChainResult, dir: &OutputDir, spinner: &Spinner) -> Result<()> {
    spinner.stage("stage 'report': figures and tables");
    let files = report::build(result).context("stage 'report' failed")?;
    dir.write(&files).context("stage 'report' failed")
}

/// The summary table: the columns of the core table ([`core_table`]) marked for the summary,
/// at each modal frequency (errors when the truth is known).
pub(crate) fn summary(r: &ChainResult, dir: &Path) -> Report {
    let table = core_table(r);
    // The summary's columns: those marked for it, each with how a terminal shows it.
    let (shown, columns): (Vec<usize>, Vec<Column>) = table
        .columns
        .iter()
        .enumerate()
        .filter(|(_, c)| c.in_summary)
        .filter_map(|(k, c)| {
            let s = c.shown?;
            let column = Column::new(c.key.clone(), c.label.clone(), s.unit, Fmt::Fixed(s.digits));
            Some((k, column.scaled(s.scale)))
        })
        .unzip();
    let frf = r.frf.route();
    let mut rep = Report::new("run", columns);
    rep.input("job", r.job_path.display().to_string());
    rep.input("measurement", r.measured.source.clone());
    rep.input("model", r.model_line.clone());
    if let Some(l) = &r.layered_line {
        rep.input("layered inverse", l.clone());
    }
    if let Some(b) = r.band_widths() {
        rep.input("bands", b.describe());
    }
    rep.input("FRF fit", r.frf.describe());
    rep.input("report", dir.join("report.html").display().to_string());
    if let Some(m) = &r.uncertainty {
        rep.input(
            "uncertainty",
            format!(
                "Monte Carlo, {} samples, seed {}, {} threads",
                m.samples, m.seed, m.threads
            ),
        );
    }
    let times: Vec<String> = r
        .timings
        .iter()
        .map(|t| {
            format!(
                "{} {:.2} s{}",
                t.name,
                t.seconds,
                if t.cached { " (cached)" } else { "" }
            )
        })
        .collect();
    rep.input("stages", times.join(", "));
    for row in &table.rows {
        rep.row(shown.iter().map(|&k| Cell::from(row[k].number())).collect());
    }
    rep.warnings.extend(r.warnings.iter().cloned());
    let failed = r.modes_without_core();
    if !failed.is_empty() {
        let list: Vec<String> = failed.iter().map(|f| format!("{f:.2}")).collect();
        rep.warnings.push(format!(
            "no core at {} Hz: neither the exact nor the layered inverse has a solution and the \
             paper's is beyond its validity{}; check the stack's faces (modulus, thicknesses, \
             densities) against the part; exit code 1",
            list.join(", "),
            r.frf.answer().map_or(String::new(), |a| format!(
                ", and they lie beyond the FRF fit's band ({:.1}-{:.1} Hz, as far as its basis \
                 holds the layered model: raise inverse.layered_modes)",
                a.fit.band_hz[0], a.fit.band_hz[1]
            ))
        ));
    }
    rep.notes.push(
        "G'_paper: paper eqs. 33-45 (eq. 41); G'_exact: Mead-Markus exact sandwich \
         inverse; G'_layer: layered solid model matched to each EMA pole; |phi| > 0.1: \
         beyond the paper model's ~1 % validity."
            .into(),
    );
    if frf.is_some() {
        rep.notes.push(
            "G'_frf: the core's law fitted to the measured FRFs through the layered \
             model (the whole band at once, no poles), corrected for the mesh by the \
             ladder."
                .into(),
        );
    }
    rep
}
