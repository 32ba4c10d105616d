//! The whole chain on a job file (`lamdyn run`), and the demo's virtual tests written as jobs.

use crate::{py_err, py_msg, to_json};
use lamdyn_pipeline::demo::{DemoSampling, demo_roof, demo_roof_at, write_virtual_test};
use lamdyn_pipeline::job::{Job, MAX_SAMPLES, base_of};
use lamdyn_pipeline::output::{OptionNames, OutputDir};
use lamdyn_pipeline::report::core_table::{CoreValue, Groups, core_table_with};
use lamdyn_pipeline::{ChainResult, RunOptions, Silent, report, run_job};
use pyo3::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(write_demo_job, m)?)?;
    m.add_function(wrap_pyfunction!(core_columns, m)?)?;
    Ok(())
}

/// One cell of the core table as JSON: a number (null where none) or a text.
#[derive(Serialize)]
#[serde(untagged)]
enum CellOut {
    Number(Option<f64>),
    Text(Option<String>),
}

/// The core table of `r` with every group's columns ([`Groups::ALL`]), as JSON key → one
/// value per modal frequency: the columns Python's `ModalTable` has.
fn modal_columns(r: &ChainResult) -> BTreeMap<String, Vec<CellOut>> {
    let table = core_table_with(r, Groups::ALL);
    table
        .columns
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let values = table
                .rows
                .iter()
                .map(|row| match &row[k] {
                    CoreValue::Number(v) => CellOut::Number(*v),
                    CoreValue::Text(t) => CellOut::Text(t.clone()),
                })
                .collect();
            (c.key.clone(), values)
        })
        .collect()
}

/// One column of Python's `ModalTable` ([`core_columns`]).
#[derive(Serialize)]
struct ColumnOut<'a> {
    key: &'a str,
    unit: &'a str,
    about: &'a str,
    text: bool,
}

/// The columns of the run's core table with every group, as JSON: what Python's `ModalTable`
/// is made of (key, SI unit, meaning, and whether it holds text).
#[pyfunction]
fn core_columns() -> PyResult<String> {
    let columns = lamdyn_pipeline::report::core_table::core_columns(Groups::ALL);
    let out: Vec<ColumnOut<'_>> = columns
        .iter()
        .map(|c| ColumnOut {
            key: &c.key,
            unit: c.unit,
            about: &c.about,
            text: c.shown.is_none(),
        })
        .collect();
    to_json(&out)
}

#[derive(Serialize)]
struct RunOut<'a> {
    title: &'a str,
    job: String,
    temperature_k: Option<f64>,
    modal: BTreeMap<String, Vec<CellOut>>,
    ema_modes: Vec<(f64, f64)>,
    modes_without_core: Vec<f64>,
    warnings: &'a [String],
    timings: Vec<(&'static str, f64, bool)>,
    report: Option<String>,
}

fn run_out(r: &ChainResult, report_dir: Option<String>) -> PyResult<String> {
    let modal = modal_columns(r);
    to_json(&RunOut {
        title: &r.job.title,
        job: r.job_path.display().to_string(),
        temperature_k: r.job.temperature_k,
        modal,
        ema_modes: r
            .ema
            .modes
            .iter()
            .map(|m| (m.freq_hz, m.damping_ratio))
            .collect(),
        modes_without_core: r.modes_without_core(),
        warnings: &r.warnings,
        timings: r
            .timings
            .iter()
            .map(|t| (t.name, t.seconds, t.cached))
            .collect(),
        report: report_dir,
    })
}

/// `lamdyn run JOB`: the chain on a job file, the report written to `out` when given (the same
/// folder rules as the CLI: only lamdyn's own files are replaced unless `force`), the core
/// table as JSON. `cache` is the cache folder (None: no cache).
#[pyfunction]
#[pyo3(signature = (job, out, cache, samples, seed, force))]
fn run(
    py: Python<'_>,
    job: PathBuf,
    out: Option<PathBuf>,
    cache: Option<PathBuf>,
    samples: Option<usize>,
    seed: Option<u64>,
    force: bool,
) -> PyResult<String> {
    py.detach(|| {
        lamdyn_pipeline::check_job_path(&job).map_err(py_err)?;
        let j = Job::read(&job)
            .and_then(|j| j.with_overrides(samples, seed))
            .map_err(py_err)?;
        let base = base_of(&job);
        let mut inputs: Vec<PathBuf> = j.input_files(&base).into_iter().map(|(_, p)| p).collect();
        inputs.push(job.clone());
        let dir = out
            .as_ref()
            .map(|d| OutputDir::prepare_named(d, &inputs, force, OptionNames::PYTHON))
            .transpose()
            .map_err(py_err)?;
        let options = RunOptions { cache_dir: cache };
        let result = run_job(j, &job, &options, &Silent).map_err(py_err)?;
        if let Some(d) = &dir {
            let files = report::build(&result).map_err(py_err)?;
            d.write(&files).map_err(py_err)?;
        }
        run_out(&result, dir.map(|d| d.path().display().to_string()))
    })
}

/// Simulates the demo roof's impact test (at `temperature_k` with a WLF-shifted core when
/// given) and writes it as a job folder `out`; returns the job file's path.
#[pyfunction]
#[pyo3(signature = (out, temperature_k, c1, c2_k, samples, seed, force))]
#[allow(clippy::too_many_arguments)]
fn write_demo_job(
    py: Python<'_>,
    out: PathBuf,
    temperature_k: Option<f64>,
    c1: f64,
    c2_k: f64,
    samples: usize,
    seed: u64,
    force: bool,
) -> PyResult<String> {
    if samples > MAX_SAMPLES {
        return Err(py_msg(format!(
            "samples: {samples} is more than {MAX_SAMPLES}"
        )));
    }
    py.detach(|| {
        let d = match temperature_k {
            Some(t) => demo_roof_at(t, c1, c2_k).map_err(py_err)?,
            None => demo_roof(),
        };
        let dir =
            OutputDir::prepare_named(&out, &[], force, OptionNames::PYTHON).map_err(py_err)?;
        let sampling = DemoSampling {
            samples,
            seed,
            temperature_k,
        };
        let path = write_virtual_test(&d, &dir, sampling, &Silent).map_err(py_err)?;
        Ok(path.display().to_string())
    })
}
