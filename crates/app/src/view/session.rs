//! The viewer's live session, without a window: a runtime with the scene bound and the graph
//! applied, and every way the graph can change — a file edit (graph, shader, transfer function),
//! a parameter slider, a scene feature or scalar, a resize. Each change recompiles (a pure
//! function) and applies; any failure leaves the last good graph running and becomes an
//! [`Event::Error`] with located diagnostics; the next good change is an [`Event::Recovered`].
//! What the user edits — the graph text and its overrides, the transfer function, the level of
//! detail's step — is the GPU-free [`Workbench`] (`workbench/`): the session asks it for the
//! options of a change, compiles and applies them on the runtime, and tells it once they run.
//! The window (`window.rs`) and the tests drive the same object.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use volgraph_accel::cuts::Cuts;
use volgraph_accel::volume::Volume;
use volgraph_core::graph::edit::SetTarget;
use volgraph_core::runtime::{ApplyReport, CameraData, PresentTarget, Runtime};
use volgraph_core::{CompileOptions, Plan};

use super::workbench::{LodTarget, StepRequest, Workbench};
use crate::inputs;

mod labels;
mod measure;
mod open;
mod save_image;
mod slices;
mod tf;

pub use super::workbench::SAVED_TF;
pub use save_image::MAX_SAVED_SIDE;
pub use tf::SavedTf;

/// What the session reports, one line each on stdout.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// The graph was loaded at start.
    Loaded {
        /// The graph file.
        graph: String,
        /// Milliseconds from reading the file to the plan applied.
        ms: f64,
        /// Steps and slots of the plan.
        summary: String,
    },
    /// Something changed and the new graph is running.
    Reloaded {
        /// What changed (`graph`, `shader raycast.wgsl`, `transfer function`, `parameter march.step_voxels`).
        what: String,
        /// What was rebuilt and reused.
        detail: String,
        /// Milliseconds from noticing the change to the plan applied.
        ms: f64,
    },
    /// A change failed; the last good graph keeps rendering.
    Error {
        /// What changed.
        what: String,
        /// The located diagnostics (file:line:col, the fix).
        message: String,
    },
    /// The first good change after an error.
    Recovered {
        /// What changed.
        what: String,
    },
    /// A file could not be written (a TF, a saved view, the graph's values); nothing else
    /// changed.
    NotSaved {
        /// What was to be saved.
        what: String,
        /// Why, and the path.
        message: String,
    },
    /// The viewer wrote a file (a TF edit saved).
    Saved {
        /// What was saved.
        what: String,
        /// Where.
        path: PathBuf,
    },
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Loaded { graph, ms, summary } => write!(f, "loaded {graph} in {ms:.1} ms ({summary})"),
            Event::Reloaded { what, detail, ms } => write!(f, "reloaded {what} in {ms:.1} ms ({detail})"),
            Event::Error { what, message } => {
                let first = message.lines().next().unwrap_or_default();
                write!(f, "error in {what}: {first}; keeping the last good graph")
            }
            Event::Recovered { what } => write!(f, "recovered: {what} is good again"),
            Event::Saved { what, path } => write!(f, "saved {what} {}", path.display()),
            Event::NotSaved { what, message } => {
                write!(f, "not saved: {what}: {}", message.lines().next().unwrap_or_default())
            }
        }
    }
}

fn describe(report: &ApplyReport) -> String {
    format!(
        "{} nodes kept, {} updated in place, {} built; {} pipelines built, {} reused; {} textures created",
        report.nodes_kept,
        report.nodes_updated,
        report.nodes_created,
        report.pipelines_built,
        report.pipelines_reused,
        report.textures_created
    )
}

fn summary(plan: &Plan) -> String {
    format!("{} steps, {} slots, {} culled", plan.steps.len(), plan.slots.len(), plan.culled.len())
}

/// How the session was started.
#[derive(Clone, Debug)]
pub struct SessionArgs {
    /// The graph file.
    pub graph: PathBuf,
    /// The volume (a file, a DICOM folder or slices; empty: the generated default).
    pub volume: Vec<PathBuf>,
    /// Raw layout options.
    pub raw: volgraph_accel::load::LoadOptions<'static>,
    /// The transfer-function file.
    pub tf: Option<PathBuf>,
    /// A ParaView colour map's name.
    pub tf_map: Option<String>,
    /// The first viewport.
    pub viewport: (u32, u32),
    /// Scene features on at start.
    pub features: Vec<String>,
    /// A shader folder to read (and watch) instead of the built-in shaders.
    pub shaders: Option<PathBuf>,
    /// GPU memory (MiB) a brick pool may hold; None: 2 GiB, bounded by the adapter's 3D texture limit.
    pub gpu_memory_mb: Option<u64>,
    /// Host memory for a streamed store's decoded chunks (`--memory-mb`).
    pub memory_mb: Option<u64>,
    /// A scene supplying the volume and transfer function where `volume` and `tf` are not
    /// given, and its precision and opacity reference.
    pub scene: Option<crate::scene::Scene>,
    /// The crop box and clip planes at start (`--crop`/`--clip` over the scene's).
    pub cuts: Cuts,
    /// The lights at start (`--light` over the scene's).
    pub lights: volgraph_accel::light::Lights,
    /// The environment map's file (`--environment` over the scene's).
    pub environment: Option<PathBuf>,
    /// Volumes bound by name (`--volume NAME=PATH`); `volume` is then the frame volume's path.
    pub named: Vec<(String, PathBuf)>,
    /// Transfer functions and label tables bound by name (`--tf NAME=FILE`).
    pub named_tfs: Vec<(String, PathBuf)>,
}

/// A graph running on a runtime, with everything that can change it.
pub struct LiveSession {
    /// The runtime.
    pub runtime: Runtime,
    /// The graph and transfer function being edited.
    bench: Workbench,
    volume: Volume,
    /// The store a streaming graph reads brick by brick (then `volume` is its coarsest level).
    pyramid: Option<std::sync::Arc<dyn volgraph_accel::pyramid::PyramidSource>>,
    /// The LUT of the transfer function on screen.
    lut: Vec<[f32; 4]>,
    shader_dirs: Vec<PathBuf>,
    /// The last change's error, while it lasts.
    error: Option<(String, String)>,
    /// The graph text and options whose frames last rendered without a GPU error: what a frame
    /// failure falls back to.
    validated: Option<(String, CompileOptions, volgraph_core::runtime::shaders::ShaderSnapshot)>,
    /// True until a frame of the current plan has rendered.
    unproven: bool,
    /// Where the volume came from, for "save view"; `Err`: why "save view" cannot name it.
    volume_source: Result<crate::scene::VolumeSource, String>,
    /// How the volume was read (`--series`, `--frame`, `--dims`, `--spacing`, ...), for "save view".
    volume_options: volgraph_accel::load::LoadOptions<'static>,
    /// What the TF's opacity is per (the scene's).
    opacity_reference: volgraph_core::runtime::OpacityReference,
    /// The label list, when the graph reads a label table.
    labels: Option<super::label_list::LabelList>,
    /// The label map is the frame volume (`multi/labels`): its TF is not what is seen.
    labels_are_the_volume: bool,
    /// The named volume input holding the label map (`None`: the frame volume).
    label_map_input: Option<String>,
    /// Inputs bound by name (`--volume NAME=PATH`, `--tf NAME=…`): rebound on every apply.
    bindings: Option<crate::named_inputs::NamedBindings>,
    /// The environment map's file, for "save view".
    environment: Option<PathBuf>,
    /// A path tracer's error, estimated from its own image at powers of two of samples.
    noise: volgraph_accel::progressive_error::ErrorTracker,
    /// Since when the camera rests (a reprojecting path tracer's estimate counts from there).
    resting: Resting,
    /// The axial, coronal and sagittal panes beside the 3D view, while open.
    slices: Option<crate::view::slice_panes::SlicePanes>,
}

/// The camera of the last frame, the frames it has rested, and how often it moved.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Resting {
    camera: Option<volgraph_accel::camera::OrbitCamera>,
    frames: u64,
    moves: u64,
}

impl LiveSession {
    /// The graph and transfer function being edited.
    pub fn workbench(&self) -> &Workbench {
        &self.bench
    }

    /// The graph and transfer function being edited, to change what needs no device (the TF
    /// editor's "save on change").
    pub fn workbench_mut(&mut self) -> &mut Workbench {
        &mut self.bench
    }

    /// The running plan.
    pub fn plan(&self) -> Option<&Plan> {
        self.runtime.plan()
    }

    /// The current compile options (features, scalars, parameter overrides, viewport).
    pub fn options(&self) -> &CompileOptions {
        self.bench.graph.options()
    }

    /// The error of the last change, while the last good graph runs: (what, message).
    pub fn error(&self) -> Option<&(String, String)> {
        self.error.as_ref()
    }

    /// The shader folders read from disk (and watched), in search order.
    pub fn shader_dirs(&self) -> &[PathBuf] {
        &self.shader_dirs
    }

    /// Every file whose edit changes what is shown: the graph, the transfer function, and every
    /// shader file the running pipelines were built from (imports included).
    pub fn watched_files(&self) -> Vec<PathBuf> {
        let mut files = vec![self.bench.graph.path().to_path_buf()];
        files.extend(self.bench.tf.path().map(Path::to_path_buf));
        files.extend(self.bench.named_tfs.iter().filter_map(|(_, e)| e.path().map(Path::to_path_buf)));
        files.extend(self.runtime.shaders().watched_files());
        files
    }

    /// Compiles `source` with `options` and applies it; the report, or the error message.
    fn compile_and_apply(&mut self, source: &str, options: &CompileOptions) -> Result<ApplyReport, String> {
        let plan = self.bench.graph.plan_for(source, options)?;
        match &self.bindings {
            Some(b) => b.bind(&mut self.runtime, &plan, &self.volume, &self.lut),
            None => self.runtime.bind_scene(&plan.inputs, &self.volume, &self.lut),
        }
        .map_err(|e| e.to_string())?;
        if let Some(p) = &self.pyramid {
            self.runtime.bind_pyramid(volgraph_core::runtime::inputs::PRIMARY_VOLUME, p.clone());
        }
        bind_label_list(&mut self.runtime, &plan.inputs, self.labels.as_ref()).map_err(|e| e.to_string())?;
        self.runtime.apply(plan, self.bench.graph.registry()).map_err(|e| e.to_string())
    }

    /// Compiles the running graph text with `options` and applies it; the change's detail.
    fn apply_options(&mut self, options: &CompileOptions) -> Result<String, String> {
        let source = self.bench.graph.source().to_string();
        self.compile_and_apply(&source, options).map(|r| describe(&r))
    }

    /// Turns a change's outcome into events (an error keeps the last good graph).
    fn outcome(&mut self, what: String, start: Instant, result: Result<String, String>) -> Vec<Event> {
        match result {
            Ok(detail) => {
                self.unproven = true;
                let ms = start.elapsed().as_secs_f64() * 1e3;
                let mut events = vec![Event::Reloaded { what: what.clone(), detail, ms }];
                if self.error.take().is_some() {
                    events.push(Event::Recovered { what });
                }
                events
            }
            Err(message) => {
                self.error = Some((what.clone(), message.clone()));
                vec![Event::Error { what, message }]
            }
        }
    }

    /// The graph file changed: recompile it and apply.
    pub fn reload_graph(&mut self) -> Vec<Event> {
        let start = Instant::now();
        let result = inputs::read_graph(self.bench.graph.path()).map_err(|e| format!("{e:#}")).and_then(|source| {
            let options = self.bench.graph.options().clone();
            let report = self.compile_and_apply(&source, &options)?;
            self.bench.graph.set_source(source);
            Ok(describe(&report))
        });
        self.outcome("graph".to_string(), start, result)
    }

    /// Shader files changed: rebuild exactly the nodes whose pipelines use them.
    pub fn reload_shaders(&mut self, changed: &[PathBuf]) -> Vec<Event> {
        let start = Instant::now();
        let modules = self.runtime.shaders_changed(changed);
        if modules.is_empty() {
            return Vec::new();
        }
        let what = format!("shader {}", modules.join(", "));
        let options = self.bench.graph.options().clone();
        let result = self.apply_options(&options);
        self.outcome(what, start, result)
    }

    /// The panel's "set" field: `PASS.PARAM=VALUE` or `input.NAME=VALUE`, checked as
    /// `volgraph set` checks it ([`GraphEdits::check_assignment`]) — then applied as a slider
    /// would apply it (the file changes only with "write to graph file").
    pub fn assign(&mut self, text: &str) -> Vec<Event> {
        let start = Instant::now();
        match self.bench.graph.check_assignment(text) {
            Err(message) => self.outcome(format!("set {}", text.trim()), start, Err(message)),
            Ok((SetTarget::Param { pass, param }, value)) => self.set_param(&pass, &param, value),
            Ok((SetTarget::Input(name), value)) => match value {
                ron::Value::Number(n) => self.set_scalar(&name, n.into_f64()),
                _ => self.outcome(
                    format!("set {}", text.trim()),
                    start,
                    Err(format!("input.{name}: a Scalar input takes a number, such as 0.5")),
                ),
            },
        }
    }

    /// Writes the parameters and graph inputs changed in the panel into the graph file
    /// ([`GraphEdits::write_back`]), the graph's own step, not the level of detail's wider one.
    pub fn write_back(&mut self) -> anyhow::Result<Vec<String>> {
        self.set_step_factor(1.0);
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        self.bench.graph.write_back(&inputs)
    }

    /// Files changed on disk: the events of reloading what they affect (see
    /// [`GraphEdits::needs_reload`] and [`TfEdits::needs_reload`]).
    pub fn files_changed(&mut self, changed: &[PathBuf]) -> Vec<Event> {
        let mut events = Vec::new();
        if self.bench.graph.needs_reload(changed, self.error.is_some()) {
            events.extend(self.reload_graph());
        }
        if self.bench.tf.needs_reload(changed) {
            events.extend(self.reload_transfer_function());
        }
        events.extend(self.reload_named_transfer_functions(changed));
        let shaders: Vec<PathBuf> =
            changed.iter().filter(|c| c.extension().is_some_and(|e| e == "wgsl")).cloned().collect();
        if !shaders.is_empty() {
            events.extend(self.reload_shaders(&shaders));
        }
        events
    }

    /// Sets a pass parameter (a slider): written in place where the pass allows.
    pub fn set_param(&mut self, pass: &str, param: &str, value: ron::Value) -> Vec<Event> {
        let start = Instant::now();
        let options = self.bench.graph.with_param(pass, param, &value);
        let result = self.apply_options(&options);
        if result.is_ok() {
            self.bench.graph.param_set(pass, param, &value, options);
        }
        self.outcome(format!("parameter {pass}.{param}"), start, result)
    }

    /// Sets a scene scalar (a Scalar graph input).
    pub fn set_scalar(&mut self, name: &str, value: f64) -> Vec<Event> {
        let start = Instant::now();
        let options = self.bench.graph.with_scalar(name, value);
        let result = self.apply_options(&options);
        if result.is_ok() {
            self.bench.graph.scalar_set(name, value, options);
        }
        self.outcome(format!("scalar {name}"), start, result)
    }

    /// Turns a scene feature on or off: gated passes appear and disappear.
    pub fn set_feature(&mut self, name: &str, on: bool) -> Vec<Event> {
        let start = Instant::now();
        let options = self.bench.graph.with_feature(name, on);
        let result = self.apply_options(&options);
        if result.is_ok() {
            self.bench.graph.set_options(options);
        }
        self.outcome(format!("feature {name} {}", if on { "on" } else { "off" }), start, result)
    }

    /// Sets the crop box and clip planes (the panel's sliders, `--crop`/`--clip`, a scene's
    /// `crop:`/`clip:`). Moving a box or plane writes the frame uniforms only; turning a kind of
    /// cut on or off recompiles the raycasters with or without its code.
    pub fn set_cuts(&mut self, cuts: Cuts) -> Vec<Event> {
        let old = self.runtime.cuts();
        if cuts == old {
            return Vec::new();
        }
        let options = self.bench.graph.with_cuts(&cuts);
        self.runtime.set_cuts(cuts);
        if options.features == self.options().features {
            return Vec::new();
        }
        let start = Instant::now();
        let result = self.apply_options(&options);
        if result.is_ok() {
            self.bench.graph.set_options(options);
        } else {
            self.runtime.set_cuts(old);
        }
        let what = match (cuts.crop().is_some(), cuts.planes().next().is_some()) {
            (false, false) => "cuts off",
            (true, false) => "crop",
            (false, true) => "clip",
            (true, true) => "crop and clip",
        };
        self.outcome(what.to_string(), start, result)
    }

    /// The factor the level of detail's step is widened by now (1: the graph's own).
    pub fn step_factor(&self) -> f64 {
        self.bench.graph.step_factor()
    }

    /// The level of detail's step: every pass with a `step_voxels` samples `factor` times further
    /// apart while the camera moves, and a multipass graph's segments (an input wired to
    /// `segment_steps`) get `factor` times longer (1: the graph's own values again, with the
    /// overrides from before; [`super::workbench::StepWidening`]). A graph that refuses the wider
    /// step (a range) just keeps its own; no error is shown for it. Returns whether the step is
    /// now `factor`.
    pub fn set_step_factor(&mut self, factor: f64) -> bool {
        let change = match self.bench.graph.step_request(factor, self.runtime.plan()) {
            StepRequest::Unchanged => return true,
            StepRequest::NoPlan => return false,
            StepRequest::Apply(change) => change,
        };
        let source = self.bench.graph.source().to_string();
        match self.compile_and_apply(&source, &change.options) {
            Ok(_) => {
                self.bench.graph.step_applied(change);
                true
            }
            Err(_) => false,
        }
    }

    /// The window was resized: only viewport-sized targets are reallocated.
    pub fn resize(&mut self, width: u32, height: u32) -> Vec<Event> {
        if (width, height) == self.options().viewport || width == 0 || height == 0 {
            return Vec::new();
        }
        let start = Instant::now();
        let options = self.bench.graph.with_viewport((width, height));
        let result = self.apply_options(&options);
        if result.is_ok() {
            self.bench.graph.set_options(options);
        }
        self.outcome(format!("viewport {width}x{height}"), start, result)
    }

    /// Submits a frame seen by `camera`, presented to `target` when given.
    pub fn submit(
        &mut self,
        camera: &volgraph_accel::camera::OrbitCamera,
        target: Option<&PresentTarget<'_>>,
    ) -> Result<u64, volgraph_core::runtime::RuntimeError> {
        let viewport = self.options().viewport;
        self.runtime.submit(CameraData::from_orbit(camera, viewport), target)
    }

    /// Renders a frame; a GPU error in the frame of a newly applied plan (a validation error
    /// wgpu only reports when the commands run) puts the last plan that rendered back, so the
    /// window is never left blank. The events say what happened; `Err` only when even the last
    /// good plan fails (a lost device).
    pub fn frame(
        &mut self,
        camera: &volgraph_accel::camera::OrbitCamera,
        target: Option<&PresentTarget<'_>>,
    ) -> Result<Vec<Event>, volgraph_core::runtime::RuntimeError> {
        match self.submit(camera, target) {
            Ok(_) => {
                self.track_noise(camera);
                if self.unproven {
                    self.unproven = false;
                    let graph = &self.bench.graph;
                    self.validated =
                        Some((graph.source().to_string(), graph.options().clone(), self.runtime.shader_snapshot()));
                }
                Ok(Vec::new())
            }
            Err(e) => {
                let Some((source, options, shaders)) = self.validated.clone().filter(|_| self.unproven) else {
                    return Err(e);
                };
                // The compiled modules that rendered, not the files: after a shader edit the
                // GPU rejected, the files hold that edit.
                self.runtime.restore_shaders(&shaders);
                let what = "frame".to_string();
                let message = format!("{e}\n(the new graph's frame failed; the last graph that rendered is back)");
                self.error = Some((what.clone(), message.clone()));
                if let Err(revert) = self.compile_and_apply(&source, &options) {
                    return Err(volgraph_core::runtime::RuntimeError::Readback(format!(
                        "{e}; and the last good graph no longer applies: {revert}"
                    )));
                }
                self.bench.graph.set_source(source);
                self.bench.graph.set_options(options);
                self.unproven = false;
                Ok(vec![Event::Error { what, message }])
            }
        }
    }

    /// The output the window shows: `display` when the graph has it, else `image`.
    pub fn shown_output(&self) -> &'static str {
        match self.plan() {
            Some(p) if p.outputs.contains_key("display") => "display",
            _ => "image",
        }
    }
}

/// The level of detail changes the session's viewport and step.
impl LodTarget for LiveSession {
    fn viewport(&self) -> (u32, u32) {
        self.options().viewport
    }

    fn resize(&mut self, width: u32, height: u32) -> Vec<Event> {
        LiveSession::resize(self, width, height)
    }

    fn step_factor(&self) -> f64 {
        LiveSession::step_factor(self)
    }

    fn set_step_factor(&mut self, factor: f64) -> bool {
        LiveSession::set_step_factor(self, factor)
    }

    fn next_frame_index(&self) -> u64 {
        self.runtime.next_frame_index()
    }
}

/// Binds the label list's table to every `LabelTable` input of `inputs` (what `bind_scene` bound
/// there is the default palette).
pub(super) fn bind_label_list(
    runtime: &mut Runtime,
    inputs: &std::collections::BTreeMap<String, volgraph_core::graph::ast::InputKind>,
    list: Option<&super::label_list::LabelList>,
) -> Result<bool, volgraph_core::runtime::RuntimeError> {
    let Some(list) = list else { return Ok(false) };
    let lut = list.lut();
    let mut uploaded = false;
    for (name, kind) in inputs {
        if *kind == volgraph_core::graph::ast::InputKind::LabelTable {
            uploaded |= runtime.bind_label_table(name, &lut)?;
        }
    }
    Ok(uploaded)
}
