//! The package's exceptions and how a library error becomes one: by the error's kind
//! (`volgraph_app::api::ApiError`), never by the words of its message.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use volgraph_app::api::{ApiError, GraphProblem};

pyo3::create_exception!(volgraph, GraphError, PyException, "A graph file's problems, located: .path, .line, .column.");
pyo3::create_exception!(
    volgraph,
    VolumeError,
    PyException,
    "A volume that cannot be read, with the reason and the fix."
);
pyo3::create_exception!(volgraph, GpuError, PyException, "No GPU adapter, or the GPU refused the work.");

/// `e` as the exception of its kind: a graph's problems as `GraphError` (located), the GPU's as
/// `GpuError`, the caller's as `input` makes them (`ValueError`, or `VolumeError` where a volume
/// was read).
pub fn raise(e: ApiError, input: fn(String) -> PyErr) -> PyErr {
    match e {
        ApiError::Graph(diagnostics) => graph_error(&GraphProblem::of(&diagnostics)),
        ApiError::Gpu(e) => GpuError::new_err(escaped(format!("{e:#}"))),
        ApiError::Input(e) => input(escaped(format!("{e:#}"))),
    }
}

fn graph_error(problem: &GraphProblem) -> PyErr {
    Python::attach(|py| {
        let err = GraphError::new_err(escaped(problem.message.clone()));
        let value = err.value(py);
        let _ = value.setattr("path", &problem.path);
        let _ = value.setattr("line", problem.line);
        let _ = value.setattr("column", problem.column);
        err
    })
}

/// A `ValueError` (a bad argument or array).
pub fn value_error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// A `VolumeError` (a volume that cannot be read).
pub fn volume_error(message: String) -> PyErr {
    VolumeError::new_err(message)
}

/// A message as an exception may carry it: control characters of a path or name escaped
/// (`\x1b`), as the command line prints them, so printing the exception never drives a terminal.
pub fn escaped(message: String) -> String {
    volgraph_core::terminal::escape_controls(&message).into_owned()
}
