//! `volgraph.Renderer`: a graph kept on the GPU (`volgraph_app::api::Renderer`), with the
//! volume, transfer function, parameters, effects, cuts, light and scene as attributes; frames
//! rendered with the GIL released.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use volgraph_app::api::{Camera, Rendered, TfChoice};

use crate::errors::{raise, value_error};
use crate::tf::TransferFunction;

/// `camera`: None, (azimuth, elevation, distance) or a patient view's name.
pub fn camera_of(camera: Option<&Bound<'_, PyAny>>) -> PyResult<Camera> {
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

/// A transfer function argument: None (fitted, or the scene's), a name or file, or a
/// `TransferFunction`.
fn tf_choice(tf: Option<&Bound<'_, PyAny>>) -> PyResult<TfChoice> {
    let Some(tf) = tf.filter(|t| !t.is_none()) else { return Ok(TfChoice::Fitted) };
    if let Ok(f) = tf.cast::<TransferFunction>() {
        return Ok(TfChoice::Function(f.get().inner.clone()));
    }
    tf.extract::<PathBuf>().map(TfChoice::Named).map_err(|_| {
        PyValueError::new_err(
            "tf: a preset (\"ct-bone\"), a TF file, a data-folder TF's name, a TransferFunction or None",
        )
    })
}

/// A graph kept on the GPU: set a volume, a transfer function, parameters, effects, cuts and the
/// light; render frames. Any thread may use it; calls from several threads take turns, and
/// several renderers render in parallel.
#[pyclass(module = "volgraph", subclass)]
pub struct Renderer {
    inner: Mutex<volgraph_app::api::Renderer>,
    /// Seconds the library took for the last frame (`f64` bits): the frame without this layer.
    last_frame_seconds: AtomicU64,
}

impl Renderer {
    /// Runs `f` on the library's renderer with the GIL released: the lock is taken and given
    /// back while the GIL is not held, so a thread waiting for it never holds the GIL the
    /// renderer's thread needs.
    fn with<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut volgraph_app::api::Renderer) -> R + Send) -> R {
        py.detach(|| f(&mut self.inner.lock().unwrap_or_else(PoisonError::into_inner)))
    }
}

#[pymethods]
impl Renderer {
    /// `graph`: a built-in name (`modern/fastest`) or a graph file; `scene`: a scene file (or a
    /// built-in scene's name) giving the graph, size, volume, TF, camera, effects, cuts and light
    /// that nothing else gives. `size`: (width, height), default the scene's, else 512×512.
    #[new]
    #[pyo3(signature = (graph = None, size = None, *, scene = None))]
    pub fn new(graph: Option<PathBuf>, size: Option<(u32, u32)>, scene: Option<PathBuf>) -> PyResult<Self> {
        let gpu = crate::gpu()?;
        let inner = match (scene, graph) {
            (Some(scene), graph) => volgraph_app::api::Renderer::from_scene(gpu, &scene, graph.as_deref(), size),
            (None, Some(graph)) => volgraph_app::api::Renderer::on(gpu, &graph, size.unwrap_or((512, 512))),
            (None, None) => return Err(PyValueError::new_err("Renderer: give a graph (\"modern/fastest\") or scene=")),
        };
        Ok(Self { inner: Mutex::new(inner.map_err(|e| raise(e, value_error))?), last_frame_seconds: AtomicU64::new(0) })
    }

    /// The volume: a `Volume`, or an array with `set_volume` for its spacing.
    #[setter(volume)]
    fn set_volume_attr(&self, volume: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_volume(volume, None, "zyx", None)
    }

    /// The volume: a `Volume` or an array ([z, y, x], or [x, y, z] with axes="xyz"), its voxel
    /// spacing (x, y, z). `name`: the graph's volume input it binds (`pet` of `multi/pet_ct`,
    /// as `--volume pet=PATH`); default the input `volume`.
    #[pyo3(signature = (volume, spacing = None, axes = "zyx", name = None))]
    pub fn set_volume(
        &self,
        volume: &Bound<'_, PyAny>,
        spacing: Option<(f64, f64, f64)>,
        axes: &str,
        name: Option<String>,
    ) -> PyResult<()> {
        // A path: read as `--volume PATH` reads it (an OME-Zarr store streamed by a streaming
        // graph, anything else loaded whole).
        if name.is_none()
            && spacing.is_none()
            && !volume.is_instance_of::<pyo3::types::PyList>()
            && let Ok(path) = volume.extract::<PathBuf>()
        {
            return self
                .with(volume.py(), |r| r.set_volume_path(&path, None))
                .map_err(|e| raise(e, crate::errors::volume_error));
        }
        let (v, ring_tf) = crate::volume::volume_of(volume, spacing, axes)?;
        match name.filter(|n| n != volgraph_core::runtime::inputs::PRIMARY_VOLUME) {
            Some(name) => self.with(volume.py(), |r| r.set_named_volume(&name, v)),
            None => self.with(volume.py(), |r| r.set_volume(v, ring_tf)),
        }
        Ok(())
    }

    /// Streams the OME-Zarr store `path` brick by brick (a streaming graph such as
    /// `streaming/ray_guided`): `frame` picks the volume N = t·C + c, `memory_mb` bounds the
    /// decoded chunks held (default 512). A raw, NRRD or MetaImage file larger than `memory_mb`
    /// streams from the file itself; a smaller one is read in core. A render waits for the full
    /// image, or for `time_budget_ms`.
    #[pyo3(signature = (path, *, frame = None, memory_mb = None))]
    pub fn stream(&self, py: Python<'_>, path: PathBuf, frame: Option<u64>, memory_mb: Option<u64>) -> PyResult<()> {
        self.with(py, |r| r.stream(&path, frame, memory_mb)).map_err(|e| raise(e, value_error))
    }

    /// Milliseconds a render of a streaming graph may refine before it returns what it drew
    /// (bricks still being read drawn from a coarser level); None: until the image is complete.
    #[setter(time_budget_ms)]
    fn set_time_budget_ms(&self, py: Python<'_>, ms: Option<f64>) -> PyResult<()> {
        // At most a day, as `--time-budget-ms`; NaN, negatives and 1e39 are refused, not panics.
        let budget = match ms {
            None => None,
            Some(m) if (0.0..=86_400_000.0).contains(&m) => Some(std::time::Duration::from_secs_f64(m / 1e3)),
            Some(m) => {
                return Err(PyValueError::new_err(format!(
                    "time_budget_ms {m}: milliseconds from 0 to 86400000 (a day), or None"
                )));
            }
        };
        self.with(py, |r| r.set_time_budget(budget));
        Ok(())
    }

    /// Binds the transfer-function or label-table input `name` (`pet_tf`, `label_table`) to a
    /// preset, a file or a data-folder TF's name, as `--tf NAME=…`.
    pub fn set_named_tf(&self, py: Python<'_>, name: String, tf: PathBuf) {
        self.with(py, |r| r.set_named_tf(&name, tf));
    }

    /// The transfer function: a preset ("ct-bone"), a file, a data-folder TF's name, a
    /// `TransferFunction`, or None for the scene's or the one fitted to the data.
    #[setter(tf)]
    pub fn set_tf(&self, py: Python<'_>, tf: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let tf = tf_choice(tf)?;
        self.with(py, |r| r.set_tf(tf));
        Ok(())
    }

    /// The transfer function the next frame classifies with (fitted to the volume if none was
    /// given), as a `TransferFunction`.
    #[getter(tf)]
    fn get_tf(&self, py: Python<'_>) -> PyResult<TransferFunction> {
        let tf = self.with(py, |r| r.transfer_function()).map_err(|e| raise(e, value_error))?;
        Ok(TransferFunction { inner: tf })
    }

    /// Effects that are on, besides the scene's: a list of names or "shading,jitter" (as
    /// `--features`; a name the graph lacks is an error at the next frame, naming its effects).
    #[setter]
    pub fn set_effects(&self, effects: &Bound<'_, PyAny>) -> PyResult<()> {
        let features = if effects.is_none() { Vec::new() } else { crate::look::effects(effects)? };
        self.with(effects.py(), |r| r.set_features(features));
        Ok(())
    }

    /// The crop box and clip planes in volume fractions (as `--crop` and `--clip`; they replace
    /// the scene's): `crop` (x0, y0, z0, x1, y1, z1), `clip` a plane (nx, ny, nz, d) or a list.
    #[pyo3(signature = (crop = None, clip = None))]
    pub fn set_cuts(
        &self,
        py: Python<'_>,
        crop: Option<&Bound<'_, PyAny>>,
        clip: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let cuts = crate::look::cuts(crop, clip)?;
        self.with(py, |r| r.set_cuts(cuts));
        Ok(())
    }

    /// The light (as `--light`): "headlight", (azimuth, elevation) or ("point", x, y, z); a list
    /// of up to three for several.
    #[setter]
    pub fn set_light(&self, light: &Bound<'_, PyAny>) -> PyResult<()> {
        let parsed = crate::look::lights(light)?;
        self.with(light.py(), |r| r.set_lights(parsed));
        Ok(())
    }

    /// Sets "PASS.PARAM" (a pass's parameter) or "input.NAME" (a Scalar input).
    pub fn set(&self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let parsed = ron_value(value)?;
        self.with(value.py(), |r| r.set(key, parsed)).map_err(|e| raise(e, value_error))
    }

    /// The volume's data values that map to 0 and 1 (a TF slider's range); None before a volume.
    #[getter]
    fn value_range(&self, py: Python<'_>) -> Option<(f64, f64)> {
        self.with(py, |r| r.volume().map(|v| v.value_range))
    }

    /// (azimuth, elevation, distance) of the default camera: the scene's, the anterior view for
    /// a volume in the patient frame, else 30°, 20°, 3.2.
    #[getter]
    fn default_camera(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        let c = self.with(py, |r| r.default_camera()).map_err(|e| raise(e, value_error))?;
        Ok((c.azimuth_deg, c.elevation_deg, c.distance))
    }

    /// The notes of the last frame's compile (an effect the graph lacks, a TF repaired, a volume
    /// the TF hides): what the command line prints on stderr.
    #[getter]
    fn notes(&self, py: Python<'_>) -> Vec<String> {
        self.with(py, |r| r.notes().to_vec())
    }

    /// Renders one frame: (H, W, 4) uint8 sRGB of `display`, or float32 linear of another output
    /// ("image"). The GIL is released while the GPU works.
    #[pyo3(signature = (camera = None, output = None))]
    pub fn render<'py>(
        &self,
        py: Python<'py>,
        camera: Option<&Bound<'py, PyAny>>,
        output: Option<String>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let camera = camera_of(camera)?;
        let rendered = self.with(py, |r| {
            let start = Instant::now();
            let rendered = r.render(&camera, output.as_deref());
            self.last_frame_seconds.store(start.elapsed().as_secs_f64().to_bits(), Ordering::Relaxed);
            rendered
        });
        image_array(py, rendered.map_err(|e| raise(e, value_error))?)
    }

    /// Milliseconds the library took for the last `render` (render, wait, read back), without
    /// the Python layer around it: a script's wall clock minus this is what Python adds.
    #[getter]
    fn last_frame_ms(&self) -> f64 {
        f64::from_bits(self.last_frame_seconds.load(Ordering::Relaxed)) * 1e3
    }

    /// The converged f64 reference of the frame `camera` shows: the graph's raycast model
    /// (mode, effects, cuts, light) at `step_voxels` with lossless termination and no jitter —
    /// premultiplied linear RGBA, float64 (H, W, 4), to compare with `render(output="image")`
    /// (what `volgraph sweep` measures). Computed on the CPU (all cores), the GIL released.
    #[pyo3(signature = (camera = None, step_voxels = 0.1))]
    fn reference<'py>(
        &self,
        py: Python<'py>,
        camera: Option<&Bound<'py, PyAny>>,
        step_voxels: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let camera = camera_of(camera)?;
        let (image, (w, h)) = self
            .with(py, |r| r.reference(&camera, step_voxels).map(|image| (image, r.size())))
            .map_err(|e| raise(e, value_error))?;
        let flat: Vec<f64> = image.into_iter().flatten().collect();
        Ok(PyArray1::from_vec(py, flat).reshape([h as usize, w as usize, 4])?.into_any())
    }

    /// The default view as PNG bytes, so a notebook shows a renderer as its image.
    fn _repr_png_(&self, py: Python<'_>) -> PyResult<Vec<u8>> {
        let rendered = self.with(py, |r| r.render(&Camera::Default, None)).map_err(|e| raise(e, value_error))?;
        png_bytes(rendered)
    }

    /// (width, height) in pixels.
    #[getter]
    fn size(&self, py: Python<'_>) -> (u32, u32) {
        self.with(py, |r| r.size())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let (w, h) = self.size(py);
        format!("volgraph.Renderer({w}×{h})")
    }
}

/// `rendered` as an opaque PNG, as the CLI writes one: sRGB bytes as read back, linear colour
/// encoded.
pub fn png_bytes(rendered: Rendered) -> PyResult<Vec<u8>> {
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
