//! The master curve over temperature ([`lamdyn_fit::master`]).

use crate::{py_err, py_msg, to_json};
use lamdyn_fit::master::{CorePoint, MasterSettings, ShiftKind, fit_master_curve};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use serde::Serialize;

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(master_curve, m)?)?;
    Ok(())
}

/// Fits one fractional Zener law and a WLF or Arrhenius shift to cores identified at several
/// temperatures; the result, its curve at `curve_freqs_hz` (reduced) and a_T at
/// `curve_temperatures_k`, as JSON.
#[pyfunction]
#[pyo3(signature = (temperature_k, freq_hz, storage_pa, loss_factor, reference_temperature_k, shift, curve_freqs_hz, curve_temperatures_k))]
#[allow(clippy::too_many_arguments)]
fn master_curve(
    py: Python<'_>,
    temperature_k: PyReadonlyArray1<'_, f64>,
    freq_hz: PyReadonlyArray1<'_, f64>,
    storage_pa: PyReadonlyArray1<'_, f64>,
    loss_factor: PyReadonlyArray1<'_, f64>,
    reference_temperature_k: f64,
    shift: &str,
    curve_freqs_hz: PyReadonlyArray1<'_, f64>,
    curve_temperatures_k: PyReadonlyArray1<'_, f64>,
) -> PyResult<String> {
    let cols = [
        temperature_k.as_slice().map_err(py_err)?,
        freq_hz.as_slice().map_err(py_err)?,
        storage_pa.as_slice().map_err(py_err)?,
        loss_factor.as_slice().map_err(py_err)?,
    ];
    if cols.iter().any(|c| c.len() != cols[0].len()) {
        return Err(py_msg(format!(
            "temperature_k, freq_hz, storage_pa and loss_factor have {}, {}, {} and {} values",
            cols[0].len(),
            cols[1].len(),
            cols[2].len(),
            cols[3].len()
        )));
    }
    let points: Vec<CorePoint> = (0..cols[0].len())
        .map(|k| CorePoint {
            temperature_k: cols[0][k],
            freq_hz: cols[1][k],
            storage_pa: cols[2][k],
            loss_factor: cols[3][k],
        })
        .collect();
    let shift = match shift {
        "wlf" => ShiftKind::Wlf,
        "arrhenius" => ShiftKind::Arrhenius,
        s => return Err(py_msg(format!("shift '{s}': give wlf or arrhenius"))),
    };
    let settings = MasterSettings {
        reference_temperature_k,
        shift,
    };
    let freqs = curve_freqs_hz.as_slice().map_err(py_err)?.to_vec();
    let temps = curve_temperatures_k.as_slice().map_err(py_err)?.to_vec();
    py.detach(|| {
        let m = fit_master_curve(&points, &settings).map_err(py_err)?;
        #[derive(Serialize)]
        struct Out<'a> {
            fit: &'a lamdyn_fit::master::MasterCurve,
            curve: Vec<lamdyn_fit::master::CurvePoint>,
            shift_curve: Vec<lamdyn_fit::master::ShiftPoint>,
        }
        to_json(&Out {
            curve: m.curve(&freqs),
            shift_curve: temps.iter().filter_map(|&t| m.shift_at(t)).collect(),
            fit: &m,
        })
    })
}
