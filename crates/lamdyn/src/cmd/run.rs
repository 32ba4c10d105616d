//! `lamdyn run`: the whole chain on a job file ([`lamdyn_pipeline`]), the report written to a
//! folder, a summary of the core at the modal frequencies printed.

use crate::Outcome;
use crate::cli::RunArgs;
use crate::progress::Spinner;
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result};
use lamdyn_fem::eigen::Progress;
use lamdyn_pipeline::job::{Job, base_of};
use lamdyn_pipeline::output::OutputDir;
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

/// The summary table: the core at each modal frequency (errors when the truth is known).
pub(crate) fn summary(r: &ChainResult, dir: &Path) -> Report {
    let truth = r.truth.is_some();
    let mut columns = vec![
        Column::new("f_hz", "f", "Hz", Fmt::Fixed(3)),
        Column::new("e_storage_pa", "E'", "GPa", Fmt::Fixed(3)).scaled(1e9),
        Column::new("phi_abs", "|phi|", "", Fmt::Fixed(4)),
        Column::new("g_paper_storage_pa", "G'_paper", "MPa", Fmt::Fixed(3)).scaled(1e6),
        Column::new("g_paper_loss_factor", "eta_paper", "", Fmt::Fixed(3)),
        Column::new("g_exact_storage_pa", "G'_exact", "MPa", Fmt::Fixed(3)).scaled(1e6),
        Column::new("g_exact_loss_factor", "eta_exact", "", Fmt::Fixed(3)),
        Column::new("g_layered_storage_pa", "G'_layer", "MPa", Fmt::Fixed(3)).scaled(1e6),
        Column::new("g_layered_loss_factor", "eta_layer", "", Fmt::Fixed(3)),
    ];
    if truth {
        columns.extend([
            Column::new("g_true_storage_pa", "G'_true", "MPa", Fmt::Fixed(3)).scaled(1e6),
            Column::new("g_true_loss_factor", "eta_true", "", Fmt::Fixed(3)),
            Column::new("err_g_paper", "err G'_p", "%", Fmt::Fixed(1)).scaled(0.01),
            Column::new("err_eta_paper", "err eta_p", "%", Fmt::Fixed(1)).scaled(0.01),
            Column::new("err_g_exact", "err G'_x", "%", Fmt::Fixed(1)).scaled(0.01),
            Column::new("err_eta_exact", "err eta_x", "%", Fmt::Fixed(1)).scaled(0.01),
            Column::new("err_g_layered", "err G'_l", "%", Fmt::Fixed(1)).scaled(0.01),
            Column::new("err_eta_layered", "err eta_l", "%", Fmt::Fixed(1)).scaled(0.01),
        ]);
    }
    let frf = r.frf.route();
    if frf.is_some() {
        columns.extend([
            Column::new("g_frf_storage_pa", "G'_frf", "MPa", Fmt::Fixed(3)).scaled(1e6),
            Column::new("g_frf_loss_factor", "eta_frf", "", Fmt::Fixed(3)),
        ]);
        if truth {
            columns.extend([
                Column::new("err_g_frf", "err G'_f", "%", Fmt::Fixed(1)).scaled(0.01),
                Column::new("err_eta_frf", "err eta_f", "%", Fmt::Fixed(1)).scaled(0.01),
            ]);
        }
    }
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
    let split = |g: Option<num_complex::Complex64>| -> [Cell; 2] {
        match g {
            Some(g) => [g.re.into(), (g.im / g.re).into()],
            None => [Cell::Empty, Cell::Empty],
        }
    };
    let err = |a: Option<f64>, b: Option<f64>| -> Cell {
        match (a, b) {
            (Some(a), Some(b)) => (a / b - 1.0).into(),
            _ => Cell::Empty,
        }
    };
    for p in &r.modal {
        let (gp, ge, gl) = (p.paper_g(), p.exact_g(), p.layered_g());
        let mut row: Vec<Cell> = vec![p.freq_hz.into(), p.e_storage_pa().into(), p.phi().into()];
        row.extend(split(gp));
        row.extend(split(ge));
        row.extend(split(gl));
        if let Some(t) = &r.truth {
            let g = t.at(p.freq_hz);
            row.extend(split(g));
            let re = |x: Option<num_complex::Complex64>| x.map(|x| x.re);
            let eta = |x: Option<num_complex::Complex64>| x.map(|x| x.im / x.re);
            row.push(err(re(gp), re(g)));
            row.push(err(eta(gp), eta(g)));
            row.push(err(re(ge), re(g)));
            row.push(err(eta(ge), eta(g)));
            row.push(err(re(gl), re(g)));
            row.push(err(eta(gl), eta(g)));
        }
        if let Some(route) = frf {
            let gf = route.modulus(p.freq_hz);
            row.extend(split(Some(gf)));
            if let Some(t) = &r.truth {
                let g = t.at(p.freq_hz);
                row.push(err(Some(gf.re), g.map(|g| g.re)));
                row.push(err(Some(gf.im / gf.re), g.map(|g| g.im / g.re)));
            }
        }
        rep.row(row);
    }
    rep.warnings.extend(r.warnings.iter().cloned());
    let failed = r.modes_without_core();
    if !failed.is_empty() {
        let list: Vec<String> = failed.iter().map(|f| format!("{f:.2}")).collect();
        rep.warnings.push(format!(
            "no core at {} Hz: neither the exact nor the layered inverse has a solution and the paper's is beyond its validity{}; check the stack's faces (modulus, thicknesses, densities) against the part; exit code 1",
            list.join(", "),
            r.frf.answer().map_or(String::new(), |a| format!(
                ", and they lie beyond the FRF fit's band ({:.1}-{:.1} Hz, as far as its basis holds the layered model: raise inverse.layered_modes)",
                a.fit.band_hz[0], a.fit.band_hz[1]
            ))
        ));
    }
    rep.notes.push("G'_paper: paper eqs. 33-45 (eq. 41); G'_exact: Mead-Markus exact sandwich inverse; G'_layer: layered solid model matched to each EMA pole; |phi| > 0.1: beyond the paper model's ~1 % validity.".into());
    if frf.is_some() {
        rep.notes.push("G'_frf: the core's law fitted to the measured FRFs through the layered model (the whole band at once, no poles), corrected for the mesh by the ladder.".into());
    }
    rep
}
