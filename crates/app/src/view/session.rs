//! The viewer's live session, without a window: a runtime with the scene bound and the graph
//! applied, and every way the graph can change — a file edit (graph, shader, transfer function),
//! a parameter slider, a scene feature or scalar, a resize. Each change recompiles (a pure
//! function) and applies; any failure leaves the last good graph running and becomes an
//! [`Event::Error`] with located diagnostics; the next good change is an [`Event::Recovered`].
//! The window (`window.rs`) and the tests drive the same object.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::anyhow;
use volgraph_accel::cuts::Cuts;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;
use volgraph_core::graph::edit::{SetTarget, apply as apply_edits, edit_for};
use volgraph_core::runtime::{ApplyReport, CameraData, Gpu, PresentTarget, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Plan, Registry, cut_effects};

use crate::inputs;

mod tf;

use tf::{HISTOGRAM_BINS, scanner_preset_named, tf_presets_for};
pub use tf::{SAVED_TF, SavedTf};

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
    /// A scene supplying the volume and transfer function where `volume` and `tf` are not
    /// given, and its precision and opacity reference.
    pub scene: Option<crate::scene::Scene>,
    /// The crop box and clip planes at start (`--crop`/`--clip` over the scene's).
    pub cuts: Cuts,
}

/// A graph running on a runtime, with everything that can change it.
pub struct LiveSession {
    /// The runtime.
    pub runtime: Runtime,
    registry: Registry,
    graph: PathBuf,
    graph_name: String,
    /// The text of the graph that is running.
    source: String,
    tf_path: Option<PathBuf>,
    tf_map: Option<String>,
    volume: Volume,
    lut: Vec<[f32; 4]>,
    generated: bool,
    options: CompileOptions,
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
    /// Where the TF came from, for "save view" (`None`: fitted to the data).
    tf_source: Option<crate::scene::TfSource>,
    /// The TF as its source gives it (the file's, the preset's, the fitted one): the TF on
    /// screen differs from it after an edit that is not saved.
    tf_pristine: TransferFunction,
    /// What the TF's opacity is per (the scene's).
    opacity_reference: volgraph_core::runtime::OpacityReference,
    /// The transfer function on screen (the TF editor's).
    tf: TransferFunction,
    /// Voxels per bin of the volume's normalized values (the TF editor's histogram).
    histogram: Vec<u64>,
    /// The text this viewer last wrote to the TF file: the watcher's event for it is not a
    /// reload.
    tf_written: Option<String>,
    /// Save the TF file after every edit (the panel's toggle).
    pub save_tf_on_change: bool,
    /// The TF editor's presets for this volume (computed once: MR's reads percentiles).
    tf_presets: Vec<(&'static str, TransferFunction)>,
    /// While the level of detail widens the step: the factor and the overrides from before it
    /// (restored when it ends).
    coarse_step: Option<(f64, StepBase)>,
}

/// What the level of detail's step replaces: the parameter overrides and graph scalars from
/// before it, and the graph's own spacing of each pass it widens by parameter (`PASS.PARAM`,
/// taken from the plan at factor 1, so a ×2 → ×4 change widens the graph's value, not ×2's).
#[derive(Clone)]
struct StepBase {
    params: std::collections::BTreeMap<String, ron::Value>,
    scalars: std::collections::BTreeMap<String, f64>,
    steps: Vec<(String, f64)>,
}

/// The sample spacings the level of detail widens in every pass that declares one: a
/// raycaster's step, a slicer's slice distance.
const STEP_PARAMS: [&str; 2] = ["step_voxels", "slice_voxels"];

/// The parameters the level of detail widens where a graph input feeds them: the step, and a
/// multipass raycaster's segment length (Krüger & Westermann 2003 §3's M), whose pass count —
/// and so the per-pass fixed cost that dominates a small coarse image — falls with it.
const WIDENED_PARAMS: [&str; 2] = ["step_voxels", "segment_steps"];

/// The graph inputs wired into a parameter of [`WIDENED_PARAMS`] (`"step_voxels":
/// "input.NAME"`), and the ids of the passes whose `step_voxels` they feed. Widening such an
/// input, not each pass's parameter, also shortens what is computed from it — a
/// Krüger–Westermann repeat group's segment count.
fn step_inputs(source: &str) -> (std::collections::BTreeSet<String>, std::collections::BTreeSet<String>) {
    let (mut inputs, mut passes) = (std::collections::BTreeSet::new(), std::collections::BTreeSet::new());
    let Ok(doc) = volgraph_core::graph::parse_graph(source) else { return (inputs, passes) };
    let all = doc.passes.iter().flat_map(|node| match node {
        volgraph_core::graph::ast::NodeDoc::Pass(p) => std::slice::from_ref(p).iter(),
        volgraph_core::graph::ast::NodeDoc::Repeat(r) => r.body.iter(),
    });
    for pass in all {
        for param in WIDENED_PARAMS {
            if let Some(ron::Value::String(wire)) = pass.params.get(param)
                && let Some(name) = wire.strip_prefix("input.")
            {
                inputs.insert(name.to_string());
                if param == "step_voxels" {
                    passes.insert(pass.id.clone());
                }
            }
        }
    }
    (inputs, passes)
}

impl LiveSession {
    /// Loads the scene and the graph on `gpu`; fails (with located diagnostics) when the graph
    /// does not compile or build at all.
    pub fn open(gpu: Arc<Gpu>, args: &SessionArgs) -> Result<(Self, Event), crate::cli::CliError> {
        Self::open_with(gpu, args, crate::program::registry())
    }

    /// [`Self::open`] with another registry (built-ins plus a plugin crate's kinds).
    pub fn open_with(
        gpu: Arc<Gpu>,
        args: &SessionArgs,
        registry: Registry,
    ) -> Result<(Self, Event), crate::cli::CliError> {
        let start = Instant::now();
        let source = inputs::read_graph(&args.graph)?;
        let shown = crate::scene::load_shown_volume(&args.volume, args.scene.as_ref(), &args.raw)?;
        let (volume, generated, notes) = (shown.volume, shown.marschner_lobb_tf, shown.notes);
        for note in notes {
            crate::stdout::eprintln_escaped!("note: {note}");
        }
        let (tf, tf_path, tf_notes) = match (&args.tf, &args.scene) {
            (None, Some(scene)) => {
                crate::scene::load_transfer_function(scene, args.tf_map.as_deref(), &volume, generated)?
            }
            (tf, _) => {
                let (t, notes) = inputs::transfer_function(tf.as_ref(), args.tf_map.as_deref(), &volume, generated)?;
                // A preset's or a built-in TF's name is no file: nothing to watch, and "save TF"
                // writes elsewhere.
                let file =
                    |p: &PathBuf| scanner_preset_named(p).is_none() && crate::builtin_graphs::find_tf(p).is_none();
                (t, tf.clone().filter(file), notes)
            }
        };
        let tf_source = match (&args.tf, &args.scene) {
            (None, Some(scene)) => scene.transfer_function.clone(),
            (None, None) => None,
            (Some(p), _) => Some(match scanner_preset_named(p) {
                Some(name) => crate::scene::TfSource::Preset(name.to_string()),
                None => crate::scene::TfSource::File(p.display().to_string()),
            }),
        };
        for note in tf_notes {
            crate::stdout::eprintln_escaped!("note: {note}");
        }
        let lut = tf.to_lut_for(&volume, inputs::LUT_SIZE);
        let histogram = volgraph_accel::histogram::Histogram::of(&volume, HISTOGRAM_BINS).counts;
        let tf_presets = tf_presets_for(&volume);
        let (sources, _) = crate::shader_dir::sources_for(&args.graph, args.shaders.as_deref());
        // Every folder read (and so watched), in search order: the start line and the panel name
        // all of them, not just the first.
        let shader_dirs: Vec<PathBuf> = sources.disk_roots().into_iter().map(Path::to_path_buf).collect();
        let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
        runtime.set_gpu_memory_budget(args.gpu_memory_mb.map(|mb| mb << 20));
        let mut options = CompileOptions::new(args.viewport.0, args.viewport.1)
            .with_features(args.features.iter().filter(|f| !f.is_empty()).cloned());
        options.features.extend(cut_effects::features_of(&args.cuts));
        runtime.set_cuts(args.cuts);
        if let Some(scene) = &args.scene {
            options.features.extend(scene.effects.iter().cloned());
            options.precision = scene.precision;
            runtime.set_opacity_reference(scene.opacity_reference);
        }
        let graph_name = args.graph.display().to_string();
        let plan =
            compile_for(&graph_name, &source, &registry, &options, &volume).map_err(crate::cli::CliError::Graph)?;
        // A scene's effect the graph does not offer is left out with a note; a --features typo is
        // an error.
        if let Some(scene) = &args.scene {
            for effect in &scene.effects {
                if !plan.known_features.contains(effect) && !args.features.contains(effect) {
                    crate::stdout::eprintln_escaped!(
                        "note: graph \"{}\" does not offer the scene's effect \"{effect}\"; it is left out",
                        plan.name
                    );
                    options.features.remove(effect);
                }
            }
        }
        crate::cli::check_user_names(&plan, &options)?;
        if let Some(note) = crate::render::budget_note(&plan, &registry, args.gpu_memory_mb) {
            crate::stdout::eprintln_escaped!("{note}");
        }
        let shaders = match shader_dirs.as_slice() {
            [] => "built-in shaders".to_string(),
            dirs => format!(
                "shaders from {} (watched), then the built-in ones",
                dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
            ),
        };
        let loaded = format!("{}, {shaders}", summary(&plan));
        runtime.bind_scene(&plan.inputs, &volume, &lut).map_err(|e| crate::cli::CliError::Other(anyhow!(e)))?;
        runtime.apply(plan, &registry).map_err(|e| crate::cli::CliError::Other(anyhow!(e)))?;
        let session = Self {
            runtime,
            registry,
            graph: args.graph.clone(),
            graph_name: graph_name.clone(),
            source,
            tf_path,
            tf_map: args.tf_map.clone(),
            volume,
            lut,
            generated,
            options,
            shader_dirs,
            error: None,
            validated: None,
            unproven: true,
            volume_source: shown.source,
            volume_options: shown.options,
            tf_source,
            tf_pristine: tf.clone(),
            tf,
            histogram,
            tf_written: None,
            save_tf_on_change: false,
            tf_presets,
            coarse_step: None,
            opacity_reference: args.scene.as_ref().map(|s| s.opacity_reference).unwrap_or_default(),
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        Ok((session, Event::Loaded { graph: graph_name, ms, summary: loaded }))
    }

    /// The running plan.
    pub fn plan(&self) -> Option<&Plan> {
        self.runtime.plan()
    }

    /// The registry (for parameter specs).
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The current compile options (features, scalars, parameter overrides, viewport).
    pub fn options(&self) -> &CompileOptions {
        &self.options
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
        let mut files = vec![self.graph.clone()];
        files.extend(self.tf_path.clone());
        files.extend(self.runtime.shaders().watched_files());
        files
    }

    /// Compiles `source` with `options` and applies it; the report, or the error message.
    fn compile_and_apply(&mut self, source: &str, options: &CompileOptions) -> Result<ApplyReport, String> {
        let plan =
            compile_for(&self.graph_name, source, &self.registry, options, &self.volume).map_err(|d| d.to_string())?;
        crate::cli::check_user_names(&plan, options).map_err(|e| match e {
            crate::cli::CliError::Graph(d) => d.to_string(),
            crate::cli::CliError::Other(e) => e.to_string(),
        })?;
        self.runtime.bind_scene(&plan.inputs, &self.volume, &self.lut).map_err(|e| e.to_string())?;
        self.runtime.apply(plan, &self.registry).map_err(|e| e.to_string())
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
        let result = inputs::read_graph(&self.graph).map_err(|e| format!("{e:#}")).and_then(|source| {
            let options = self.options.clone();
            let report = self.compile_and_apply(&source, &options)?;
            self.source = source;
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
        let source = self.source.clone();
        let options = self.options.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        self.outcome(what, start, result)
    }

    /// What lies under window pixel `cursor` (physical pixels) seen by `camera`: the first
    /// visible point along its ray (the TF, the crop and clip planes as drawn) and the data value
    /// there, as a line for the panel in the data's units; `None` off the volume.
    pub fn probe_line(&self, camera: &volgraph_accel::camera::OrbitCamera, cursor: (f64, f64)) -> Option<String> {
        let (w, h) = self.options.viewport;
        if !(cursor.0 >= 0.0 && cursor.1 >= 0.0) {
            return None;
        }
        let pixel = (cursor.0 as u32, cursor.1 as u32);
        let cuts = self.runtime.cuts();
        let p = volgraph_accel::probe::first_visible(&self.volume, &self.lut, camera, (w, h), pixel, 0.5, &cuts)?;
        let units = self.volume.meta.units.as_deref().map_or(String::new(), |u| format!(" {u}"));
        Some(format!(
            "under the cursor: {:.4}{units} at voxel ({:.1}, {:.1}, {:.1}), α {:.2}",
            p.value, p.voxel.x, p.voxel.y, p.voxel.z, p.alpha
        ))
    }

    /// A comparison of the view on screen (the last frame's `image`) with the converged
    /// reference, for a worker thread; `None` for a graph without a float `image` output or a
    /// raycaster (`march`) to take the settings from.
    pub fn accuracy_job(&mut self, camera: &volgraph_accel::camera::OrbitCamera) -> Option<super::accuracy::Job> {
        let plan = self.plan()?;
        let march = plan.steps.iter().find(|s| s.pass_id == "march" && s.params.declares("step_voxels"))?;
        let mut settings = volgraph_passes::raycast_params::reference_settings(&march.params);
        settings.opacity_unit_voxels = match self.opacity_reference {
            volgraph_core::runtime::OpacityReference::World => 1.0 / self.volume.unit_step_world(),
            volgraph_core::runtime::OpacityReference::Voxel => 1.0,
        };
        let size = plan.viewport;
        let image = self.runtime.read_output("image").ok()?;
        if (image.width, image.height) != size || image.channels != 4 {
            return None;
        }
        Some(super::accuracy::Job {
            image: image.to_rgba_f64(),
            size,
            volume: self.volume.clone(),
            lut: self.lut.clone(),
            camera: *camera,
            settings,
            cuts: self.runtime.cuts(),
        })
    }

    /// The panel's "set" field: `PASS.PARAM=VALUE` or `input.NAME=VALUE`, checked as
    /// `volgraph set` checks it — the graph text with the value written in must compile, so a
    /// bad value or an unknown name is refused with its located message (and a "did you mean")
    /// — then applied as a slider would apply it (the file changes only with "write to graph
    /// file").
    pub fn assign(&mut self, text: &str) -> Vec<Event> {
        let start = Instant::now();
        match self.check_assignment(text) {
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

    fn check_assignment(&self, text: &str) -> Result<(SetTarget, ron::Value), String> {
        let Some((target, value)) = text.split_once('=') else {
            return Err(format!("\"{}\": expected PASS.PARAM=VALUE or input.NAME=VALUE", text.trim()));
        };
        let target = SetTarget::parse(target.trim())?;
        let edits = edit_for(&self.source, &target, value)?;
        let edited = apply_edits(&self.source, &edits);
        // The panel's own value for this name would hide the one being checked.
        let mut options = self.options.clone();
        match &target {
            SetTarget::Param { pass, param } => options.param_overrides.remove(&format!("{pass}.{param}")),
            SetTarget::Input(name) => options.scalars.remove(name).map(ron::Value::from),
        };
        compile_for(&self.graph_name, &edited, &self.registry, &options, &self.volume).map_err(|d| d.to_string())?;
        let value = ron::from_str::<ron::Value>(value.trim()).map_err(|e| format!("{}: {e}", value.trim()))?;
        Ok((target, value))
    }

    /// Writes the parameters and graph inputs changed in the panel into the graph file at their
    /// place (`volgraph set`'s code: only the values' text changes), then runs from the file:
    /// the panel's overrides are cleared, as the file now says what they said. Returns one line
    /// per value written; an error (a built-in graph, an unwritable file) changes nothing.
    pub fn write_back(&mut self) -> anyhow::Result<Vec<String>> {
        // The level of detail's wider step is not the user's: the graph's own values are written.
        self.set_step_factor(1.0);
        let mut assignments: Vec<String> = Vec::new();
        for (key, value) in &self.options.param_overrides {
            let text = ron::to_string(value).map_err(|e| anyhow!("{key}: {e}"))?;
            assignments.push(format!("{key}={text}"));
        }
        let plan_inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        for (name, value) in &self.options.scalars {
            if plan_inputs.contains_key(name) {
                assignments.push(format!("input.{name}={value:?}"));
            }
        }
        if assignments.is_empty() {
            return Ok(Vec::new());
        }
        let lines =
            crate::set_cmd::run(&self.graph, &assignments).map_err(|e| anyhow!("{}", crate::cli::error_text(&e)))?;
        self.source = inputs::read_graph(&self.graph)?;
        self.options.param_overrides.clear();
        self.options.scalars.retain(|name, _| !plan_inputs.contains_key(name));
        Ok(lines.lines().map(str::to_string).collect())
    }

    /// Files changed on disk: the events of reloading what they affect. A graph file whose text
    /// is the running one (the viewer's own write-back) is not reloaded, unless the last change
    /// failed (then the same text is the fix, and reloading it recovers).
    pub fn files_changed(&mut self, changed: &[PathBuf]) -> Vec<Event> {
        let same =
            |a: &Path, b: &Path| a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
        let mut events = Vec::new();
        if changed.iter().any(|c| same(c, &self.graph))
            // (Read without blocking: a FIFO swapped in for the graph must not freeze the viewer.)
            && (self.error().is_some()
                || volgraph_accel::input_file::read_text(&self.graph, "graph file").map_or(true, |text| text != self.source))
        {
            events.extend(self.reload_graph());
        }
        if let Some(tf) = self.tf_path.clone()
            && changed.iter().any(|c| same(c, &tf))
            // The viewer's own save is not an edit to reload.
            && (self.tf_written.is_none()
                || volgraph_accel::input_file::read_text(&tf, "transfer function").ok() != self.tf_written)
        {
            events.extend(self.reload_transfer_function());
        }
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
        let mut options = self.options.clone();
        options.param_overrides.insert(format!("{pass}.{param}"), value.clone());
        let source = self.source.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        if result.is_ok() {
            self.options = options;
            // Kept when the level of detail's step ends; a spacing the user sets is the new own one.
            if let Some((_, base)) = &mut self.coarse_step {
                let key = format!("{pass}.{param}");
                if let (Some(entry), ron::Value::Number(n)) = (base.steps.iter_mut().find(|(k, _)| *k == key), &value) {
                    entry.1 = n.into_f64();
                }
                base.params.insert(key, value);
            }
        }
        self.outcome(format!("parameter {pass}.{param}"), start, result)
    }

    /// Sets a scene scalar (a Scalar graph input).
    pub fn set_scalar(&mut self, name: &str, value: f64) -> Vec<Event> {
        let start = Instant::now();
        let mut options = self.options.clone();
        options.scalars.insert(name.to_string(), value);
        let source = self.source.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        if result.is_ok() {
            self.options = options;
            // Kept when the level of detail's step ends.
            if let Some((_, base)) = &mut self.coarse_step {
                base.scalars.insert(name.to_string(), value);
            }
        }
        self.outcome(format!("scalar {name}"), start, result)
    }

    /// Turns a scene feature on or off: gated passes appear and disappear.
    pub fn set_feature(&mut self, name: &str, on: bool) -> Vec<Event> {
        let start = Instant::now();
        let mut options = self.options.clone();
        if on {
            options.features.insert(name.to_string());
        } else {
            options.features.remove(name);
        }
        let source = self.source.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        if result.is_ok() {
            self.options = options;
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
        let mut options = self.options.clone();
        options.features.retain(|f| !cut_effects::is_cut_feature(f));
        options.features.extend(cut_effects::features_of(&cuts));
        self.runtime.set_cuts(cuts);
        if options.features == self.options.features {
            return Vec::new();
        }
        let start = Instant::now();
        let source = self.source.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        if result.is_ok() {
            self.options = options;
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
        self.coarse_step.as_ref().map_or(1.0, |(f, _)| *f)
    }

    /// The level of detail's step: every pass with a `step_voxels` samples `factor` times further
    /// apart while the camera moves, and a multipass graph's segments (an input wired to
    /// `segment_steps`) get `factor` times longer (1: the graph's own values again, with the
    /// overrides from before). A graph that refuses the wider step (a range) just keeps its own; no error is
    /// shown for it. Returns whether the step is now `factor`.
    pub fn set_step_factor(&mut self, factor: f64) -> bool {
        let current = self.coarse_step.as_ref().map_or(1.0, |(f, _)| *f);
        if factor == current {
            return true;
        }
        let (inputs, fed) = step_inputs(&self.source);
        let base = match &self.coarse_step {
            Some((_, base)) => base.clone(),
            None => {
                // At factor 1: the plan holds the graph's own (or the user's) spacings.
                let Some(plan) = self.plan() else { return false };
                let mut steps: Vec<(String, f64)> = Vec::new();
                for step in &plan.steps {
                    for param in STEP_PARAMS {
                        let key = format!("{}.{param}", step.pass_id);
                        let fed_by_input = param == "step_voxels" && fed.contains(&step.pass_id);
                        if step.params.declares(param)
                            && (!fed_by_input || self.options.param_overrides.contains_key(&key))
                            && !steps.iter().any(|(k, _)| *k == key)
                        {
                            steps.push((key, step.params.float(param)));
                        }
                    }
                }
                StepBase { params: self.options.param_overrides.clone(), scalars: self.options.scalars.clone(), steps }
            }
        };
        let mut options = self.options.clone();
        options.param_overrides = base.params.clone();
        options.scalars = base.scalars.clone();
        if factor != 1.0 {
            let Some(plan) = self.plan() else { return false };
            for name in &inputs {
                let own = match plan.inputs.get(name) {
                    Some(volgraph_core::graph::ast::InputKind::Scalar(default)) => *default,
                    _ => continue,
                };
                let step = base.scalars.get(name).copied().unwrap_or(own);
                options.scalars.insert(name.clone(), step * factor);
            }
            for (key, own) in &base.steps {
                options
                    .param_overrides
                    .insert(key.clone(), ron::Value::Number(ron::value::Number::F64((own * factor).into())));
            }
        }
        let source = self.source.clone();
        match self.compile_and_apply(&source, &options) {
            Ok(_) => {
                self.options = options;
                self.coarse_step = (factor != 1.0).then_some((factor, base));
                true
            }
            Err(_) => false,
        }
    }

    /// The window was resized: only viewport-sized targets are reallocated.
    pub fn resize(&mut self, width: u32, height: u32) -> Vec<Event> {
        if (width, height) == self.options.viewport || width == 0 || height == 0 {
            return Vec::new();
        }
        let start = Instant::now();
        let mut options = self.options.clone();
        options.viewport = (width, height);
        let source = self.source.clone();
        let result = self.compile_and_apply(&source, &options).map(|r| describe(&r));
        if result.is_ok() {
            self.options = options;
        }
        self.outcome(format!("viewport {width}x{height}"), start, result)
    }

    /// Submits a frame seen by `camera`, presented to `target` when given.
    pub fn submit(
        &mut self,
        camera: &volgraph_accel::camera::OrbitCamera,
        target: Option<&PresentTarget<'_>>,
    ) -> Result<u64, volgraph_core::runtime::RuntimeError> {
        let viewport = self.options.viewport;
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
                if self.unproven {
                    self.unproven = false;
                    self.validated = Some((self.source.clone(), self.options.clone(), self.runtime.shader_snapshot()));
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
                self.source = source;
                self.options = options;
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

/// Compiles `source` with the scene values of `volume` (its longest ray: computed in one place,
/// `volgraph_core::runtime::scene_values_of`).
fn compile_for(
    file: &str,
    source: &str,
    registry: &Registry,
    options: &CompileOptions,
    volume: &Volume,
) -> Result<Plan, volgraph_core::Diagnostics> {
    let mut options = options.clone();
    options.scene = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(volume));
    options.scene.extend(crate::inputs::data_scene_values(volume));
    volgraph_core::compile(file, source, registry, &options)
}
