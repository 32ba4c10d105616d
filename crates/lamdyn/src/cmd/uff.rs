//! `lamdyn uff info|convert`: what a UFF file holds, and conversions (lamdyn-uff does the work).

use crate::Outcome;
use crate::cli::{UffCommand, UffConvertArgs, UffInfoArgs, UffTarget};
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result, anyhow};
use lamdyn_pipeline::output::{OutputDir, check_file_target, write_file};
use lamdyn_uff::{Encoding, ReadOptions};
use std::io::Write;
use std::path::Path;

/// Runs `lamdyn uff ...`.
pub fn run(cmd: &UffCommand, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    match cmd {
        UffCommand::Info(a) => info(a, out, err),
        UffCommand::Convert(a) => convert(a, err),
    }
}

fn info(args: &UffInfoArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let f = std::fs::File::open(&args.file)
        .with_context(|| format!("cannot open '{}'", args.file.display()))?;
    let entries = lamdyn_uff::list(std::io::BufReader::with_capacity(1 << 20, f))
        .map_err(|e| anyhow!("'{}' {e}", args.file.display()))?;
    let mut report = Report::new(
        "uff info",
        vec![
            Column::new("dataset", "dataset", "", Fmt::Fixed(0)),
            Column::new("line", "line", "", Fmt::Fixed(0)),
            Column::new("offset_bytes", "offset", "B", Fmt::Fixed(0)),
            Column::new("binary", "binary", "", Fmt::Fixed(0)),
            Column::new("supported", "read", "", Fmt::Fixed(0)),
            Column::new("summary", "summary", "", Fmt::Fixed(0)),
        ],
    );
    report.input("file", format!("'{}'", args.file.display()));
    report.input("datasets", entries.len().to_string());
    let yes = |b: bool| Cell::from(if b { "yes" } else { "no" });
    for e in &entries {
        report.row(vec![
            f64::from(e.number).into(),
            (e.line as f64).into(),
            (e.offset as f64).into(),
            yes(e.binary),
            yes(e.supported),
            e.summary.clone().into(),
        ]);
    }
    let skipped = entries.iter().filter(|e| !e.supported).count();
    if skipped > 0 {
        report.notes.push(format!(
            "{skipped} dataset(s) of kinds lamdyn does not read are skipped when the file is read \
             (and copied as they are by convert --to ascii|binary)."
        ));
    }
    report.write(args.output.format(), out, err)?;
    Ok(Outcome::Done)
}

/// Notices of a read, with the skipped datasets summarised by number.
fn report_notices(input: &Path, notices: &[String], err: &mut dyn Write) -> Result<()> {
    let mut skipped: std::collections::BTreeMap<String, usize> = Default::default();
    for n in notices {
        let number = n
            .split_once("dataset ")
            .and_then(|(_, r)| r.strip_suffix(" skipped (not supported)"));
        match number {
            Some(number) => *skipped.entry(number.to_string()).or_default() += 1,
            None => writeln!(err, "lamdyn: notice: '{}' {n}", input.display())?,
        }
    }
    if !skipped.is_empty() {
        let list: Vec<String> = skipped.iter().map(|(k, v)| format!("{k} x{v}")).collect();
        writeln!(
            err,
            "lamdyn: notice: '{}': datasets lamdyn does not read were skipped: {}",
            input.display(),
            list.join(", ")
        )?;
    }
    Ok(())
}

fn convert(args: &UffConvertArgs, err: &mut dyn Write) -> Result<Outcome> {
    let options = ReadOptions {
        lenient_counts: args.lenient,
    };
    // The output is checked before the input is read: a wrong target fails at once.
    let inputs = [args.input.clone()];
    let out_dir = if args.to == UffTarget::Csv {
        Some(OutputDir::prepare(&args.output, &inputs, args.force)?)
    } else {
        check_file_target(&args.output, &inputs)?;
        None
    };
    let write_atomically = |path: &Path, bytes: &[u8]| write_file(path, bytes, &inputs);
    if matches!(args.to, UffTarget::Ascii | UffTarget::Binary) {
        // Datasets 58 change encoding; every other dataset is copied as it is.
        let encoding = match args.to {
            UffTarget::Ascii => Encoding::Ascii,
            _ => Encoding::Binary {
                little_endian: !args.big_endian,
            },
        };
        let input = std::fs::File::open(&args.input)
            .with_context(|| format!("cannot open '{}'", args.input.display()))?;
        let (bytes, notices) = lamdyn_uff::reencode(
            std::io::BufReader::with_capacity(1 << 20, input),
            encoding,
            options,
        )
        .map_err(|e| anyhow!("cannot convert '{}': {e}", args.input.display()))?;
        report_notices(&args.input, &notices, err)?;
        write_atomically(&args.output, &bytes)?;
        return Ok(Outcome::Done);
    }
    let file = lamdyn_uff::read_path(&args.input, options).map_err(|e| anyhow!(e))?;
    report_notices(&args.input, &file.notices, err)?;
    let context = |e: lamdyn_uff::UffError| anyhow!("'{}': {e}", args.input.display());
    match args.to {
        UffTarget::Json => write_atomically(&args.output, &serde_json::to_vec_pretty(&file)?)?,
        UffTarget::Csv => {
            let set = lamdyn_uff::frf::to_frf_set(&file).map_err(context)?;
            let dir = out_dir.ok_or_else(|| anyhow!("no output folder"))?;
            dir.write(&[
                (
                    "channels.csv",
                    lamdyn_frf::csv::write_channels(&set).into_bytes(),
                ),
                ("frf.csv", lamdyn_frf::csv::write_frf(&set).into_bytes()),
            ])?;
        }
        UffTarget::Vtu => {
            let text = lamdyn_uff::vtu::to_vtu(&file).map_err(context)?;
            write_atomically(&args.output, text.as_bytes())?;
        }
        UffTarget::Ascii | UffTarget::Binary => {}
    }
    Ok(Outcome::Done)
}
