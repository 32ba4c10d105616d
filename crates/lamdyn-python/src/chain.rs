//! The whole chain on a job file (`lamdyn run`), and the demo's virtual tests written as jobs.

use crate::{py_err, py_msg, to_json};
use lamdyn_pipeline::demo::{DemoSampling, demo_roof, demo_roof_at, write_virtual_test};
use lamdyn_pipeline::job::{Job, MAX_SAMPLES, base_of};
use lamdyn_pipeline::output::{OptionNames, OutputDir};
use lamdyn_pipeline::{ChainResult, RunOptions, Silent, report, run_job};
use num_complex::Complex64;
use pyo3::prelude::*;
use serde::Serialize;
use std::path::PathBuf;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(write_demo_job, m)?)?;
    Ok(())
}

/// One modal frequency of the run's core table (what `core_modal.csv` holds, in SI).
#[derive(Serialize)]
struct ModalRow {
    f_hz: f64,
    e_storage_pa: Option<f64>,
    e_loss_factor: Option<f64>,
    phi_abs: Option<f64>,
    g_paper_storage_pa: Option<f64>,
    g_paper_loss_factor: Option<f64>,
    g_exact_storage_pa: Option<f64>,
    g_exact_loss_factor: Option<f64>,
    g_layered_storage_pa: Option<f64>,
    g_layered_loss_factor: Option<f64>,
    g_true_storage_pa: Option<f64>,
    g_true_loss_factor: Option<f64>,
}

#[derive(Serialize)]
struct RunOut<'a> {
    title: &'a str,
    job: String,
    temperature_k: Option<f64>,
    modal: Vec<ModalRow>,
    ema_modes: Vec<(f64, f64)>,
    modes_without_core: Vec<f64>,
    warnings: &'a [String],
    timings: Vec<(&'static str, f64, bool)>,
    report: Option<String>,
}

fn split(g: Option<Complex64>) -> (Option<f64>, Option<f64>) {
    (g.map(|g| g.re), g.map(|g| g.im / g.re))
}

fn run_out(r: &ChainResult, report_dir: Option<String>) -> PyResult<String> {
    let modal = r
        .modal
        .iter()
        .map(|p| {
            let (gp, ep) = split(p.paper_g());
            let (ge, ee) = split(p.exact_g());
            let (gl, el) = split(p.layered_g());
            let (gt, et) = split(r.truth.as_ref().and_then(|t| t.at(p.freq_hz)));
            ModalRow {
                f_hz: p.freq_hz,
                e_storage_pa: p.e_storage_pa(),
                e_loss_factor: p.e_loss_factor(),
                phi_abs: p.phi(),
                g_paper_storage_pa: gp,
                g_paper_loss_factor: ep,
                g_exact_storage_pa: ge,
                g_exact_loss_factor: ee,
                g_layered_storage_pa: gl,
                g_layered_loss_factor: el,
                g_true_storage_pa: gt,
                g_true_loss_factor: et,
            }
        })
        .collect();
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
