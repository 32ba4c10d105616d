//! lamdyn's Python module `lamdyn._native`; the package `lamdyn` (python/lamdyn) wraps it with
//! docstrings, keyword arguments and numpy conversions of its results.
//!
//! Conventions: arrays come in as numpy arrays (float64, or complex128 for FRFs) and go out as
//! numpy arrays; structured results (modes, fitted parameters, tables) go out as JSON text that
//! the Python layer turns into dicts with numpy arrays. Every long call releases the GIL, so
//! Dask's threads and other Python threads run meanwhile. Errors raise `lamdyn.LamdynError` with
//! the whole chain of causes (the CLI's message). SI units throughout.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

mod chain;
mod frf;
mod master;
mod model;

// Module `lamdyn`, where the package exports it: pickle finds the class by its module and
// name, so the error keeps its class across processes (Dask's workers).
create_exception!(
    lamdyn,
    LamdynError,
    PyException,
    "An error of lamdyn: bad input (naming the file, line or field) or a failed computation."
);

/// A lamdyn error as a Python exception, its causes joined as the CLI prints them.
pub(crate) fn py_err(e: impl std::error::Error + 'static) -> PyErr {
    LamdynError::new_err(lamdyn_pipeline::error::chain_text(&e))
}

/// A message as a Python exception.
pub(crate) fn py_msg(message: impl Into<String>) -> PyErr {
    LamdynError::new_err(message.into())
}

/// JSON text of a result.
pub(crate) fn to_json<T: serde::Serialize>(v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(py_err)
}

/// The version of the lamdyn crates this module was built from.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Results independent of the thread count (lamdyn_pipeline::same_bits_on_any_thread_count).
    lamdyn_pipeline::same_bits_on_any_thread_count();
    m.add("LamdynError", m.py().get_type::<LamdynError>())?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    frf::register(m)?;
    model::register(m)?;
    chain::register(m)?;
    master::register(m)?;
    Ok(())
}
