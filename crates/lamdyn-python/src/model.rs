//! The shell model's modes, the fit of the laminate's modulus law, and the inverses from the
//! laminate's E* to the core's G*.

use crate::frf::frf_set;
use crate::{py_err, py_msg, to_json};
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, Shift, solve_modes};
use lamdyn_fem::model::ModelSpec;
use lamdyn_fit::fit::{Covariance, FitResult, FitSettings, LawKind, fit};
use lamdyn_fit::misfit::MisfitSpec;
use lamdyn_frf::FrfSet;
use lamdyn_material::laminate::{
    CoreShearFormula, FaceBending, FaceShear, Kinematics, PaperInverseOptions, StackSpec,
    paper_inverse,
};
use lamdyn_material::sandwich::exact_inverse;
use lamdyn_pipeline::fit_job::{load_fit_job, modal_model};
use lamdyn_pipeline::{AsProgress, Silent};
use num_complex::Complex64;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray3};
use pyo3::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add_function(wrap_pyfunction!(fit_job, m)?)?;
    m.add_function(wrap_pyfunction!(fit_frf, m)?)?;
    m.add_function(wrap_pyfunction!(core_inverse, m)?)?;
    Ok(())
}

/// A model spec from the JSON of a dict laid out as a `lamdyn modes` model file.
fn model_spec(json: &str) -> PyResult<ModelSpec> {
    serde_json::from_str(json).map_err(|e| py_msg(format!("model: {e}")))
}

type ModesOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    String,
);

/// The lowest modes of a shell model: (freqs_hz, nodes[n, 3] in m, shapes[mode, dof] mass
/// normalised with 6 dofs per node, info JSON).
#[pyfunction]
fn modes<'py>(py: Python<'py>, model: &str, base_dir: PathBuf) -> PyResult<ModesOut<'py>> {
    let spec = model_spec(model)?;
    let (mesh, sol) = py.detach(|| -> PyResult<_> {
        let (mesh, springs) = spec.build(&base_dir).map_err(py_err)?;
        let asm = Assembly::new(&mesh, &spec.material, &springs).map_err(py_err)?;
        let mut params = ModalParams::lowest(spec.solver.modes);
        if let Some(f) = spec.solver.shift_hz {
            if !(f.is_finite() && f > 0.0) {
                return Err(py_msg(format!(
                    "model: solver.shift_hz = {f} must be a positive frequency"
                )));
            }
            params = params.with_shift(Shift::BelowHz(f));
        }
        let sol = solve_modes(&asm, &params, &AsProgress(&Silent)).map_err(py_err)?;
        Ok((mesh, sol))
    })?;
    #[derive(Serialize)]
    struct Info {
        rigid: Vec<bool>,
        residual: Vec<f64>,
        elements: usize,
    }
    let info = Info {
        rigid: sol.modes.iter().map(|m| m.rigid).collect(),
        residual: sol.modes.iter().map(|m| m.residual).collect(),
        elements: mesh.elements().len(),
    };
    let nodes: Vec<f64> = mesh.nodes().iter().flat_map(|p| *p).collect();
    let (ndof, nm) = (sol.shapes.nrows(), sol.shapes.ncols());
    let shapes: Vec<f64> = (0..nm)
        .flat_map(|j| sol.shapes.col(j).iter().copied().collect::<Vec<_>>())
        .collect();
    Ok((
        sol.modes
            .iter()
            .map(|m| m.freq_hz)
            .collect::<Vec<_>>()
            .into_pyarray(py),
        nodes.into_pyarray(py).reshape([mesh.nodes().len(), 3])?,
        shapes.into_pyarray(py).reshape([nm, ndof])?,
        to_json(&info)?,
    ))
}

/// A fit's result with E'(f), η(f) and their standard deviations at the measured lines.
#[derive(Serialize)]
struct FitOut<'a> {
    result: &'a FitResult,
    source: &'a str,
    model_line: &'a str,
    notes: &'a [String],
    freqs_hz: &'a [f64],
    e_storage_pa: Vec<f64>,
    e_loss_factor: Vec<f64>,
    e_storage_sd_pa: Vec<Option<f64>>,
    e_loss_factor_sd: Vec<Option<f64>>,
}

fn fit_out(
    result: &FitResult,
    set: &FrfSet,
    source: &str,
    model_line: &str,
    notes: &[String],
) -> PyResult<String> {
    let f = set.freqs_hz();
    let at: Vec<_> = f
        .iter()
        .map(|&f| result.modulus_uncertainty(2.0 * PI * f))
        .collect();
    to_json(&FitOut {
        result,
        source,
        model_line,
        notes,
        freqs_hz: f,
        e_storage_pa: at.iter().map(|a| a.0).collect(),
        e_loss_factor: at.iter().map(|a| a.1).collect(),
        e_storage_sd_pa: at.iter().map(|a| a.2.map(|s| s.0)).collect(),
        e_loss_factor_sd: at.iter().map(|a| a.2.map(|s| s.1)).collect(),
    })
}

/// `lamdyn fit JOB`: the job's measurement, model and settings, fitted; the result as JSON.
#[pyfunction]
fn fit_job(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    py.detach(|| {
        let p = load_fit_job(&path, &Silent).map_err(py_err)?;
        let r = fit(&p.model, &p.measured, &p.settings).map_err(py_err)?;
        fit_out(&r, &p.measured, &p.source, &p.model_line, &p.notes)
    })
}

/// Fit options from Python.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FitOptions {
    law: LawKind,
    misfit: MisfitSpec,
    #[serde(default)]
    covariance: Covariance,
    modes: Option<usize>,
    #[serde(default = "yes")]
    residual: bool,
    tolerance_m: f64,
    prominence: Option<f64>,
    #[serde(default)]
    sensor_mapping: lamdyn_fit::probe::SensorMapping,
}

fn yes() -> bool {
    true
}

/// The fit on FRF arrays and a model dict (the shell model at the channels' positions).
#[pyfunction]
#[pyo3(signature = (freqs_hz, frf, responses, references, quantity, model, base_dir, options))]
#[allow(clippy::too_many_arguments)]
fn fit_frf(
    py: Python<'_>,
    freqs_hz: PyReadonlyArray1<'_, f64>,
    frf: PyReadonlyArray3<'_, Complex64>,
    responses: &str,
    references: &str,
    quantity: &str,
    model: &str,
    base_dir: PathBuf,
    options: &str,
) -> PyResult<String> {
    let set = frf_set(freqs_hz, frf, Some(responses), Some(references), quantity)?;
    let spec = model_spec(model)?;
    let o: FitOptions =
        serde_json::from_str(options).map_err(|e| py_msg(format!("fit options: {e}")))?;
    py.detach(|| {
        let modes = o.modes.unwrap_or(spec.solver.modes);
        let (model, line) = modal_model(
            &spec,
            &base_dir,
            "model",
            "the arrays",
            &set,
            lamdyn_fit::probe::SensorPlacement {
                tolerance_m: o.tolerance_m,
                mapping: o.sensor_mapping,
            },
            modes,
            o.residual,
            &Silent,
        )
        .map_err(py_err)?;
        let mut settings = FitSettings::new(o.law, o.misfit);
        settings.covariance = o.covariance;
        if let Some(p) = o.prominence {
            settings.prominence = p;
        }
        let r = fit(&model, &set, &settings).map_err(py_err)?;
        fit_out(&r, &set, "the arrays", &line, &[])
    })
}

/// The core's G* from the laminate's E* at each frequency, by the paper's inverse (eqs. 33–45
/// with the chosen core formula, faces' shear and bending) and the exact Mead–Markus inverse.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn core_inverse(
    freqs_hz: PyReadonlyArray1<'_, f64>,
    e_storage_pa: PyReadonlyArray1<'_, f64>,
    e_loss_factor: PyReadonlyArray1<'_, f64>,
    stack: &str,
    kinematics: &str,
    core_formula: &str,
    face_shear: &str,
    bending: &str,
) -> PyResult<String> {
    let (f, es, eta) = (
        freqs_hz.as_slice().map_err(py_err)?,
        e_storage_pa.as_slice().map_err(py_err)?,
        e_loss_factor.as_slice().map_err(py_err)?,
    );
    if f.len() != es.len() || f.len() != eta.len() {
        return Err(py_msg(format!(
            "freqs_hz, e_storage_pa and e_loss_factor have {}, {} and {} values",
            f.len(),
            es.len(),
            eta.len()
        )));
    }
    let spec: StackSpec = serde_json::from_str(stack).map_err(|e| py_msg(format!("stack: {e}")))?;
    let stack = spec.to_sandwich().map_err(py_err)?;
    let kin = match kinematics {
        "plate" => Kinematics::Plate {
            poisson: stack.bottom().poisson,
        },
        "beam" => Kinematics::Beam,
        k => return Err(py_msg(format!("kinematics '{k}': give plate or beam"))),
    };
    let formula = match core_formula {
        "eq41" => CoreShearFormula::Eq41,
        "eq43" => CoreShearFormula::Eq43,
        "eq26" => CoreShearFormula::Eq26,
        c => {
            return Err(py_msg(format!(
                "core_formula '{c}': give eq41, eq43 or eq26"
            )));
        }
    };
    let shear = match face_shear {
        "neglect" => FaceShear::Neglected,
        "include" => FaceShear::Included,
        c => return Err(py_msg(format!("face_shear '{c}': give neglect or include"))),
    };
    let bend = match bending {
        "faces" => FaceBending::CoreNeglected,
        "full" => FaceBending::FullStack,
        c => return Err(py_msg(format!("bending '{c}': give faces or full"))),
    };
    let options = PaperInverseOptions::new(formula, shear, bend, kin);
    #[derive(Serialize, Default)]
    struct Out {
        paper_storage_pa: Vec<Option<f64>>,
        paper_loss_factor: Vec<Option<f64>>,
        paper_phi_abs: Vec<Option<f64>>,
        paper_error: Vec<Option<String>>,
        exact_storage_pa: Vec<Option<f64>>,
        exact_loss_factor: Vec<Option<f64>>,
        exact_error: Vec<Option<String>>,
    }
    let mut out = Out::default();
    for k in 0..f.len() {
        let (w, e) = (2.0 * PI * f[k], Complex64::new(es[k], es[k] * eta[k]));
        match paper_inverse(&stack, w, e, &options) {
            Ok(c) => {
                out.paper_storage_pa.push(Some(c.core_shear_pa.re));
                out.paper_loss_factor
                    .push(Some(c.core_shear_pa.im / c.core_shear_pa.re));
                out.paper_phi_abs.push(Some(c.phi.norm()));
                out.paper_error.push(None);
            }
            Err(e) => {
                out.paper_storage_pa.push(None);
                out.paper_loss_factor.push(None);
                out.paper_phi_abs.push(None);
                out.paper_error.push(Some(e.to_string()));
            }
        }
        match exact_inverse(&stack, w, e, kin) {
            Ok(c) => {
                out.exact_storage_pa.push(Some(c.storage_pa()));
                out.exact_loss_factor.push(Some(c.loss_factor()));
                out.exact_error.push(None);
            }
            Err(e) => {
                out.exact_storage_pa.push(None);
                out.exact_loss_factor.push(None);
                out.exact_error.push(Some(e.to_string()));
            }
        }
    }
    to_json(&out)
}
