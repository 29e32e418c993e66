//! The Python package `volgraph` (its extension module `volgraph._volgraph`; the package,
//! its type stubs and docs are in `python/volgraph/`): numpy in, images out, through the same
//! steps as the command line (`volgraph_app::api`). Errors are Python exceptions carrying what the
//! command line says: `GraphError` (with `.path`, `.line`, `.column`), `VolumeError`, `GpuError`,
//! and `ValueError` for a bad array or argument. The GIL is released while a frame renders.

mod array;
mod errors;
mod look;
mod renderer;
mod tf;
mod volume;

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use volgraph_app::api::ApiError;
use volgraph_core::runtime::Gpu;

use errors::{GpuError, GraphError, VolumeError, raise, value_error};
use renderer::Renderer;

/// The one headless GPU every renderer of this process shares.
fn gpu() -> PyResult<Arc<Gpu>> {
    static GPU: OnceLock<Result<Arc<Gpu>, String>> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new_headless().map(Arc::new).map_err(|e| e.to_string()))
        .clone()
        .map_err(|e| GpuError::new_err(format!("no GPU adapter: {e} (Mesa lavapipe serves where there is no GPU)")))
}

/// Renders once: `graph` (a name or file) or a `scene`'s, of `volume` (a Volume or a numpy
/// array; default the scene's): (H, W, 4) uint8 sRGB, or float32 linear for output="image".
/// `spacing` (x, y, z) for an array; `tf` a preset, a file, a `TransferFunction` or None (the
/// scene's, else fitted to the data); `camera` (azimuth, elevation, distance) or a view's name;
/// `effects`, `crop`, `clip` and `light` as the command line's `--features`, `--crop`, `--clip`
/// and `--light`; `volumes` {"pet": array, Volume or (array, spacing)} and `tfs` {"pet_tf":
/// preset or file} bind a graph's other inputs by name, as `--volume NAME=…` and `--tf NAME=…`;
/// `params` {"PASS.PARAM": value}.
#[pyfunction]
#[pyo3(signature = (
    graph = None, volume = None, *, scene = None, spacing = None, axes = "zyx", tf = None, size = None, camera = None,
    output = None, effects = None, crop = None, clip = None, light = None, volumes = None, tfs = None, params = None,
))]
#[allow(clippy::too_many_arguments, reason = "Python keyword arguments, each optional")]
fn render<'py>(
    py: Python<'py>,
    graph: Option<PathBuf>,
    volume: Option<&Bound<'py, PyAny>>,
    scene: Option<PathBuf>,
    spacing: Option<(f64, f64, f64)>,
    axes: &str,
    tf: Option<&Bound<'py, PyAny>>,
    size: Option<(u32, u32)>,
    camera: Option<&Bound<'py, PyAny>>,
    output: Option<String>,
    effects: Option<&Bound<'py, PyAny>>,
    crop: Option<&Bound<'py, PyAny>>,
    clip: Option<&Bound<'py, PyAny>>,
    light: Option<&Bound<'py, PyAny>>,
    volumes: Option<&Bound<'py, PyDict>>,
    tfs: Option<&Bound<'py, PyDict>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let r = Renderer::new(graph, size, scene)?;
    match volume.filter(|v| !v.is_none()) {
        Some(volume) => r.set_volume(volume, spacing, axes, None)?,
        None if spacing.is_some() => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "spacing= is the spacing of a volume= array; give one",
            ));
        }
        None => {}
    }
    r.set_tf(py, tf)?;
    if let Some(effects) = effects {
        r.set_effects(effects)?;
    }
    if crop.is_some() || clip.is_some() {
        r.set_cuts(py, crop, clip)?;
    }
    if let Some(light) = light {
        r.set_light(light)?;
    }
    for (name, value) in volumes.into_iter().flat_map(|d| d.iter()) {
        let name = name.extract::<String>()?;
        match value.extract::<(Bound<'py, PyAny>, (f64, f64, f64))>() {
            Ok((array, spacing)) => r.set_volume(&array, Some(spacing), axes, Some(name))?,
            Err(_) => r.set_volume(&value, None, axes, Some(name))?,
        }
    }
    for (name, value) in tfs.into_iter().flat_map(|d| d.iter()) {
        r.set_named_tf(py, name.extract::<String>()?, value.extract::<PathBuf>()?);
    }
    if let Some(params) = params {
        for (key, value) in params.iter() {
            r.set(&key.extract::<String>()?, &value)?;
        }
    }
    r.render(py, camera, output)
}

/// The built-in graphs: name, paper, description.
#[pyfunction]
fn graphs(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for g in volgraph_app::builtin_graphs::all() {
        let d = PyDict::new(py);
        d.set_item("name", g.name)?;
        d.set_item("paper", g.paper)?;
        d.set_item("description", g.description)?;
        list.append(d)?;
    }
    Ok(list)
}

/// What `graph` compiles to at `size` (no GPU): its name, viewport, features, inputs, steps in
/// order (label, pass, kind), the passes culled and the outputs — `volgraph plan` as a dict.
/// A broken graph raises `GraphError`.
#[pyfunction]
#[pyo3(signature = (graph, size = (1920, 1080)))]
fn plan<'py>(py: Python<'py>, graph: PathBuf, size: (u32, u32)) -> PyResult<Bound<'py, PyDict>> {
    let source = volgraph_app::inputs::read_graph(&graph).map_err(|e| raise(ApiError::Input(e), value_error))?;
    let file = volgraph_app::cli::display_name(&graph);
    let options = volgraph_core::CompileOptions::new(size.0, size.1);
    let plan = volgraph_core::compile(&file, &source, &volgraph_app::program::registry(), &options)
        .map_err(|d| raise(ApiError::Graph(d), value_error))?;
    let d = PyDict::new(py);
    d.set_item("name", &plan.name)?;
    d.set_item("viewport", plan.viewport)?;
    d.set_item("features", plan.features.iter().cloned().collect::<Vec<_>>())?;
    d.set_item("inputs", plan.inputs.keys().cloned().collect::<Vec<_>>())?;
    let steps = PyList::empty(py);
    for step in &plan.steps {
        let s = PyDict::new(py);
        s.set_item("label", &step.label)?;
        s.set_item("pass", &step.pass_id)?;
        s.set_item("kind", &step.kind)?;
        steps.append(s)?;
    }
    d.set_item("steps", steps)?;
    d.set_item("culled", plan.culled.clone())?;
    d.set_item("outputs", plan.outputs.keys().cloned().collect::<Vec<_>>())?;
    Ok(d)
}

/// The extension module.
#[pymodule]
fn _volgraph(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<volume::Volume>()?;
    m.add_class::<Renderer>()?;
    m.add_class::<tf::TransferFunction>()?;
    m.add_function(wrap_pyfunction!(volume::load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(graphs, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    m.add("GraphError", m.py().get_type::<GraphError>())?;
    m.add("VolumeError", m.py().get_type::<VolumeError>())?;
    m.add("GpuError", m.py().get_type::<GpuError>())?;
    Ok(())
}
