//! What a frame shows besides the graph and the volume, as keyword arguments: `effects` (the
//! CLI's `--features`), `crop`, `clip` and `light` — checked as the command line checks them.

use glam::DVec3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};
use volgraph_accel::light::{Light, Lights};

/// `effects`: a list of names, or one string of comma-separated names.
pub fn effects(value: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if let Ok(text) = value.extract::<String>() {
        return Ok(text.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect());
    }
    value.extract::<Vec<String>>().map_err(|_| {
        PyValueError::new_err("effects: a list of names (\"shading\", \"jitter\", …) or \"shading,jitter\"")
    })
}

/// `crop` (x0, y0, z0, x1, y1, z1) and `clip` [(nx, ny, nz, d), …] in volume fractions.
pub fn cuts(crop: Option<&Bound<'_, PyAny>>, clip: Option<&Bound<'_, PyAny>>) -> PyResult<Cuts> {
    let problem = |what: &str, e: &dyn std::fmt::Display| PyValueError::new_err(format!("{what}: {e}"));
    let crop = match crop.filter(|c| !c.is_none()) {
        None => None,
        Some(c) => {
            let [x0, y0, z0, x1, y1, z1] = c.extract::<[f64; 6]>().map_err(|_| {
                PyValueError::new_err("crop: (x0, y0, z0, x1, y1, z1), fractions of the volume (0..1 per axis)")
            })?;
            Some(CropBox::new(DVec3::new(x0, y0, z0), DVec3::new(x1, y1, z1)).map_err(|e| problem("crop", &e))?)
        }
    };
    let planes = match clip.filter(|c| !c.is_none()) {
        None => Vec::new(),
        Some(c) => {
            let tuples = match c.extract::<[f64; 4]>() {
                Ok(one) => vec![one],
                Err(_) => c.extract::<Vec<[f64; 4]>>().map_err(|_| {
                    PyValueError::new_err(
                        "clip: a plane (nx, ny, nz, d) or a list of them, keeping n·f >= d (f: volume fractions)",
                    )
                })?,
            };
            tuples
                .into_iter()
                .map(|[x, y, z, d]| ClipPlane::new(DVec3::new(x, y, z), d).map_err(|e| problem("clip", &e)))
                .collect::<PyResult<Vec<_>>>()?
        }
    };
    Cuts::new(crop, &planes).map_err(|e| problem("clip", &e))
}

/// `light`: one light, or a list of up to three (as `--light` repeated; a tuple is one light).
pub fn lights(value: &Bound<'_, PyAny>) -> PyResult<Lights> {
    if let Ok(list) = value.cast::<pyo3::types::PyList>() {
        let lights = list.iter().map(|item| light(&item)).collect::<PyResult<Vec<_>>>()?;
        return Lights::new(&lights).map_err(|e| PyValueError::new_err(format!("light: {e}")));
    }
    Ok(light(value)?.into())
}

/// One light: "headlight", (azimuth, elevation) in degrees, ("point", x, y, z) in world units,
/// or the command line's text (`"30,45"`, `"point:0,2,0"`).
fn light(value: &Bound<'_, PyAny>) -> PyResult<Light> {
    let text = if let Ok(text) = value.extract::<String>() {
        text
    } else if let Ok((az, el)) = value.extract::<(f64, f64)>() {
        format!("{az},{el}")
    } else if let Ok((kind, x, y, z)) = value.extract::<(String, f64, f64, f64)>()
        && kind == "point"
    {
        format!("point:{x},{y},{z}")
    } else {
        return Err(PyValueError::new_err(
            "light: \"headlight\", (azimuth, elevation) in degrees, or (\"point\", x, y, z) in world units",
        ));
    };
    Light::parse(&text).map_err(|e| PyValueError::new_err(format!("light: {e}")))
}
