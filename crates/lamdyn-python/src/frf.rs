//! FRF sets in and out: UFF files (datasets 58, 2411) to and from numpy, and EMA.

use crate::{py_err, py_msg, to_json};
use lamdyn_ema::identify::{EmaSettings, identify};
use lamdyn_frf::{Channel, FrfSet, Quantity};
use num_complex::Complex64;
use numpy::{IntoPyArray, PyArray1, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray3};
use pyo3::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_uff, m)?)?;
    m.add_function(wrap_pyfunction!(read_uff_functions, m)?)?;
    m.add_function(wrap_pyfunction!(write_uff, m)?)?;
    m.add_function(wrap_pyfunction!(ema, m)?)?;
    Ok(())
}

/// A channel as JSON: name, point (m), direction.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ChannelJson {
    name: String,
    #[serde(default)]
    point_m: [f64; 3],
    #[serde(default = "z_axis")]
    direction: [f64; 3],
}

fn z_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

fn channel_json(c: &Channel) -> ChannelJson {
    ChannelJson {
        name: c.name.clone(),
        point_m: c.point_m,
        direction: c.direction,
    }
}

/// Channels from JSON, or `n` unnamed ones (`prefix` + index) when `None`.
fn channels(json: Option<&str>, n: usize, prefix: &str, what: &str) -> PyResult<Vec<Channel>> {
    let list: Vec<ChannelJson> = match json {
        Some(t) => serde_json::from_str(t).map_err(|e| py_msg(format!("{what}: {e}")))?,
        None => (0..n)
            .map(|k| ChannelJson {
                name: format!("{prefix}{k}"),
                point_m: [0.0; 3],
                direction: z_axis(),
            })
            .collect(),
    };
    if list.len() != n {
        return Err(py_msg(format!(
            "{what}: {} channels for an FRF array with {n} along that axis",
            list.len()
        )));
    }
    list.into_iter()
        .map(|c| Channel::new(c.name, c.point_m, c.direction).map_err(py_err))
        .collect()
}

fn quantity(name: &str) -> PyResult<Quantity> {
    match name {
        "receptance" => Ok(Quantity::Receptance),
        "mobility" => Ok(Quantity::Mobility),
        "accelerance" => Ok(Quantity::Accelerance),
        q => Err(py_msg(format!(
            "quantity '{q}': give receptance (m/N), mobility (m/(s N)) or accelerance (m/(s^2 N))"
        ))),
    }
}

fn quantity_name(q: Quantity) -> &'static str {
    match q {
        Quantity::Receptance => "receptance",
        Quantity::Mobility => "mobility",
        Quantity::Accelerance => "accelerance",
    }
}

/// An FRF set from numpy: frf[response, reference, line].
pub(crate) fn frf_set(
    freqs_hz: PyReadonlyArray1<'_, f64>,
    frf: PyReadonlyArray3<'_, Complex64>,
    responses: Option<&str>,
    references: Option<&str>,
    quantity_name: &str,
) -> PyResult<FrfSet> {
    let f = freqs_hz.as_slice().map_err(py_err)?.to_vec();
    let shape = frf.as_array().shape().to_vec();
    let (nr, nref, nl) = (shape[0], shape[1], shape[2]);
    if nl != f.len() {
        return Err(py_msg(format!(
            "frf has {nl} lines on its last axis but freqs_hz has {}",
            f.len()
        )));
    }
    let data: Vec<Complex64> = frf.as_array().iter().copied().collect();
    let resp = channels(responses, nr, "r", "responses")?;
    let refs = channels(references, nref, "ref", "references")?;
    FrfSet::new(f, resp, refs, quantity(quantity_name)?, data).map_err(py_err)
}

/// Arrays and JSON of an FRF set: (freqs_hz, frf[resp, ref, line], info JSON).
type SetOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray3<Complex64>>,
    String,
);

fn set_out<'py>(py: Python<'py>, set: &FrfSet, notices: &[String]) -> PyResult<SetOut<'py>> {
    #[derive(Serialize)]
    struct Info<'a> {
        responses: Vec<ChannelJson>,
        references: Vec<ChannelJson>,
        quantity: &'a str,
        notices: &'a [String],
    }
    let (nr, nref, nl) = (set.responses().len(), set.references().len(), set.n_lines());
    let frf = set
        .data()
        .to_vec()
        .into_pyarray(py)
        .reshape([nr, nref, nl])?;
    let info = Info {
        responses: set.responses().iter().map(channel_json).collect(),
        references: set.references().iter().map(channel_json).collect(),
        quantity: quantity_name(set.quantity()),
        notices,
    };
    Ok((
        set.freqs_hz().to_vec().into_pyarray(py),
        frf,
        to_json(&info)?,
    ))
}

fn read_file(path: &Path, lenient: bool) -> PyResult<lamdyn_uff::UffFile> {
    let options = lamdyn_uff::ReadOptions {
        lenient_counts: lenient,
    };
    lamdyn_uff::read_path(path, options).map_err(|e| py_msg(e.to_string()))
}

/// The FRFs (datasets 58 of function type 4) of a UFF file as one set.
#[pyfunction]
fn read_uff<'py>(py: Python<'py>, path: PathBuf, lenient: bool) -> PyResult<SetOut<'py>> {
    let (set, notices) = py.detach(|| -> PyResult<_> {
        let file = read_file(&path, lenient)?;
        let set = lamdyn_uff::frf::to_frf_set(&file)
            .map_err(|e| py_msg(format!("'{}': {e}", path.display())))?;
        Ok((set, file.notices))
    })?;
    set_out(py, &set, &notices)
}

/// One dataset 58 as it is: header JSON, abscissas, ordinates (real or complex).
type Record<'py> = (String, Bound<'py, PyArray1<f64>>, Py<PyAny>);

/// Every dataset 58 of a UFF file as it is: (header JSON, abscissas, ordinates) per record.
#[pyfunction]
fn read_uff_functions<'py>(
    py: Python<'py>,
    path: PathBuf,
    lenient: bool,
) -> PyResult<Vec<Record<'py>>> {
    #[derive(Serialize)]
    struct Header<'a> {
        id_lines: &'a [String; 5],
        function_type: i64,
        function_id: i64,
        response_entity: &'a str,
        response_node: i64,
        response_direction: i64,
        reference_entity: &'a str,
        reference_node: i64,
        reference_direction: i64,
        complex: bool,
    }
    let file = py.detach(|| read_file(&path, lenient))?;
    file.functions()
        .map(|f| {
            let header = Header {
                id_lines: &f.id_lines,
                function_type: f.function_type,
                function_id: f.function_id,
                response_entity: &f.response.entity,
                response_node: f.response.node,
                response_direction: f.response.direction,
                reference_entity: &f.reference.entity,
                reference_node: f.reference.node,
                reference_direction: f.reference.direction,
                complex: f.ordinate_type.is_complex(),
            };
            let data: Py<PyAny> = match &f.data {
                lamdyn_uff::d58::Ordinate::Real(v) => {
                    v.clone().into_pyarray(py).into_any().unbind()
                }
                lamdyn_uff::d58::Ordinate::Complex(v) => {
                    v.clone().into_pyarray(py).into_any().unbind()
                }
            };
            Ok((to_json(&header)?, f.x().into_pyarray(py), data))
        })
        .collect()
}

/// Writes an FRF set as UFF (2411 nodes, then 58 or 58b per pair).
#[pyfunction]
#[pyo3(signature = (path, freqs_hz, frf, responses, references, quantity, binary))]
#[allow(clippy::too_many_arguments)]
fn write_uff(
    py: Python<'_>,
    path: PathBuf,
    freqs_hz: PyReadonlyArray1<'_, f64>,
    frf: PyReadonlyArray3<'_, Complex64>,
    responses: Option<&str>,
    references: Option<&str>,
    quantity: &str,
    binary: bool,
) -> PyResult<()> {
    let set = frf_set(freqs_hz, frf, responses, references, quantity)?;
    py.detach(|| {
        let datasets = lamdyn_uff::frf::from_frf_set(&set).map_err(py_err)?;
        let encoding = if binary {
            lamdyn_uff::Encoding::Binary {
                little_endian: true,
            }
        } else {
            lamdyn_uff::Encoding::Ascii
        };
        let bytes = lamdyn_uff::write(&datasets, encoding).map_err(py_err)?;
        lamdyn_pipeline::output::write_own_file(
            &path,
            &bytes,
            &[],
            lamdyn_uff::meta::written_by_lamdyn,
            "lamdyn's 151 header",
        )
        .map_err(py_err)
    })
}

/// EMA settings as JSON from Python (every field optional).
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct EmaOptions {
    band_hz: Option<[f64; 2]>,
    orders: Option<(usize, usize, usize)>,
    near_hz: Option<Vec<f64>>,
    reject_hz: Option<Vec<f64>>,
    window_hz: Option<f64>,
    polymax: Option<bool>,
    refine: Option<bool>,
    estimator: Option<lamdyn_ema::identify::PoleEstimator>,
    driving: Option<Driving>,
    cmif_prominence: Option<f64>,
}

/// The driving-point response: its name, as `lamdyn ema --driving` takes it, or its index.
#[derive(Deserialize)]
#[serde(untagged)]
enum Driving {
    Index(usize),
    Name(String),
}

impl Driving {
    /// The response's index in `set`; a name or index that is not a response is an error that
    /// lists the responses.
    fn index(&self, set: &FrfSet) -> PyResult<usize> {
        let names: Vec<&str> = set.responses().iter().map(|c| c.name.as_str()).collect();
        let found = match self {
            Self::Index(k) => (*k < names.len()).then_some(*k),
            Self::Name(name) => names.iter().position(|n| n == name),
        };
        found.ok_or_else(|| {
            let given = match self {
                Self::Index(k) => format!("index {k}"),
                Self::Name(name) => format!("'{name}'"),
            };
            let shown: Vec<&str> = names.iter().take(10).copied().collect();
            py_msg(format!(
                "driving: {given} is not a response of the data ({} responses: {}{})",
                names.len(),
                shown.join(", "),
                if names.len() > shown.len() {
                    ", ..."
                } else {
                    ""
                }
            ))
        })
    }
}

/// Modal identification (PolyMAX / LSCF, stabilization, LSFD) of an FRF set; the result as JSON.
#[pyfunction]
#[pyo3(signature = (freqs_hz, frf, responses, references, quantity, options))]
fn ema(
    py: Python<'_>,
    freqs_hz: PyReadonlyArray1<'_, f64>,
    frf: PyReadonlyArray3<'_, Complex64>,
    responses: Option<&str>,
    references: Option<&str>,
    quantity: &str,
    options: &str,
) -> PyResult<String> {
    let set = frf_set(freqs_hz, frf, responses, references, quantity)?;
    let o: EmaOptions =
        serde_json::from_str(options).map_err(|e| py_msg(format!("ema options: {e}")))?;
    let d = EmaSettings::default();
    let s = EmaSettings {
        band_hz: o.band_hz,
        orders: o.orders.unwrap_or(d.orders),
        near_hz: o.near_hz,
        reject_hz: o.reject_hz.unwrap_or_default(),
        window_hz: o.window_hz.unwrap_or(d.window_hz),
        polymax: o.polymax.unwrap_or(d.polymax),
        refine_iterations: if o.refine.unwrap_or(true) {
            d.refine_iterations
        } else {
            0
        },
        estimator: o.estimator.unwrap_or(d.estimator),
        driving: o.driving.map(|d| d.index(&set)).transpose()?,
        cmif_prominence: o.cmif_prominence.unwrap_or(d.cmif_prominence),
        ..d
    };
    if s.orders.0 < 1 || s.orders.1 < s.orders.0 || s.orders.2 < 1 {
        return Err(py_msg(format!(
            "orders {:?}: give (lowest >= 1, highest >= lowest, step >= 1)",
            s.orders
        )));
    }
    let result = py.detach(|| identify(&set, &s)).map_err(py_err)?;
    to_json(&result)
}
