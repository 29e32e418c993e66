//! The Python package `volgraph` (its extension module `volgraph._volgraph`; the package,
//! its type stubs and docs are in `python/volgraph/`): numpy in, images out, through the same
//! steps as the command line (`volgraph_app::api`). Errors are Python exceptions carrying what the
//! command line says: `GraphError` (with `.path`, `.line`, `.column`), `VolumeError`, `GpuError`,
//! and `ValueError` for a bad array or argument. The GIL is released while a frame renders.

mod array;

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use volgraph_accel::volume::VoxelData;
use volgraph_app::api::{Camera, GraphProblem, Rendered};
use volgraph_app::cli::CliError;
use volgraph_core::runtime::Gpu;

pyo3::create_exception!(volgraph, GraphError, PyException, "A graph file's problems, located: .path, .line, .column.");
pyo3::create_exception!(
    volgraph,
    VolumeError,
    PyException,
    "A volume that cannot be read, with the reason and the fix."
);
pyo3::create_exception!(volgraph, GpuError, PyException, "No GPU adapter, or the GPU refused the work.");

/// The one headless GPU every renderer of this process shares.
fn gpu() -> PyResult<Arc<Gpu>> {
    static GPU: OnceLock<Result<Arc<Gpu>, String>> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new_headless().map(Arc::new).map_err(|e| e.to_string()))
        .clone()
        .map_err(|e| GpuError::new_err(format!("no GPU adapter: {e} (Mesa lavapipe serves where there is no GPU)")))
}

/// A command-line error as the Python exception of its kind: graph problems as `GraphError`,
/// the rest as `fallback`.
fn raise(e: CliError, fallback: fn(String) -> PyErr) -> PyErr {
    match e {
        CliError::Graph(diagnostics) => {
            let problem = GraphProblem::of(&diagnostics);
            Python::attach(|py| {
                let err = GraphError::new_err(escaped(problem.message.clone()));
                let value = err.value(py);
                let set = |name: &str, v: Py<PyAny>| value.setattr(name, v);
                let _ = set("path", problem.path.into_pyobject(py).map(|o| o.into_any().unbind()).unwrap_or(py.None()));
                let _ = set("line", problem.line.into_pyobject(py).map(|o| o.into_any().unbind()).unwrap_or(py.None()));
                let _ =
                    set("column", problem.column.into_pyobject(py).map(|o| o.into_any().unbind()).unwrap_or(py.None()));
                err
            })
        }
        CliError::Other(e) => fallback(escaped(format!("{e:#}"))),
    }
}

fn value_error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// A message as an exception may carry it: control characters of a path or name escaped
/// (`\x1b`), as the command line prints them, so printing the exception never drives a terminal.
fn escaped(message: String) -> String {
    volgraph_core::terminal::escape_controls(&message).into_owned()
}

/// A volume: voxels, spacing and what the file says of them.
#[pyclass(module = "volgraph", frozen)]
pub struct Volume {
    inner: Arc<volgraph_accel::volume::Volume>,
    /// A generated Marschner–Lobb volume: its default TF is the band that shows its rings (as
    /// the command line's).
    ring_tf: bool,
}

#[pymethods]
impl Volume {
    /// The voxels as a numpy array indexed [z, y, x] (a copy).
    #[getter]
    fn array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let d = self.inner.dims;
        let shape = [d.z as usize, d.y as usize, d.x as usize];
        let any = match &self.inner.data {
            VoxelData::U8(v) => PyArray1::from_vec(py, v.clone()).reshape(shape)?.into_any(),
            VoxelData::U16(v) => PyArray1::from_vec(py, v.clone()).reshape(shape)?.into_any(),
            VoxelData::I16(v) => PyArray1::from_vec(py, v.clone()).reshape(shape)?.into_any(),
            VoxelData::F32(v) => PyArray1::from_vec(py, v.clone()).reshape(shape)?.into_any(),
        };
        Ok(any)
    }

    /// Voxel spacing (x, y, z), as the CLI's --spacing.
    #[getter]
    fn spacing(&self) -> (f64, f64, f64) {
        let s = self.inner.spacing;
        (s.x, s.y, s.z)
    }

    /// Voxels per axis (x, y, z).
    #[getter]
    fn dims(&self) -> (u32, u32, u32) {
        let d = self.inner.dims;
        (d.x, d.y, d.z)
    }

    /// The data values that map to 0 and 1 on the GPU.
    #[getter]
    fn value_range(&self) -> (f64, f64) {
        self.inner.value_range
    }

    /// Modality, units, window, frame, origin and description, as far as the file says.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &self.inner.meta;
        let d = PyDict::new(py);
        d.set_item("modality", m.modality.clone())?;
        d.set_item("units", m.units.clone())?;
        d.set_item("window", m.window.map(|w| (w.center, w.width)))?;
        d.set_item("frame", m.frame.describe())?;
        d.set_item("origin", m.origin.map(|o| (o.x, o.y, o.z)))?;
        d.set_item("description", m.description.clone())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let d = self.inner.dims;
        format!("volgraph.Volume(\"{}\", {}×{}×{}, {:?})", self.inner.name, d.x, d.y, d.z, self.inner.data.voxel_type())
    }
}

/// `volume` (a Volume or an array) as the library's volume, and whether its default TF is the
/// Marschner–Lobb band; an array takes `spacing` (x, y, z).
fn volume_of(
    volume: &Bound<'_, PyAny>,
    spacing: Option<(f64, f64, f64)>,
    axes: &str,
) -> PyResult<(volgraph_accel::volume::Volume, bool)> {
    if let Ok(v) = volume.cast::<Volume>() {
        let mut inner = (*v.get().inner).clone();
        if let Some((x, y, z)) = spacing {
            inner.spacing = glam::DVec3::new(x, y, z);
        }
        return Ok((inner, v.get().ring_tf));
    }
    let (data, dims) = array::voxels(volume, axes)?;
    let (x, y, z) = spacing.unwrap_or((1.0, 1.0, 1.0));
    let v = volgraph_app::api::volume_from_memory("array", dims, glam::DVec3::new(x, y, z), data)
        .map_err(|e| raise(e, value_error))?;
    Ok((v, false))
}

/// `camera`: None, (azimuth, elevation, distance) or a patient view's name.
fn camera_of(camera: Option<&Bound<'_, PyAny>>) -> PyResult<Camera> {
    let Some(c) = camera.filter(|c| !c.is_none()) else { return Ok(Camera::Default) };
    if let Ok(name) = c.extract::<String>() {
        return Ok(Camera::View(name));
    }
    let (a, e, d) = c.extract::<(f64, f64, f64)>().map_err(|_| {
        PyValueError::new_err("camera: (azimuth, elevation, distance) in degrees and world units, or a view's name")
    })?;
    Ok(Camera::Orbit(a, e, d))
}

/// A rendered output as numpy: (H, W, 4) uint8 sRGB for `display` (its bytes as read back,
/// what the CLI's PNG holds), float32 linear otherwise.
fn image_array<'py>(py: Python<'py>, rendered: Rendered) -> PyResult<Bound<'py, PyAny>> {
    match rendered {
        Rendered::Srgb8 { width, height, bytes } => {
            Ok(PyArray1::from_vec(py, bytes).reshape([height as usize, width as usize, 4])?.into_any())
        }
        Rendered::Linear(image) => {
            let shape = [image.height as usize, image.width as usize, image.channels as usize];
            Ok(PyArray1::from_vec(py, image.data).reshape(shape)?.into_any())
        }
    }
}

/// A Python value as a graph parameter's RON value.
fn ron_value(value: &Bound<'_, PyAny>) -> PyResult<ron::Value> {
    if let Ok(b) = value.extract::<bool>() {
        return Ok(ron::Value::Bool(b));
    }
    if let Ok(i) = value.extract::<i64>() {
        return Ok(ron::Value::from(i));
    }
    if let Ok(f) = value.extract::<f64>() {
        return Ok(ron::Value::from(f));
    }
    if let Ok(s) = value.extract::<String>() {
        return Ok(ron::Value::String(s));
    }
    Err(PyValueError::new_err("a parameter is a bool, a number or a string"))
}

/// A graph kept on the GPU: set a volume, a transfer function and parameters; render frames.
#[pyclass(module = "volgraph", unsendable)]
pub struct Renderer {
    inner: volgraph_app::api::Renderer,
    size: (u32, u32),
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (graph, size = (512, 512)))]
    fn new(graph: PathBuf, size: (u32, u32)) -> PyResult<Self> {
        let inner = volgraph_app::api::Renderer::on(gpu()?, &graph, size).map_err(|e| raise(e, value_error))?;
        Ok(Self { inner, size })
    }

    /// The volume: a `Volume`, or an array with `set_volume` for its spacing.
    #[setter(volume)]
    fn set_volume_attr(&mut self, volume: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_volume(volume, None, "zyx")
    }

    /// The volume: a `Volume` or an array ([z, y, x], or [x, y, z] with axes="xyz"), its voxel
    /// spacing (x, y, z).
    #[pyo3(signature = (volume, spacing = None, axes = "zyx"))]
    fn set_volume(&mut self, volume: &Bound<'_, PyAny>, spacing: Option<(f64, f64, f64)>, axes: &str) -> PyResult<()> {
        let (v, ring_tf) = volume_of(volume, spacing, axes)?;
        self.inner.set_volume(v, ring_tf);
        Ok(())
    }

    /// The transfer function: a preset ("ct-bone"), a file, a data-folder TF's name, or None
    /// for the one fitted to the data.
    #[setter]
    fn set_tf(&mut self, tf: Option<PathBuf>) {
        self.inner.set_tf(tf);
    }

    /// Sets "PASS.PARAM" (a pass's parameter) or "input.NAME" (a Scalar input).
    fn set(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.inner.set(key, ron_value(value)?).map_err(|e| raise(e, value_error))
    }

    /// Renders one frame: (H, W, 4) uint8 sRGB of `display`, or float32 linear of another output
    /// ("image"). The GIL is released while the GPU works.
    #[pyo3(signature = (camera = None, output = None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        camera: Option<&Bound<'py, PyAny>>,
        output: Option<String>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let camera = camera_of(camera)?;
        let inner = &mut self.inner;
        let rendered = py.detach(|| inner.render(&camera, output.as_deref()));
        image_array(py, rendered.map_err(|e| raise(e, render_error))?)
    }

    /// The default view as PNG bytes, so a notebook shows a renderer as its image.
    fn _repr_png_(&mut self, py: Python<'_>) -> PyResult<Vec<u8>> {
        let rendered = py.detach(|| self.inner.render(&Camera::Default, None)).map_err(|e| raise(e, render_error))?;
        png_bytes(rendered)
    }

    fn __repr__(&self) -> String {
        format!("volgraph.Renderer({}×{})", self.size.0, self.size.1)
    }
}

/// What fails in a render that is not the graph's: no volume, a bad TF or camera (ValueError),
/// else the GPU's.
fn render_error(message: String) -> PyErr {
    if message.contains("GPU") || message.contains("device") || message.contains("adapter") {
        GpuError::new_err(message)
    } else {
        PyValueError::new_err(message)
    }
}

fn png_bytes(rendered: Rendered) -> PyResult<Vec<u8>> {
    // Opaque, as the CLI writes a PNG: sRGB bytes as read back, linear colour encoded.
    let (width, height, bytes) = match rendered {
        Rendered::Srgb8 { width, height, mut bytes } => {
            bytes.chunks_exact_mut(4).for_each(|p| p[3] = 255);
            (width, height, bytes)
        }
        Rendered::Linear(image) => {
            let mut bytes = Vec::with_capacity((image.width * image.height * 4) as usize);
            for y in 0..image.height {
                for x in 0..image.width {
                    let p = image.rgba(x, y);
                    let encode =
                        |v: f32| (volgraph_accel::srgb::encode(f64::from(v)).clamp(0.0, 1.0) * 255.0).round() as u8;
                    bytes.extend([encode(p[0]), encode(p[1]), encode(p[2]), 255]);
                }
            }
            (image.width, image.height, bytes)
        }
    };
    let buffer = image::RgbaImage::from_raw(width, height, bytes)
        .ok_or_else(|| PyValueError::new_err("internal: image size mismatch"))?;
    let mut png = std::io::Cursor::new(Vec::new());
    buffer.write_to(&mut png, image::ImageFormat::Png).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(png.into_inner())
}

/// Reads a volume: a file (.raw named NAME_XxYxZ_TYPE.raw, .nrrd, .nhdr, .mhd, .mha, .nii,
/// .nii.gz), a folder of DICOM slices, a dataset of the data folder by name (`engine`), or a
/// generated volume (`ml64`, `organs128`).
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<Volume> {
    let shown = py
        .detach(|| volgraph_app::scene::load_shown_volume(&[path], None, &volgraph_accel::load::LoadOptions::default()))
        .map_err(|e| VolumeError::new_err(escaped(format!("{e:#}"))))?;
    Ok(Volume { inner: Arc::new(shown.volume), ring_tf: shown.marschner_lobb_tf })
}

/// Renders `volume` (a Volume or a numpy array) with `graph` once: (H, W, 4) uint8 sRGB, or
/// float32 linear for output="image". `spacing` (x, y, z) for an array; `tf` a preset, a file or
/// None (fitted to the data); `camera` (azimuth, elevation, distance) or a view's name.
#[pyfunction]
#[pyo3(signature = (graph, volume, *, spacing = None, axes = "zyx", tf = None, size = (512, 512), camera = None, output = None, params = None))]
#[allow(clippy::too_many_arguments, reason = "Python keyword arguments, each optional")]
fn render<'py>(
    py: Python<'py>,
    graph: PathBuf,
    volume: &Bound<'py, PyAny>,
    spacing: Option<(f64, f64, f64)>,
    axes: &str,
    tf: Option<PathBuf>,
    size: (u32, u32),
    camera: Option<&Bound<'py, PyAny>>,
    output: Option<String>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut r = Renderer::new(graph, size)?;
    r.set_volume(volume, spacing, axes)?;
    r.inner.set_tf(tf);
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
    let source = volgraph_app::inputs::read_graph(&graph).map_err(|e| raise(CliError::Other(e), value_error))?;
    let file = volgraph_app::cli::display_name(&graph);
    let options = volgraph_core::CompileOptions::new(size.0, size.1);
    let plan = volgraph_core::compile(&file, &source, &volgraph_app::program::registry(), &options)
        .map_err(|d| raise(CliError::Graph(d), value_error))?;
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
    m.add_class::<Volume>()?;
    m.add_class::<Renderer>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(graphs, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    m.add("GraphError", m.py().get_type::<GraphError>())?;
    m.add("VolumeError", m.py().get_type::<VolumeError>())?;
    m.add("GpuError", m.py().get_type::<GpuError>())?;
    Ok(())
}
