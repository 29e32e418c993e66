//! `volgraph.TransferFunction`: a piecewise-linear transfer function made in Python (control
//! points of data value, linear RGB and opacity per voxel), read from a file, or taken from a
//! renderer; checked as a TF file is checked, its problems a `ValueError` naming the point.

use std::path::{Path, PathBuf};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use volgraph_accel::transfer_function::{ControlPoint, TransferFunction as Tf};

/// A transfer function: control points (value, (r, g, b), alpha) over a domain of data values.
#[pyclass(module = "volgraph", name = "TransferFunction", frozen)]
#[derive(Clone)]
pub struct TransferFunction {
    pub inner: Tf,
}

/// A point as `(value, (r, g, b), alpha)` or `(value, r, g, b, alpha)`, its value finite.
fn point(index: usize, p: &Bound<'_, PyAny>) -> PyResult<ControlPoint> {
    let point = if let Ok((value, color, alpha)) = p.extract::<(f64, [f64; 3], f64)>() {
        Some(ControlPoint { value, color, alpha })
    } else if let Ok((value, r, g, b, alpha)) = p.extract::<(f64, f64, f64, f64, f64)>() {
        Some(ControlPoint { value, color: [r, g, b], alpha })
    } else {
        None
    };
    if let Some(point) = point {
        if !point.value.is_finite() {
            return Err(PyValueError::new_err(format!(
                "points[{index}].value = {}: a control point sits at a finite data value",
                point.value
            )));
        }
        return Ok(point);
    }
    Err(PyValueError::new_err(format!(
        "points[{index}]: (value, (r, g, b), alpha) or (value, r, g, b, alpha): a data value, linear RGB in 0..1 and \
         an opacity per voxel in 0..1"
    )))
}

fn checked(tf: Tf) -> PyResult<TransferFunction> {
    tf.validate(Path::new("TransferFunction"))
        .map_err(|e| PyValueError::new_err(crate::errors::escaped(e.to_string())))?;
    Ok(TransferFunction { inner: tf })
}

#[pymethods]
impl TransferFunction {
    /// From control points sorted by value, each `(value, (r, g, b), alpha)` (or
    /// `(value, r, g, b, alpha)`): value in the volume's data units, colour linear RGB, alpha the
    /// opacity per voxel of distance; `domain` (lo, hi) defaults to the first and last values.
    #[staticmethod]
    #[pyo3(signature = (points, domain = None))]
    fn from_points(points: &Bound<'_, PyAny>, domain: Option<(f64, f64)>) -> PyResult<Self> {
        let points = points
            .try_iter()
            .map_err(|_| PyValueError::new_err("points: a list of (value, (r, g, b), alpha)"))?
            .enumerate()
            .map(|(i, p)| point(i, &p?))
            .collect::<PyResult<Vec<_>>>()?;
        let domain = match (domain, points.first(), points.last()) {
            (Some(d), _, _) => d,
            (None, Some(first), Some(last)) if last.value > first.value => (first.value, last.value),
            (None, Some(first), Some(_)) => (first.value, first.value + 1.0),
            _ => return Err(PyValueError::new_err("points: a transfer function needs at least one point")),
        };
        checked(Tf { domain, points })
    }

    /// Reads a TF file (RON, or a ParaView colour map .json).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let is_json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let tf = if is_json { Tf::load_paraview(&path) } else { Tf::load(&path) };
        tf.map(|inner| Self { inner }).map_err(|e| PyValueError::new_err(crate::errors::escaped(e.to_string())))
    }

    /// The control points, `(value, (r, g, b), alpha)` each.
    #[getter]
    fn points(&self) -> Vec<(f64, (f64, f64, f64), f64)> {
        self.inner.points.iter().map(|p| (p.value, (p.color[0], p.color[1], p.color[2]), p.alpha)).collect()
    }

    /// The data values the LUT covers, (lo, hi).
    #[getter]
    fn domain(&self) -> (f64, f64) {
        self.inner.domain
    }

    /// This function with every value below `value` transparent (a step there), as the viewer's
    /// threshold does.
    fn hidden_below(&self, value: f64) -> PyResult<Self> {
        checked(self.inner.hidden_below(value))
    }

    /// (r, g, b, alpha) at data value `value`.
    fn __call__(&self, value: f64) -> (f64, f64, f64, f64) {
        let [r, g, b, a] = self.inner.eval(value);
        (r, g, b, a)
    }

    /// The RON text of a TF file (`volgraph render --tf FILE` reads it back).
    fn to_ron(&self) -> String {
        self.inner.to_ron_string()
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        format!(
            "volgraph.TransferFunction({} points over {} .. {})",
            self.inner.points.len(),
            self.inner.domain.0,
            self.inner.domain.1
        )
    }
}
