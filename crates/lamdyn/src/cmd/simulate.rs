//! `lamdyn simulate`: a virtual impact test on the layered model of lamdyn-testbench, from a TOML
//! description (or the built-in `roof`), written as FRFs (UFF 58 in the global frame, CSV in the
//! sensor frames), hammer-hit time signals (CSV, one file per hit, for `lamdyn ema --time`) and
//! the core's true law at every line.

use crate::Outcome;
use crate::cli::SimulateArgs;
use crate::progress::Spinner;
use crate::table::{Column, Fmt, Report};
use anyhow::{Context, Result, anyhow, bail};
use lamdyn_frf::FrfSet;
use lamdyn_pipeline::Reporter;
use lamdyn_pipeline::output::OutputDir;
use lamdyn_testbench::description::{Bench, Description, ROOF_TOML};
use lamdyn_testbench::impact::{Hits, to_global_frame};
use std::io::Write;
use std::time::Instant;

/// The description and where it came from.
fn description(args: &SimulateArgs) -> Result<(Description, String, String)> {
    match (&args.description, args.example.as_deref()) {
        (Some(p), None) => {
            let text = lamdyn_pipeline::io::read_text(p)?;
            let d: Description = lamdyn_pipeline::io::parse_toml(p, &text)?;
            Ok((d, p.display().to_string(), text))
        }
        (None, Some("roof")) => Ok((
            Description::roof(),
            "built-in example 'roof'".into(),
            ROOF_TOML.into(),
        )),
        (None, Some(other)) => bail!("unknown example '{other}': the built-in example is 'roof'"),
        _ => bail!("give a description file or --example roof"),
    }
}

/// Runs `lamdyn simulate`.
pub fn run(args: &SimulateArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let (desc, source, text) = description(args)?;
    if args.print_description {
        out.write_all(text.as_bytes())?;
        return Ok(Outcome::Done);
    }
    let inputs: Vec<std::path::PathBuf> = args.description.iter().cloned().collect();
    let out_dir = args
        .out
        .as_ref()
        .map(|d| OutputDir::prepare(d, &inputs, args.force))
        .transpose()?;
    let spinner = Spinner::new();
    let mut times: Vec<(&str, f64)> = Vec::new();
    let t0 = Instant::now();
    let bench = desc
        .build(&mut |stage: &str| spinner.stage(stage))
        .context("cannot build the virtual test")?;
    times.push(("build (mesh, assembly, basis)", t0.elapsed().as_secs_f64()));
    spinner.stage("FRFs");
    let t = Instant::now();
    let frfs = bench.frfs().context("cannot simulate the FRFs")?;
    times.push(("FRFs", t.elapsed().as_secs_f64()));
    let hits = if args.no_hits {
        None
    } else {
        spinner.stage("hammer hits");
        let t = Instant::now();
        let h = bench.hit_records().context("cannot simulate the hits")?;
        times.push(("hits", t.elapsed().as_secs_f64()));
        h
    };
    spinner.finish();
    let mut report = build_report(&bench, &frfs, hits.as_ref(), &source, &times);
    if let Some(dir) = &out_dir {
        let t = Instant::now();
        let files = output_files(&bench, &frfs, hits.as_ref(), &text, &report)?;
        dir.write(&files)?;
        report.notes.push(format!(
            "{} files written to '{}' in {:.2} s",
            files.len(),
            dir.path().display(),
            t.elapsed().as_secs_f64()
        ));
    }
    report.write(args.output.format(), out, err)?;
    Ok(Outcome::Done)
}

fn build_report(
    bench: &Bench,
    frfs: &FrfSet,
    hits: Option<&Hits>,
    source: &str,
    times: &[(&str, f64)],
) -> Report {
    let mut report = Report::new(
        "simulate",
        vec![
            Column::new("stage", "stage", "", Fmt::Fixed(0)),
            Column::new("seconds", "time", "s", Fmt::Fixed(2)),
        ],
    );
    report.input("description", source);
    report.input(
        "mesh",
        format!(
            "{} C3D20 elements, {} nodes, {} dofs; basis of {} vectors",
            bench.mesh.elements.len(),
            bench.mesh.nodes.len(),
            bench.dofs(),
            bench.model.size()
        ),
    );
    report.input(
        "core",
        format!(
            "layers {:?} ({} law): {}; assembled at {:.4e} Pa",
            bench.core_layers,
            if bench.core_law_is_shear {
                "shear"
            } else {
                "Young's"
            },
            bench.core_law.describe(),
            bench.assembled_modulus_pa
        ),
    );
    let f = frfs.freqs_hz();
    report.input(
        "FRFs",
        format!(
            "{} responses x {} reference, {} lines {}-{} Hz (accelerance)",
            frfs.responses().len(),
            frfs.references().len(),
            f.len(),
            f[0],
            f[f.len() - 1]
        ),
    );
    if let Some(h) = hits {
        let r = &h.records[0];
        report.input(
            "hits",
            format!(
                "{} hits of {} samples at {} Hz",
                h.records.len(),
                r.force.len(),
                r.rate_hz
            ),
        );
    }
    report.input("threads", rayon::current_num_threads().to_string());
    for (stage, s) in times {
        report.row(vec![
            crate::table::Cell::Text(stage.to_string()),
            (*s).into(),
        ]);
    }
    report
}

/// The files of the results folder.
fn output_files(
    bench: &Bench,
    frfs: &FrfSet,
    hits: Option<&Hits>,
    description: &str,
    report: &Report,
) -> Result<Vec<(String, Vec<u8>)>> {
    let mut files: Vec<(String, Vec<u8>)> = vec![
        ("description.toml".into(), description.as_bytes().to_vec()),
        (
            "channels.csv".into(),
            lamdyn_frf::csv::write_channels(frfs).into_bytes(),
        ),
        (
            "frf.csv".into(),
            lamdyn_frf::csv::write_frf(frfs).into_bytes(),
        ),
        (
            "truth.csv".into(),
            bench.truth_table(frfs.freqs_hz()).into_bytes(),
        ),
    ];
    match to_global_frame(frfs) {
        Ok(global) => {
            let datasets = lamdyn_uff::frf::from_frf_set(&global)
                .map_err(|e| anyhow!("cannot write the FRFs as UFF: {e}"))?;
            let bytes = lamdyn_uff::write(&datasets, lamdyn_uff::Encoding::Ascii)
                .map_err(|e| anyhow!("cannot write the FRFs as UFF: {e}"))?;
            files.push(("frf_global.uff".into(), bytes));
        }
        Err(e) => files.push((
            "frf_global.uff.skipped.txt".into(),
            format!("no UFF file: {e}\n").into_bytes(),
        )),
    }
    if let Some(h) = hits {
        for (k, r) in h.records.iter().enumerate() {
            let text = lamdyn_frf::csv::write_time(r, &h.responses, &h.reference)?;
            files.push((format!("hit{}.csv", k + 1), text.into_bytes()));
        }
    }
    let mut json = Vec::new();
    report.write(crate::table::Format::Json, &mut json, &mut std::io::sink())?;
    files.push(("summary.json".into(), json));
    Ok(files)
}
