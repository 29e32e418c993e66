//! volgraph as a library: a graph kept on a GPU, a volume handed over in memory, images back —
//! what the Python package (`crates/python`) wraps and any Rust program may use. Every step is
//! the command line's (`render.rs`): the graph read by name or file, the transfer function by
//! preset, file or fitted to the data, the scene values of the volume, the camera (the anterior
//! view for a volume in the patient frame), the same runtime and output — so an image equals
//! `volgraph render`'s of the same voxels bit for bit (`crates/python/tests/test_volgraph.py`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::anyhow;
use volgraph_accel::camera::{OrbitCamera, PatientView};
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, Plan, Registry};

use crate::cli::CliError;

/// Where a graph problem lies: the file as given, 1-based line and column where the graph text
/// has one, the message and the help — what `volgraph.GraphError` carries.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphProblem {
    /// The graph file as named.
    pub path: String,
    /// 1-based line, where the problem has a place in the text.
    pub line: Option<usize>,
    /// 1-based column (characters).
    pub column: Option<usize>,
    /// Every problem, as the command line prints them (located, with their fixes).
    pub message: String,
}

impl GraphProblem {
    /// The first problem's place of `diagnostics`, and all of them as text.
    pub fn of(diagnostics: &volgraph_core::Diagnostics) -> Self {
        let place = diagnostics.items.iter().find_map(|d| match &d.location {
            volgraph_core::Location::Span(s) => Some(volgraph_core::graph::spans::line_col(&diagnostics.text, s.start)),
            _ => None,
        });
        Self {
            path: diagnostics.file.clone(),
            line: place.map(|p| p.0),
            column: place.map(|p| p.1),
            message: diagnostics.to_string(),
        }
    }
}

/// A camera as the library takes it: an orbit, a patient view by name, or the command line's
/// default for the volume.
#[derive(Clone, Debug, PartialEq)]
pub enum Camera {
    /// `--camera AZ,EL,DIST`: degrees about +y, degrees up, distance in world units.
    Orbit(f64, f64, f64),
    /// `--view NAME` (anterior, posterior, left, right, superior, inferior).
    View(String),
    /// Neither: the anterior view for a volume in the patient frame, else 30°, 20°, 3.2.
    Default,
}

impl Camera {
    /// The orbit camera this names for `volume`.
    pub fn orbit(&self, volume: &Volume) -> Result<OrbitCamera, CliError> {
        match self {
            Camera::Orbit(azimuth_deg, elevation_deg, distance) => {
                let finite = [azimuth_deg, elevation_deg, distance].iter().all(|v| v.is_finite());
                if !finite || *distance <= 0.0 {
                    return Err(anyhow!(
                        "camera ({azimuth_deg}, {elevation_deg}, {distance}): azimuth, elevation and a distance > 0, \
                         all finite"
                    )
                    .into());
                }
                Ok(OrbitCamera {
                    azimuth_deg: *azimuth_deg,
                    elevation_deg: *elevation_deg,
                    distance: *distance,
                    ..OrbitCamera::default()
                })
            }
            Camera::View(name) => {
                crate::scene_args::check_view_frame(Some(name), volume)?;
                let view = PatientView::from_name(name)
                    .ok_or_else(|| anyhow!("view \"{name}\": not a view; the views are {}", PatientView::names()))?;
                Ok(view.camera(3.2))
            }
            Camera::Default if volume.meta.frame == volgraph_accel::volume_meta::WorldFrame::Lps => {
                Ok(PatientView::Anterior.camera(3.2))
            }
            Camera::Default => Ok(OrbitCamera::default()),
        }
    }
}

/// A rendered output, rows from the top.
pub enum Rendered {
    /// An 8-bit RGBA output (`present`'s `display`): sRGB-encoded bytes, as the PNG holds them.
    Srgb8 {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// RGBA bytes.
        bytes: Vec<u8>,
    },
    /// Any other target: linear float values.
    Linear(Image),
}

/// A graph on a GPU with its inputs: set a volume, a transfer function and parameters, render.
/// The GPU state (pipelines, textures) stays between renders; a change recompiles only what it
/// touches, as in the viewer.
pub struct Renderer {
    graph: PathBuf,
    source: String,
    registry: Registry,
    size: (u32, u32),
    runtime: Runtime,
    volume: Option<Volume>,
    /// A generated Marschner–Lobb volume: the default TF is the band showing its rings.
    ring_tf: bool,
    tf: Option<PathBuf>,
    lut: Option<Vec<[f32; 4]>>,
    overrides: BTreeMap<String, ron::Value>,
    scalars: BTreeMap<String, f64>,
    /// The plan applied, or `None` once something it was compiled from changed.
    plan: Option<Plan>,
}

impl Renderer {
    /// Graph `graph` (a file or a built-in name, `modern/fastest`) at `size` pixels on a new
    /// headless GPU.
    pub fn new(graph: &Path, size: (u32, u32)) -> Result<Self, CliError> {
        let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
        Self::on(gpu, graph, size)
    }

    /// [`Self::new`] on an existing GPU (several renderers share one device).
    pub fn on(gpu: Arc<Gpu>, graph: &Path, size: (u32, u32)) -> Result<Self, CliError> {
        if size.0 == 0 || size.1 == 0 || size.0 > 16384 || size.1 > 16384 {
            return Err(anyhow!("size {}x{}: 1 to 16384 pixels a side", size.0, size.1).into());
        }
        let source = crate::inputs::read_graph(graph)?;
        let (sources, _) = crate::shader_dir::sources_for(graph, None);
        let runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
        let renderer = Self {
            graph: graph.to_path_buf(),
            source,
            registry: crate::program::registry(),
            size,
            runtime,
            volume: None,
            ring_tf: false,
            tf: None,
            lut: None,
            overrides: BTreeMap::new(),
            scalars: BTreeMap::new(),
            plan: None,
        };
        // The graph is checked now (without a volume's scene values), so a broken file fails here.
        renderer.compile(&Volume::new(
            "check",
            glam::UVec3::ONE,
            glam::DVec3::ONE,
            volgraph_accel::volume::VoxelData::U8(vec![0]),
        ))?;
        Ok(renderer)
    }

    /// The volume to render (its transfer function refitted unless one was set);
    /// `marschner_lobb_tf`: a generated Marschner–Lobb volume, whose default TF is the band that
    /// shows its rings (`scene::ShownVolume::marschner_lobb_tf`).
    pub fn set_volume(&mut self, volume: Volume, marschner_lobb_tf: bool) {
        self.volume = Some(volume);
        self.ring_tf = marschner_lobb_tf;
        self.lut = None;
        self.plan = None;
    }

    /// The volume set, if any.
    pub fn volume(&self) -> Option<&Volume> {
        self.volume.as_ref()
    }

    /// The transfer function: a preset (`ct-bone`), a file, a data-folder TF by name, or `None`
    /// for the one fitted to the data (as `--tf`).
    pub fn set_tf(&mut self, tf: Option<PathBuf>) {
        self.tf = tf;
        self.lut = None;
    }

    /// Sets `PASS.PARAM` or `input.NAME` (a Scalar input) to `value`, checked when the graph is
    /// next compiled (an unknown name or a value out of range is an error then, named).
    pub fn set(&mut self, key: &str, value: ron::Value) -> Result<(), CliError> {
        match key.strip_prefix("input.") {
            Some(name) => {
                let v = match &value {
                    ron::Value::Number(n) => n.into_f64(),
                    _ => return Err(anyhow!("{key}: an input takes a number").into()),
                };
                self.scalars.insert(name.to_string(), v);
            }
            None if key.contains('.') => {
                self.overrides.insert(key.to_string(), value);
            }
            None => return Err(anyhow!("{key}: write PASS.PARAM or input.NAME").into()),
        }
        self.plan = None;
        Ok(())
    }

    fn compile(&self, volume: &Volume) -> Result<Plan, CliError> {
        let mut options = CompileOptions::new(self.size.0, self.size.1);
        options.scalars = self.scalars.clone();
        options.param_overrides = self.overrides.clone();
        options.scene = scene_values_of(&VolumeDesc::of(volume));
        options.scene.extend(crate::inputs::data_scene_values(volume));
        let file = crate::cli::display_name(&self.graph);
        let plan = volgraph_core::compile(&file, &self.source, &self.registry, &options).map_err(CliError::Graph)?;
        crate::cli::check_user_names(&plan, &options)?;
        Ok(plan)
    }

    /// Renders one frame of `camera` and reads `output` (default: `display` where the graph has
    /// it, else `image`). Waits for the GPU.
    pub fn render(&mut self, camera: &Camera, output: Option<&str>) -> Result<Rendered, CliError> {
        let Some(volume) = self.volume.as_ref() else {
            return Err(anyhow!("no volume: set one before rendering").into());
        };
        if self.lut.is_none() {
            let (tf, _) = crate::inputs::transfer_function(self.tf.as_ref(), None, volume, self.ring_tf)?;
            let lut = tf.to_lut_for(volume, crate::inputs::LUT_SIZE);
            self.lut = Some(lut);
            self.plan = None;
        }
        let orbit = camera.orbit(volume)?;
        if self.plan.is_none() {
            let plan = self.compile(volume)?;
            let lut = self.lut.as_deref().unwrap_or_default();
            self.runtime.bind_scene(&plan.inputs, volume, lut).map_err(|e| anyhow!(e))?;
            self.runtime.apply(plan.clone(), &self.registry).map_err(|e| anyhow!(e))?;
            self.plan = Some(plan);
        }
        let plan = self.plan.as_ref().ok_or_else(|| anyhow!("internal: no plan"))?;
        let output = match output {
            Some(name) => name.to_string(),
            None if plan.outputs.contains_key("display") => "display".to_string(),
            None => "image".to_string(),
        };
        let Some(&resource) = plan.outputs.get(&output) else {
            let known: Vec<&str> = plan.outputs.keys().map(String::as_str).collect();
            return Err(anyhow!("output \"{output}\": the graph's outputs are {}", known.join(", ")).into());
        };
        let srgb = matches!(
            plan.resources[resource].desc,
            volgraph_core::plan::ResourceDesc::Target { format: volgraph_core::TargetFormat::Rgba8Unorm, .. }
        );
        self.runtime.render(CameraData::from_orbit(&orbit, plan.viewport)).map_err(|e| anyhow!(e))?;
        if srgb {
            let (width, height, bytes) = self.runtime.read_output_rgba8(&output).map_err(|e| anyhow!(e))?;
            return Ok(Rendered::Srgb8 { width, height, bytes });
        }
        Ok(Rendered::Linear(self.runtime.read_output(&output).map_err(|e| anyhow!(e))?))
    }
}

/// A volume handed over in memory, as a raw file of the same voxels is read (`load::from_memory`).
pub fn volume_from_memory(
    name: &str,
    dims: glam::UVec3,
    spacing: glam::DVec3,
    data: volgraph_accel::volume::VoxelData,
) -> Result<Volume, CliError> {
    Ok(volgraph_accel::load::from_memory(name, dims, spacing, data).map_err(|e| anyhow!(e))?.volume)
}
