//! [`Renderer`]: a graph kept on a GPU with its inputs — volume, transfer function, parameters,
//! effects, cuts, light, a scene — compiled and bound again only when one of them changed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::anyhow;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::Cuts;
use volgraph_accel::light::{Light, Lights};
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Gpu, OpacityReference, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, Plan, Registry};

use super::{ApiError, Camera, Rendered};
use crate::scene::Scene;

/// The transfer function a renderer classifies with.
#[derive(Clone, Debug, Default)]
pub enum TfChoice {
    /// The scene's, where a scene gives one; else the one fitted to the data (`--tf` left out).
    #[default]
    Fitted,
    /// A preset (`ct-bone`), a file, or a data-folder TF by name, as `--tf` takes it.
    Named(PathBuf),
    /// A transfer function made in memory.
    Function(TransferFunction),
}

/// A graph on a GPU with its inputs: set a volume, a transfer function, parameters, effects,
/// cuts and the light; render. The GPU state (pipelines, textures) stays between renders; a
/// change recompiles only what it touches, as in the viewer.
pub struct Renderer {
    graph: PathBuf,
    source: String,
    registry: Registry,
    size: (u32, u32),
    runtime: Runtime,
    volume: Option<Volume>,
    /// A store a streaming graph reads brick by brick ([`Self::stream`]); `volume` is then its
    /// coarsest level.
    pyramid: Option<Arc<dyn volgraph_accel::pyramid::PyramidSource>>,
    /// How long a frame of a streaming graph may refine before it is returned (`None`: until
    /// the rays lack nothing).
    time_budget: Option<std::time::Duration>,
    /// A generated Marschner–Lobb volume: the default TF is the band showing its rings.
    ring_tf: bool,
    tf: TfChoice,
    lut: Option<Vec<[f32; 4]>>,
    /// The transfer function the LUT was made from.
    tf_used: Option<TransferFunction>,
    overrides: BTreeMap<String, ron::Value>,
    scalars: BTreeMap<String, f64>,
    /// `--features`: effects asked for by the caller (a name the graph lacks is an error).
    features: Vec<String>,
    cuts: Cuts,
    lights: Lights,
    /// `--scene`: its effects (those the graph lacks left out, with a note), TF, camera, volume,
    /// opacity reference and precision, under what the caller sets.
    scene: Option<Scene>,
    /// Other volume inputs by name (`--volume NAME=PATH`: a PET as `pet`, a label map as
    /// `labels`), the set volume being the input `volume`.
    others: Vec<(String, Volume)>,
    /// Transfer-function or label-table inputs by name (`--tf NAME=FILE|PRESET`).
    named_tfs: Vec<(String, PathBuf)>,
    /// Notes of the last compile (an effect left out, a TF's repair), for the caller to show.
    notes: Vec<String>,
    /// The plan applied, or `None` once something it was compiled from changed.
    plan: Option<Plan>,
}

impl Renderer {
    /// Graph `graph` (a file or a built-in name, `modern/fastest`) at `size` pixels on a new
    /// headless GPU.
    pub fn new(graph: &Path, size: (u32, u32)) -> Result<Self, ApiError> {
        let gpu = Arc::new(Gpu::new_headless().map_err(ApiError::gpu)?);
        Self::on(gpu, graph, size)
    }

    /// [`Self::new`] on an existing GPU (several renderers share one device).
    pub fn on(gpu: Arc<Gpu>, graph: &Path, size: (u32, u32)) -> Result<Self, ApiError> {
        if size.0 == 0 || size.1 == 0 || size.0 > 16384 || size.1 > 16384 {
            return Err(ApiError::Input(anyhow!("size {}x{}: 1 to 16384 pixels a side", size.0, size.1)));
        }
        let source = crate::inputs::read_graph(graph)?;
        let (sources, _) = crate::shader_dir::sources_for(graph, None);
        let runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
        let mut renderer = Self {
            graph: graph.to_path_buf(),
            source,
            registry: crate::program::registry(),
            size,
            runtime,
            volume: None,
            pyramid: None,
            time_budget: None,
            ring_tf: false,
            tf: TfChoice::Fitted,
            lut: None,
            tf_used: None,
            overrides: BTreeMap::new(),
            scalars: BTreeMap::new(),
            features: Vec::new(),
            cuts: Cuts::NONE,
            lights: Lights::default(),
            scene: None,
            others: Vec::new(),
            named_tfs: Vec::new(),
            notes: Vec::new(),
            plan: None,
        };
        // The graph is checked now (without a volume's scene values), so a broken file fails here.
        let check =
            Volume::new("check", glam::UVec3::ONE, glam::DVec3::ONE, volgraph_accel::volume::VoxelData::U8(vec![0]));
        renderer.compile(&check)?;
        Ok(renderer)
    }

    /// A scene file (`scenes/*.ron`, or a built-in scene's name) on `gpu`, as `--scene` reads
    /// it: its graph unless `graph` names another, its viewport unless `size` is given (else
    /// 512×512), its volume until one is set, and its TF, camera, effects, cuts, light, opacity
    /// reference and precision under what the caller sets.
    pub fn from_scene(
        gpu: Arc<Gpu>,
        scene: &Path,
        graph: Option<&Path>,
        size: Option<(u32, u32)>,
    ) -> Result<Self, ApiError> {
        let scene = Scene::load_named(scene).map_err(|e| ApiError::Input(anyhow!(e)))?;
        let graph = match (graph, scene.graph.as_deref()) {
            (Some(g), _) | (None, Some(g)) => g.to_path_buf(),
            (None, None) => {
                return Err(ApiError::Input(anyhow!(
                    "{}: the scene names no graph; give one (Renderer(graph, scene=…))",
                    scene.path.display()
                )));
            }
        };
        let size = size.or(scene.viewport).unwrap_or((512, 512));
        let mut renderer = Self::on(gpu, &graph, size)?;
        renderer.cuts = scene.cuts;
        renderer.lights = scene.lights;
        renderer.runtime.set_opacity_reference(scene.opacity_reference);
        renderer.scene = Some(scene);
        Ok(renderer)
    }

    /// The volume to render (its transfer function refitted unless one was set);
    /// `marschner_lobb_tf`: a generated Marschner–Lobb volume, whose default TF is the band that
    /// shows its rings (`scene::ShownVolume::marschner_lobb_tf`).
    pub fn set_volume(&mut self, volume: Volume, marschner_lobb_tf: bool) {
        self.pyramid = None;
        self.volume = Some(volume);
        self.ring_tf = marschner_lobb_tf;
        self.lut = None;
        self.plan = None;
    }

    /// The OME-Zarr store `path` (the volume `frame` picks, N = t·C + c), read brick by brick
    /// by a streaming graph (`streaming/ray_guided`) as `volgraph render` reads it: decoded
    /// chunks held within `memory_mb` MiB (default 512); a render waits for the full image (or
    /// [`Self::set_time_budget`]). A volume file larger than `memory_mb` is streamed from the
    /// file (`zarr_input::stream_file`), a smaller one read in core. Another graph is an error
    /// saying to load the store in core.
    pub fn stream(&mut self, path: &Path, frame: Option<u64>, memory_mb: Option<u64>) -> Result<(), ApiError> {
        if !crate::zarr_input::graph_streams(&self.source) {
            return Err(ApiError::Input(anyhow!(
                "{}: graph \"{}\" reads its volume whole; a store is streamed brick by brick by streaming/ray_guided \
                 (or load it in core: volgraph.load)",
                path.display(),
                self.graph.display()
            )));
        }
        if path.is_dir() && !volgraph_zarr::is_zarr(path) {
            return Err(ApiError::Input(anyhow!(
                "{}: not an OME-Zarr store (a folder with zarr.json or .zgroup)",
                path.display()
            )));
        }
        if let Some(mb) = memory_mb.filter(|mb| !(16..=1 << 24).contains(mb)) {
            return Err(ApiError::Input(anyhow!("memory_mb {mb}: 16 to 16777216 MiB, as --memory-mb")));
        }
        let options = volgraph_accel::load::LoadOptions { frame, ..Default::default() };
        let streamed = if volgraph_zarr::is_zarr(path) {
            crate::zarr_input::stream(path, &options, memory_mb)?
        } else {
            // A volume file: streamed from the file when its voxels exceed the budget, else
            // read in core as `volume = path` reads it (it fits).
            match crate::zarr_input::stream_file(path, &options, memory_mb, |_| ())? {
                Some(streamed) => streamed,
                None => {
                    let shown = crate::scene::load_shown_volume(&[path.to_path_buf()], None, &options)?;
                    self.notes.extend(shown.notes);
                    self.notes.push(format!("{}: fits in memory_mb: read in core", path.display()));
                    self.set_volume(shown.volume, shown.marschner_lobb_tf);
                    return Ok(());
                }
            }
        };
        self.notes.extend(streamed.notes);
        self.set_volume(streamed.coarsest, false);
        self.pyramid = Some(streamed.source);
        Ok(())
    }

    /// The volume file, folder or name `path`, as `--volume PATH` reads it: an OME-Zarr store,
    /// or a file over the default memory budget, is streamed where the graph streams
    /// ([`Self::stream`], `zarr_input::stream_file`), anything else is loaded whole.
    pub fn set_volume_path(&mut self, path: &Path, frame: Option<u64>) -> Result<(), ApiError> {
        let streams = crate::zarr_input::graph_streams(&self.source);
        if volgraph_zarr::is_zarr(path) && streams {
            return self.stream(path, frame, None);
        }
        let options = volgraph_accel::load::LoadOptions { frame, ..Default::default() };
        // A file over the memory budget is streamed from the file, as `--volume` does; a graph
        // that holds its volume whole refuses one too large to read.
        if streams && let Some(streamed) = crate::zarr_input::stream_file(path, &options, None, |_| ())? {
            self.notes.extend(streamed.notes);
            self.set_volume(streamed.coarsest, false);
            self.pyramid = Some(streamed.source);
            return Ok(());
        }
        if !streams {
            crate::zarr_input::refuse_large_file(path, &options)?;
        }
        let shown = crate::scene::load_shown_volume(&[path.to_path_buf()], None, &options)?;
        self.notes.extend(shown.notes);
        self.set_volume(shown.volume, shown.marschner_lobb_tf);
        Ok(())
    }

    /// How long a render of a streaming graph may go on refining (`None`: until complete).
    pub fn set_time_budget(&mut self, budget: Option<std::time::Duration>) {
        self.time_budget = budget;
    }

    /// Binds the graph's volume input `name` (`--volume NAME=PATH`: `pet` of `multi/pet_ct`,
    /// `labels` of `multi/ct_with_labels`) to `volume`; `volume` itself is [`Self::set_volume`]'s.
    /// Its `NAME_tf` input is fitted to it unless [`Self::set_named_tf`] names one. Checked at
    /// the next frame: an input the graph lacks, or a volume outside the frame volume's patient
    /// frame, is an error naming it.
    pub fn set_named_volume(&mut self, name: &str, volume: Volume) {
        self.others.retain(|(n, _)| n != name);
        self.others.push((name.to_string(), volume));
        self.plan = None;
    }

    /// Binds the transfer-function or label-table input `name` (`--tf NAME=FILE|PRESET`).
    pub fn set_named_tf(&mut self, name: &str, tf: PathBuf) {
        self.named_tfs.retain(|(n, _)| n != name);
        self.named_tfs.push((name.to_string(), tf));
        self.plan = None;
    }

    /// The volume set (or the scene's, once a frame loaded it), if any.
    pub fn volume(&self) -> Option<&Volume> {
        self.volume.as_ref()
    }

    /// The transfer function (as `--tf`; [`TfChoice::Fitted`] leaves the scene's or fits one).
    pub fn set_tf(&mut self, tf: TfChoice) {
        self.tf = tf;
        self.lut = None;
    }

    /// Sets `PASS.PARAM` or `input.NAME` (a Scalar input) to `value`, checked when the graph is
    /// next compiled (an unknown name or a value out of range is an error then, named).
    pub fn set(&mut self, key: &str, value: ron::Value) -> Result<(), ApiError> {
        match key.strip_prefix("input.") {
            Some(name) => {
                let v = match &value {
                    ron::Value::Number(n) => n.into_f64(),
                    _ => return Err(ApiError::Input(anyhow!("{key}: an input takes a number"))),
                };
                self.scalars.insert(name.to_string(), v);
            }
            None if key.contains('.') => {
                self.overrides.insert(key.to_string(), value);
            }
            None => return Err(ApiError::Input(anyhow!("{key}: write PASS.PARAM or input.NAME"))),
        }
        self.plan = None;
        Ok(())
    }

    /// The effects that are on (`--features`: shading, preintegration, jitter, tricubic,
    /// shadows…), besides the scene's; checked at the next frame (a name the graph lacks is an
    /// error naming the ones it has).
    pub fn set_features(&mut self, features: Vec<String>) {
        self.features = features;
        self.plan = None;
    }

    /// The crop box and clip planes (`--crop`, `--clip`; they replace the scene's). A kind of
    /// cut turned on or off recompiles the graph; moving one does not.
    pub fn set_cuts(&mut self, cuts: Cuts) {
        let kinds = |c: &Cuts| volgraph_core::cut_effects::features_of(c);
        if kinds(&cuts) != kinds(&self.cuts) {
            self.plan = None;
        }
        self.cuts = cuts;
    }

    /// One light (`--light`; it replaces the scene's).
    pub fn set_light(&mut self, light: Light) {
        self.lights = light.into();
    }

    /// Up to three lights (`--light` repeated; they replace the scene's).
    pub fn set_lights(&mut self, lights: Lights) {
        self.lights = lights;
    }

    /// The notes of the last compile: a scene's effect the graph does not offer, a TF repaired,
    /// a volume the TF hides — what the command line prints on stderr.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    fn compile(&mut self, volume: &Volume) -> Result<Plan, ApiError> {
        let scene_effects = self.scene.as_ref().map(|s| s.effects.clone()).unwrap_or_default();
        let mut features = scene_effects.clone();
        features.extend(self.features.iter().cloned());
        features.extend(volgraph_core::cut_effects::features_of(&self.cuts));
        let mut options = CompileOptions::new(self.size.0, self.size.1).with_features(features);
        options.precision = self.scene.as_ref().and_then(|s| s.precision);
        options.scalars = self.scalars.clone();
        options.param_overrides = self.overrides.clone();
        options.scene = scene_values_of(&match &self.pyramid {
            Some(p) => VolumeDesc::of_box(p.levels()[0].dims, p.spacing()),
            None => VolumeDesc::of(volume),
        });
        options.scene.extend(crate::inputs::data_scene_values(volume));
        let file = crate::cli::display_name(&self.graph);
        let plan = volgraph_core::compile(&file, &self.source, &self.registry, &options)
            .map_err(crate::cli::CliError::Graph)?;
        // A scene's effect the graph does not offer is a note; the caller's own is checked.
        let mut user = options.clone();
        user.features.retain(|f| {
            let scene_only = scene_effects.contains(f) && !self.features.contains(f);
            if scene_only && !plan.known_features.contains(f) {
                self.notes.push(format!(
                    "note: graph \"{}\" does not offer the scene's effect \"{f}\"; it is left out",
                    plan.name
                ));
                return false;
            }
            true
        });
        crate::cli::check_user_names(&plan, &user)?;
        Ok(plan)
    }

    /// The scene's volume, loaded at the first frame that needs it.
    fn load_scene_volume(&mut self) -> Result<(), ApiError> {
        if self.volume.is_some() {
            return Ok(());
        }
        let Some(scene) = self.scene.as_ref() else {
            return Err(ApiError::Input(anyhow!("no volume: set one before rendering")));
        };
        let shown = crate::scene::load_shown_volume(&[], Some(scene), &volgraph_accel::load::LoadOptions::default())?;
        self.notes.extend(shown.notes);
        self.set_volume(shown.volume, shown.marschner_lobb_tf);
        Ok(())
    }

    /// Loads what is missing, fits the LUT and compiles, binds and applies the plan where
    /// something changed. Returns the plan.
    fn prepare(&mut self) -> Result<&Plan, ApiError> {
        self.load_scene_volume()?;
        let Some(volume) = self.volume.take() else {
            return Err(ApiError::Input(anyhow!("no volume: set one before rendering")));
        };
        let prepared = self.prepare_for(&volume);
        self.volume = Some(volume);
        prepared?;
        self.plan.as_ref().ok_or_else(|| ApiError::Input(anyhow!("internal: no plan")))
    }

    fn prepare_for(&mut self, volume: &Volume) -> Result<(), ApiError> {
        if self.lut.is_none() {
            let tf = match (&self.tf, &self.scene) {
                (TfChoice::Function(tf), _) => tf.clone(),
                (TfChoice::Named(path), _) => {
                    let (tf, notes) = crate::inputs::transfer_function(Some(path), None, volume, self.ring_tf)?;
                    self.notes.extend(notes);
                    tf
                }
                (TfChoice::Fitted, Some(scene)) => {
                    let (tf, _, notes) = crate::scene::load_transfer_function(scene, None, volume, self.ring_tf)?;
                    self.notes.extend(notes);
                    tf
                }
                (TfChoice::Fitted, None) => crate::inputs::transfer_function(None, None, volume, self.ring_tf)?.0,
            };
            tf.validate(Path::new("the transfer function")).map_err(|e| ApiError::Input(anyhow!(e)))?;
            self.lut = Some(tf.to_lut_for(volume, crate::inputs::LUT_SIZE));
            self.tf_used = Some(tf);
            self.plan = None;
        }
        if self.plan.is_none() {
            self.notes.clear();
            let plan = self.compile(volume)?;
            self.runtime.set_cuts(self.cuts);
            self.bind(&plan, volume)?;
            self.runtime.apply(plan.clone(), &self.registry).map_err(ApiError::gpu)?;
            self.plan = Some(plan);
        }
        self.runtime.set_cuts(self.cuts);
        self.runtime.set_lights(self.lights);
        Ok(())
    }

    /// The viewport, (width, height) pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The transfer function the next frame classifies with: the one set, the scene's, or the
    /// one fitted to the volume.
    pub fn transfer_function(&mut self) -> Result<TransferFunction, ApiError> {
        self.prepare()?;
        self.tf_used.clone().ok_or_else(|| ApiError::Input(anyhow!("internal: no transfer function")))
    }

    /// The camera [`Camera::Default`] names: the scene's, the anterior view for a volume in the
    /// patient frame, else 30°, 20°, 3.2.
    pub fn default_camera(&mut self) -> Result<OrbitCamera, ApiError> {
        self.load_scene_volume()?;
        self.orbit(&Camera::Default)
    }

    /// Binds `plan`'s inputs as `volgraph render` does: by name where volumes or TFs are named
    /// or the graph reads a label table, else `volume` and the LUT to every input of their kind.
    fn bind(&mut self, plan: &Plan, volume: &Volume) -> Result<(), ApiError> {
        let lut = self.lut.clone().unwrap_or_default();
        let named: Vec<(String, PathBuf)> = match self.others.is_empty() {
            true => Vec::new(),
            false => std::iter::once(volgraph_core::runtime::inputs::PRIMARY_VOLUME.to_string())
                .chain(self.others.iter().map(|(n, _)| n.clone()))
                .map(|n| (n, PathBuf::new()))
                .collect(),
        };
        let plain_tf = match &self.tf {
            TfChoice::Named(path) => Some(path.clone()),
            _ => None,
        };
        let bindings = crate::render::named_bindings(
            plan,
            (&named, 0, None),
            self.others.clone(),
            (&self.named_tfs, plain_tf.as_ref()),
            volume,
            None,
        )?;
        self.notes.extend(crate::render::unnamed_volume_notes(plan, &named));
        match bindings {
            Some((bindings, notes)) => {
                self.notes.extend(notes);
                let file = crate::cli::display_name(&self.graph);
                self.notes.extend(bindings.check(plan, &file, &self.source, volume)?);
                bindings.bind(&mut self.runtime, plan, volume, &lut)
            }
            None => self.runtime.bind_scene(&plan.inputs, volume, &lut),
        }
        .map_err(ApiError::gpu)?;
        if let Some(p) = &self.pyramid {
            self.runtime.bind_pyramid(volgraph_core::runtime::inputs::PRIMARY_VOLUME, p.clone());
        }
        Ok(())
    }

    /// The orbit camera `camera` names for the volume set.
    fn orbit(&self, camera: &Camera) -> Result<OrbitCamera, ApiError> {
        let volume = self.volume.as_ref().ok_or_else(|| ApiError::Input(anyhow!("no volume")))?;
        let scene_camera = self.scene.as_ref().and_then(|s| s.camera.as_ref()).map(|c| c.at(0));
        camera.orbit(volume, scene_camera)
    }

    /// Renders one frame of `camera` and reads `output` (default: `display` where the graph has
    /// it, else `image`). Waits for the GPU.
    pub fn render(&mut self, camera: &Camera, output: Option<&str>) -> Result<Rendered, ApiError> {
        let plan = self.prepare()?;
        let output = match output {
            Some(name) => name.to_string(),
            None if plan.outputs.contains_key("display") => "display".to_string(),
            None => "image".to_string(),
        };
        let Some(&resource) = plan.outputs.get(&output) else {
            let known: Vec<&str> = plan.outputs.keys().map(String::as_str).collect();
            return Err(ApiError::Input(anyhow!("output \"{output}\": the graph's outputs are {}", known.join(", "))));
        };
        let srgb = matches!(
            plan.resources[resource].desc,
            volgraph_core::plan::ResourceDesc::Target { format: volgraph_core::TargetFormat::Rgba8Unorm, .. }
        );
        let viewport = plan.viewport;
        let orbit = self.orbit(camera)?;
        let started = std::time::Instant::now();
        self.runtime.render(CameraData::from_orbit(&orbit, viewport)).map_err(ApiError::gpu)?;
        // A streaming graph: frames at this camera until the rays lack nothing (or the budget).
        if !crate::stream_progress::StreamProgress::of(&self.runtime.pass_counters()).is_empty() {
            let camera = CameraData::from_orbit(&orbit, viewport);
            crate::stream_progress::refine_runtime(&mut self.runtime, camera, started, self.time_budget, |_| ())
                .map_err(ApiError::gpu)?;
        }
        if srgb {
            let (width, height, bytes) = self.runtime.read_output_rgba8(&output).map_err(ApiError::gpu)?;
            return Ok(Rendered::Srgb8 { width, height, bytes });
        }
        Ok(Rendered::Linear(self.runtime.read_output(&output).map_err(ApiError::gpu)?))
    }

    /// The converged f64 reference of this frame (`docs/rendering_model.md`): the graph's
    /// raycast model — its mode, effects and shading, the cuts and light — integrated at
    /// `step_voxels` (or the graph's step where finer) with lossless termination and no jitter;
    /// premultiplied linear RGBA, rows from the top, as the `image` output. The error of
    /// `render(camera, Some("image"))` against it is the accuracy `volgraph sweep` measures.
    pub fn reference(&mut self, camera: &Camera, step_voxels: f64) -> Result<Vec<[f64; 4]>, ApiError> {
        if !(step_voxels.is_finite() && step_voxels > 0.0) {
            return Err(ApiError::Input(anyhow!("step_voxels {step_voxels}: a step > 0 in voxels (0.1 converges)")));
        }
        let plan = self.prepare()?;
        let Some(march) = plan.steps.iter().find(|s| s.params.declares("step_voxels")) else {
            return Err(ApiError::Input(anyhow!(
                "graph \"{}\" has no raycast step (none declares step_voxels), so there is no ray integral to converge; \
                 a reference is made for the raycasters (modern/fastest, basic/fragment_raycast, the papers' graphs)",
                plan.name
            )));
        };
        if volgraph_passes::fusion::FusionSettings::of(&march.params).combine().is_some() {
            return Err(ApiError::Input(anyhow!(
                "graph \"{}\" marches several volumes; the reference here is of one volume's march",
                plan.name
            )));
        }
        let graph_settings = volgraph_passes::raycast_params::reference_settings(&march.params);
        let (width, height) = plan.viewport;
        let orbit = self.orbit(camera)?;
        let (Some(volume), Some(lut)) = (self.volume.as_ref(), self.lut.as_ref()) else {
            return Err(ApiError::Input(anyhow!("no volume")));
        };
        let settings = volgraph_accel::reference::RaycastSettings {
            step_voxels: step_voxels.min(graph_settings.step_voxels),
            threshold: 1.0,
            jitter: false,
            max_steps: u32::MAX,
            cuts: self.cuts,
            lights: self.lights,
            opacity_unit_voxels: match self.runtime.opacity_reference() {
                OpacityReference::World => 1.0 / volume.unit_step_world(),
                OpacityReference::Voxel => 1.0,
            },
            ..graph_settings
        };
        let image = volgraph_accel::reference::render_reference(volume, lut, &orbit, width, height, &settings);
        Ok(image.color)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_renderer_may_move_between_threads() {
        fn send<T: Send>() {}
        send::<super::Renderer>();
    }
}
