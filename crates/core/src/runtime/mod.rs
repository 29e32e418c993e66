//! The live runtime: one object that lives as long as the GPU device and owns everything that
//! outlives a plan — the shader library, the pipeline cache, the texture pool, the named history
//! store, the bound graph inputs and the frames in flight. Plans come and go through
//! [`Runtime::apply`], which reuses every pipeline, texture, history entry and input whose key did
//! not change and keeps the previous plan running when the new one fails. Frames are submitted
//! without waiting ([`Runtime::submit`]); timings come back asynchronously.
//!
//! Data flow: `compile` (pure) → [`Runtime::apply`] (nodes, slots) → per frame
//! [`Runtime::submit`] (frame contract → uniforms, history swap, record every step, optional
//! window blit, submit) → [`Runtime::poll`] / [`Runtime::finish`] (timings) and
//! [`Runtime::read_output`] (readback).

mod bypass;
pub mod create;
pub use volgraph_compiler::reflect;
pub mod footprint;
pub mod frame;
pub mod frames;
pub mod gpu;
pub mod history;
pub mod inputs;
pub mod present;
pub mod readback;
pub mod record;
pub mod schedule;
pub mod shaders;
mod step_clock;
pub mod textures;
pub mod uniforms;
pub mod upload;

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

pub use bypass::BypassStatus;
pub use create::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, DepthSpec, FOOTPRINT_VERTEX, FULLSCREEN_VERTEX, PassError,
    PassPipeline, PipelineCache, PipelineKind, PortInfo, RUNTIME_VERTEX_STAGES, RenderPassPipeline, RenderPipelineSpec,
};
pub use frame::{
    BLOCK_SIZE, CameraData, FOOTPRINT_GROW, FOOTPRINT_WHOLE, FrameData, FrameUniforms, LONGEST_RAY_VOXELS,
    OpacityReference, PixelRays, VolumeDesc, VolumeWindow, WindowBoxes, scene_values_of,
};
pub use frames::{FrameStats, MAX_FRAMES_IN_FLIGHT};
pub use gpu::{Gpu, GpuError, GpuFault, GpuFaultKind, GpuOptions};
pub use inputs::{upload_volume_texture, volume_region_bytes, volume_texture_format};
pub use present::PresentTarget;
pub use readback::Image;
pub use record::{RecordContext, SystemBindings};
pub use schedule::{ApplyError, ApplyReport};
pub use shaders::ShaderLibrary;
pub use uniforms::UniformBlocks;
pub use upload::{
    UploadError, UploadedVolume, VolumeFormat, VolumeTexels, upload_lut, upload_volume, volume_format_for,
};

use crate::diagnostic::Diagnostics;
use crate::graph::ast::InputKind;
use crate::plan::{Binding, Plan, ResourceDesc};
use crate::plugin::{Access, Registry};
use crate::{CompileOptions, compile, cut_effects};
use record::BoundPort;
use schedule::{Schedule, SlotTexture};
use volgraph_accel::cuts::Cuts;

/// Why the runtime could not do what was asked.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// No plan has been applied yet.
    #[error("no graph is loaded; apply a compiled plan first")]
    NoPlan,
    /// Applying a plan failed (the previous plan keeps running).
    #[error(transparent)]
    Apply(#[from] ApplyError),
    /// A pass failed to record.
    #[error(transparent)]
    Pass(#[from] PassError),
    /// The application did not bind a graph input the plan reads.
    #[error("graph input \"{name}\" ({kind}) is not bound; {hint}")]
    UnboundInput {
        /// Input name.
        name: String,
        /// Its kind.
        kind: String,
        /// How to bind it.
        hint: String,
    },
    /// A requested output does not exist.
    #[error("the graph has no output \"{name}\" (it has: {known})")]
    UnknownOutput {
        /// Requested name.
        name: String,
        /// Existing names.
        known: String,
    },
    /// An upload failed.
    #[error(transparent)]
    Upload(#[from] UploadError),
    /// The GPU rejected work (validation, out of memory), with what was being done.
    #[error(transparent)]
    Gpu(#[from] GpuFault),
    /// Reading a result back failed.
    #[error("{0}")]
    Readback(String),
    /// Cuts were set that the applied plan was not compiled with.
    #[error(
        "the scene now cuts the volume ({wanted}) but the plan was applied without it; apply the plan again after Runtime::set_cuts"
    )]
    CutsNotApplied {
        /// The cut features set.
        wanted: String,
    },
    /// A volume window was set that the applied plan was not compiled with.
    #[error(
        "a volume window (sort-last rendering) was set after the plan was applied; apply the plan again after Runtime::set_volume_window"
    )]
    WindowNotApplied,
}

/// Memory the runtime holds, for reports and soak tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryInUse {
    /// Transient targets of the current plan.
    pub transient_bytes: u64,
    /// Free textures kept in the pool.
    pub pooled_free_bytes: u64,
    /// History entries (both textures).
    pub history_bytes: u64,
    /// Bound inputs (volume, LUT).
    pub input_bytes: u64,
    /// Cached pipelines.
    pub pipelines: usize,
    /// Textures created since start.
    pub textures_created: u64,
    /// Bind groups created since the current plan was applied.
    pub bind_groups_created: u64,
}

/// How a graph's history was used (see [`Runtime::history_stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HistoryStats {
    /// Frames that read the previous frame's history instead of its initial value.
    pub frames_from_history: u64,
    /// Consecutive frames up to the last one that read the previous frame's history.
    pub run: u64,
    /// How often history started over after being used (resize, edit, new input, camera jump).
    pub restarts: u64,
}

/// The long-lived runtime.
pub struct Runtime {
    gpu: Arc<Gpu>,
    shaders: ShaderLibrary,
    pipelines: PipelineCache,
    textures: textures::TexturePool,
    history: history::HistoryStore,
    inputs: inputs::InputStore,
    frames: frames::FrameRing,
    blitter: present::Blitter,
    system: SystemBindings,
    schedule: Option<Schedule>,
    /// Shader modules edited since the current schedule was built.
    stale_modules: Vec<String>,
    frame_index: u64,
    history_age: u64,
    history_stats: HistoryStats,
    last_camera: Option<(CameraData, (u32, u32))>,
    /// What the transfer function's opacity is per (a scene setting).
    opacity_reference: OpacityReference,
    window: Option<VolumeWindow>,
    /// The scene's crop box and clip planes.
    cuts: Cuts,
    /// GPU memory passes that stream data may use (`--gpu-memory-mb`); `None`: the adapter's.
    gpu_memory_budget: Option<u64>,
    /// Submit and time every step on its own ([`Runtime::set_step_profiling`]).
    profile_steps: bool,
    /// The applied plan's bypasses: their measures and choices.
    bypasses: bypass::Bypasses,
}

impl Runtime {
    /// A runtime on `gpu` reading shaders from `shaders`.
    pub fn new(gpu: Arc<Gpu>, shaders: ShaderLibrary) -> Self {
        let system = SystemBindings::new(&gpu);
        Self {
            gpu,
            shaders,
            pipelines: PipelineCache::default(),
            textures: textures::TexturePool::default(),
            history: history::HistoryStore::default(),
            inputs: inputs::InputStore::default(),
            frames: frames::FrameRing::default(),
            blitter: present::Blitter::default(),
            system,
            schedule: None,
            stale_modules: Vec::new(),
            frame_index: 0,
            history_age: 0,
            history_stats: HistoryStats::default(),
            last_camera: None,
            opacity_reference: OpacityReference::default(),
            window: None,
            cuts: Cuts::NONE,
            gpu_memory_budget: None,
            profile_steps: false,
            bypasses: bypass::Bypasses::default(),
        }
    }

    /// Times every step of the following frames by wall clock, each submitted on its own and
    /// waited for (`FrameStats::step_gpu_ms` then holds these times, `steps_serialised` says
    /// so): per-pass costs on adapters whose timestamps do not cover compute work (lavapipe).
    /// Serialises the GPU, so the frames themselves get slower.
    pub fn set_step_profiling(&mut self, on: bool) {
        self.profile_steps = on;
    }

    /// The index the next submitted frame gets (`FrameStats::frame_index`).
    pub fn next_frame_index(&self) -> u64 {
        self.frame_index
    }

    /// Whether [`Runtime::set_step_profiling`] is on.
    pub fn step_profiling(&self) -> bool {
        self.profile_steps
    }

    /// Bounds the GPU memory passes that stream data may hold (a brick pool), in bytes; `None`
    /// leaves it to the pass (raycast_bricks: 2 GiB, bounded by the 3D texture limit). Takes
    /// effect with the next frame.
    pub fn set_gpu_memory_budget(&mut self, bytes: Option<u64>) {
        self.gpu_memory_budget = bytes;
    }

    /// Figures the applied plan's passes report about their last frame ([`crate::plugin::PassNode::counters`]),
    /// as `(pass id, name, value)` in step order.
    pub fn pass_counters(&self) -> Vec<(String, &'static str, f64)> {
        let Some(schedule) = &self.schedule else { return Vec::new() };
        let mut out = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for step in &schedule.plan.steps {
            if !seen.insert(step.pass_id.clone()) {
                continue;
            }
            if let Some(entry) = schedule.nodes.get(&step.pass_id) {
                out.extend(entry.node.counters().into_iter().map(|(name, v)| (step.pass_id.clone(), name, v)));
            }
        }
        out
    }

    /// Sets what the transfer function's opacity is per (per voxel by default; per world unit
    /// keeps the look when the resolution changes). Takes effect with the next frame.
    pub fn set_opacity_reference(&mut self, reference: OpacityReference) {
        self.opacity_reference = reference;
    }

    /// What the transfer function's opacity is per.
    pub fn opacity_reference(&self) -> OpacityReference {
        self.opacity_reference
    }

    /// The GPU.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// A shared handle to the GPU.
    pub fn gpu_arc(&self) -> Arc<Gpu> {
        self.gpu.clone()
    }

    /// The shader library.
    pub fn shaders(&self) -> &ShaderLibrary {
        &self.shaders
    }

    /// The pipeline cache (hit and miss counts for reload reports).
    pub fn pipelines(&self) -> &PipelineCache {
        &self.pipelines
    }

    /// The applied plan.
    pub fn plan(&self) -> Option<&Plan> {
        self.schedule.as_ref().map(|s| &s.plan)
    }

    /// The bound volume's description and texture format.
    pub fn volume(&self) -> Option<(VolumeDesc, VolumeFormat)> {
        self.inputs.volume()
    }

    /// Binds a volume to graph input `name` (uploads only new content).
    pub fn bind_volume(&mut self, name: &str, volume: &volgraph_accel::volume::Volume) -> Result<bool, RuntimeError> {
        Ok(self.inputs.bind_volume(&self.gpu, name, volume)?)
    }

    /// Binds a transfer-function LUT to graph input `name` (uploads only new content).
    pub fn bind_lut(&mut self, name: &str, lut: &[[f32; 4]]) -> Result<bool, RuntimeError> {
        Ok(self.inputs.bind_lut(&self.gpu, name, lut)?)
    }

    /// Binds an application-made texture to graph input `name` (a transfer function's is 1D,
    /// one RGBA texel per LUT entry, as `bind_lut` uploads it; a volume's is 3D).
    pub fn bind_texture(&mut self, name: &str, texture: wgpu::Texture) {
        self.inputs.bind_texture(name, texture);
    }

    /// Uploads done since start (a plan change re-uploads nothing).
    pub fn uploads(&self) -> u64 {
        self.inputs.uploads()
    }

    /// Scene values of what is bound, for compiling: the bound volume's
    /// [`LONGEST_RAY_VOXELS`] and [`BLOCK_SIZE`]. Computed in this one place.
    pub fn scene_values(&self) -> BTreeMap<String, f64> {
        self.volume_desc().map(|v| frame::scene_values_of(&v)).unwrap_or_default()
    }

    /// Binds `volume` and `lut` to every graph input of kind Volume and TransferFunction in
    /// `inputs` (a plan's inputs).
    pub fn bind_scene(
        &mut self,
        inputs: &BTreeMap<String, InputKind>,
        volume: &volgraph_accel::volume::Volume,
        lut: &[[f32; 4]],
    ) -> Result<(), RuntimeError> {
        let mut uploaded = false;
        for (name, kind) in inputs {
            match kind {
                InputKind::Volume => uploaded |= self.bind_volume(name, volume)?,
                InputKind::TransferFunction => uploaded |= self.bind_lut(name, lut)?,
                InputKind::Scalar(_) | InputKind::Data(_) => {}
            }
        }
        // What history keeps was computed from the old inputs (Klein et al. 2005 §4.1: a new
        // transfer function restarts from the box).
        if uploaded {
            self.invalidate_history();
        }
        Ok(())
    }

    /// Compiles graph text with the scene values of what is bound (a pure function; nothing is
    /// applied).
    pub fn compile(
        &self,
        file: &str,
        source: &str,
        registry: &Registry,
        options: &CompileOptions,
    ) -> Result<Plan, Diagnostics> {
        let mut options = options.clone();
        for (k, v) in self.scene_values() {
            options.scene.entry(k).or_insert(v);
        }
        compile(file, source, registry, &options)
    }

    /// Makes `plan` the running plan, reusing what did not change; on error the previous plan
    /// keeps running.
    pub fn apply(&mut self, plan: Plan, registry: &Registry) -> Result<ApplyReport, RuntimeError> {
        // The graph's own WGSL-only kinds join the registry for this plan.
        let extended;
        let registry = if plan.kinds.is_empty() {
            registry
        } else {
            extended = crate::wgsl_pass::with_graph_kinds(registry, &plan.kinds);
            &extended
        };
        let viewport_changed = self.plan().is_some_and(|p| p.viewport != plan.viewport);
        let cut_defines = self.frame_defines_for(&plan.features);
        let old = self.schedule.take();
        let resources = schedule::Resources {
            gpu: &self.gpu,
            shaders: &self.shaders,
            pipelines: &self.pipelines,
            textures: &mut self.textures,
            history: &mut self.history,
        };
        match schedule::build(resources, registry, plan, old, &self.stale_modules, &cut_defines) {
            Ok((schedule, report)) => {
                // Klein et al. 2005 §4.1: a resize starts from scratch, and so does a parameter
                // edit of a pass a history entry declares it depends on (an isovalue change).
                let stale = schedule
                    .plan
                    .history
                    .values()
                    .any(|h| h.reset_on_params_of.iter().any(|p| report.changed_passes.contains(p)));
                // A measure taken at another size or with other parameters says nothing now.
                self.bypasses.for_plan(&self.gpu, &schedule.plan, !(viewport_changed || stale));
                self.schedule = Some(schedule);
                self.stale_modules.clear();
                if viewport_changed || stale {
                    self.invalidate_history();
                }
                Ok(report)
            }
            Err((e, old)) => {
                self.schedule = old;
                Err(e.into())
            }
        }
    }

    /// The compiled shader modules now in use ([`ShaderLibrary::snapshot`]): a viewer takes one
    /// when a graph has rendered, to fall back on.
    pub fn shader_snapshot(&self) -> shaders::ShaderSnapshot {
        self.shaders.snapshot()
    }

    /// Puts back the modules of `snapshot` and marks those that differ stale, so the next
    /// [`Self::apply`] rebuilds their nodes from the good modules instead of re-reading an edit
    /// the GPU rejected.
    pub fn restore_shaders(&mut self, snapshot: &shaders::ShaderSnapshot) {
        let changed = self.shaders.restore(snapshot);
        self.stale_modules.extend(changed);
    }

    /// Forgets the cached modules built from `changed` files; the next [`Self::apply`] rebuilds
    /// exactly the nodes whose pipelines use them. Returns the modules affected.
    pub fn shaders_changed(&mut self, changed: &[std::path::PathBuf]) -> Vec<String> {
        let stale = self.shaders.invalidate(changed);
        self.stale_modules.extend(stale.iter().cloned());
        stale
    }

    /// Forgets history: the next frame reads every entry's initial value (resize, transfer
    /// function or isovalue change, camera jump; Klein et al. 2005 §4).
    pub fn invalidate_history(&mut self) {
        self.history.invalidate();
        // What a bypass measured was of the old view, volume or TF.
        self.bypasses.forget(self.frame_index);
        if self.history_age > 0 {
            self.history_stats.restarts += 1;
        }
        self.history_age = 0;
        self.last_camera = None;
    }

    /// How the graph's history has been used: frames that read the previous frame's values
    /// (Klein et al. 2005: frames that ran from reprojected starts) and how often it started
    /// over. Zero for a graph without history.
    pub fn history_stats(&self) -> HistoryStats {
        self.history_stats
    }

    /// Whether `camera` turned further from the last frame's than some history entry allows
    /// (`max_camera_degrees`): a camera jump starts that history over (Klein et al. 2005 §4.1).
    fn camera_jumped(&self, camera: &CameraData) -> bool {
        let (Some(plan), Some((last, _))) = (self.plan(), self.last_camera) else { return false };
        let turned = last.forward.angle_between(camera.forward).to_degrees();
        plan.history.values().any(|h| h.max_camera_degrees.is_some_and(|bound| turned > bound))
    }

    /// Declares the bound volume a window of a larger one (sort-last rendering,
    /// `docs/scaling.md`): rays meet the whole volume's box, samples are taken in the window's
    /// own box only, and cameras given in the whole volume's world are moved to the window's.
    /// `None`: the bound volume is the whole volume.
    pub fn set_volume_window(&mut self, window: Option<VolumeWindow>) {
        if self.window != window {
            self.window = window;
            self.invalidate_history();
        }
    }

    /// Sets the scene's crop box and clip planes (volume fractions of the whole volume,
    /// `volgraph_accel::cuts`). Moving a box or plane takes effect with the next frame; turning
    /// a kind of cut on needs a plan applied after this call (the cut's code is compiled in only
    /// then: `volgraph_compiler::cut_effects`), else the next frame is refused.
    pub fn set_cuts(&mut self, cuts: Cuts) {
        if self.cuts != cuts {
            self.cuts = cuts;
            self.invalidate_history();
        }
    }

    /// The scene's cuts.
    pub fn cuts(&self) -> Cuts {
        self.cuts
    }

    /// The frame `#if` names a plan with `features` is built with (for the passes that honour a
    /// sub-box of the volume): the plan's and the set cuts', and the window's while one is set.
    fn frame_defines_for(&self, features: &std::collections::BTreeSet<String>) -> Vec<&'static str> {
        let mut all = cut_effects::features_of(&self.cuts);
        all.extend(features.iter().cloned());
        cut_effects::frame_defines(&all, self.window.is_some())
    }

    /// The bound volume as the frame contract describes it (windowed when a window is set).
    fn volume_desc(&self) -> Option<VolumeDesc> {
        let (desc, _) = self.inputs.volume()?;
        let desc = match &self.window {
            Some(window) => VolumeDesc::of_window(desc.dims, window),
            None => desc,
        };
        Some(desc.with_opacity_reference(self.opacity_reference))
    }

    /// `camera` (in the whole volume's world) in the bound box's world.
    fn local_camera(&self, camera: CameraData) -> CameraData {
        match self.volume_desc().and_then(|v| v.window) {
            Some(w) => camera.translated(-w.centre_world),
            None => camera,
        }
    }

    /// The frame data the next frame will see for `camera`.
    pub fn frame_data(&self, camera: CameraData) -> Result<FrameData, RuntimeError> {
        let plan = self.plan().ok_or(RuntimeError::NoPlan)?;
        let previous = self.last_camera.filter(|(_, vp)| *vp == plan.viewport).map(|(c, _)| c);
        Ok(FrameData {
            viewport: plan.viewport,
            camera: self.local_camera(camera),
            previous_camera: previous.map(|c| self.local_camera(c)),
            frame_index: self.frame_index,
            history_age: self.history_age,
            volume: self.volume_desc(),
            gpu_memory_budget: self.gpu_memory_budget,
            cuts: self.cuts,
        })
    }

    /// Records and submits one frame seen by `camera`, optionally presenting an output to a
    /// window; returns the frame's index at once (at most [`MAX_FRAMES_IN_FLIGHT`] frames are
    /// queued: a further submit waits for the oldest).
    pub fn submit(&mut self, camera: CameraData, present: Option<&PresentTarget<'_>>) -> Result<u64, RuntimeError> {
        if self.camera_jumped(&camera) {
            self.invalidate_history();
        }
        let frame = self.frame_data(camera)?;
        let Some(schedule) = self.schedule.as_mut() else { return Err(RuntimeError::NoPlan) };
        let wanted = cut_effects::defines_of(&cut_effects::features_of(&self.cuts));
        if !wanted.iter().all(|d| schedule.cut_defines.contains(d)) {
            let wanted = cut_effects::features_of(&self.cuts).into_iter().collect::<Vec<_>>().join(", ");
            return Err(RuntimeError::CutsNotApplied { wanted });
        }
        if self.window.is_some() && !schedule.cut_defines.contains(&cut_effects::WINDOW) {
            return Err(RuntimeError::WindowNotApplied);
        }
        Self::check_inputs_of(&self.inputs, &schedule.plan)?;
        for step in &schedule.plan.steps {
            for bp in &step.ports {
                if let Binding::Input(name) = &bp.binding {
                    self.inputs.ensure_volume_texture(&self.gpu, name)?;
                }
            }
        }
        let gpu = self.gpu.clone();
        let (uniforms, footprint) = FrameUniforms::and_footprint(&frame);
        self.gpu.queue.write_buffer(&self.system.frame, 0, bytemuck::bytes_of(&uniforms));
        let steps = schedule.plan.steps.len();
        // Profiled frames time their steps by wall clock: no timestamp queries to write or resolve.
        let timed_steps = if self.profile_steps { 0 } else { steps };
        let timestamps = self.frames.begin(&gpu, timed_steps);
        let mut clock = self.profile_steps.then(|| step_clock::StepClock::new(&gpu));
        let pixels = u64::from(frame.viewport.0) * u64::from(frame.viewport.1);
        let bypassing = self.bypasses.begin_frame(&gpu, steps, frame.frame_index, pixels);
        let what = format!("frame {} of graph \"{}\"", frame.frame_index, schedule.plan.name);
        let history = &mut self.history;
        let inputs = &self.inputs;
        let system = &self.system;
        let frames = &self.frames;
        let blitter = &mut self.blitter;
        let pipelines = &self.pipelines;
        // A validation error names bindings by number; say which port each number is.
        let named = |mut fault: GpuFault| {
            for line in pipelines.binding_names_in(&fault.message) {
                fault.message.push_str(&format!("\n  {line}"));
            }
            fault
        };
        let commands = gpu
            .checked(
                || what.clone(),
                || -> Result<wgpu::CommandBuffer, RuntimeError> {
                    let mut encoder = gpu
                        .device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&schedule.plan.name) });
                    history.begin_frame(&mut encoder);
                    record_steps(
                        &gpu,
                        schedule,
                        history,
                        inputs,
                        system,
                        (&frame, &footprint),
                        &mut encoder,
                        timestamps.as_ref(),
                        clock.as_mut(),
                        &bypassing,
                    )?;
                    if let Some(clock) = clock.as_mut() {
                        clock.lap(&mut encoder);
                    }
                    if let Some(target) = present {
                        let (view, encoded) = output_view(schedule, history, target.output)?;
                        blitter.record(&gpu, &mut encoder, &view, encoded, target)?;
                    }
                    frames.resolve(&mut encoder, timed_steps);
                    Ok(encoder.finish())
                },
            )
            .map_err(|fault| RuntimeError::from(named(fault)))
            .and_then(|recorded| recorded);
        drop(bypassing);
        let commands = match commands {
            Ok(c) => c,
            Err(e) => {
                self.bypasses.abandoned();
                return Err(e);
            }
        };
        let submitted = Instant::now();
        let submission = match gpu.checked(|| what.clone(), || gpu.queue.submit([commands])) {
            Ok(s) => s,
            Err(fault) => {
                self.bypasses.abandoned();
                return Err(named(fault).into());
            }
        };
        self.bypasses.submitted();
        self.history.end_frame();
        let pass_ids = schedule.pass_ids.clone();
        let profiled = clock.map(|c| c.ms);
        self.frames.submitted(&gpu, submission, frame.frame_index, pass_ids, submitted, profiled);
        schedule.bind_groups.borrow_mut().evict_older_than(frame.frame_index, 8);
        self.last_camera = Some((camera, frame.viewport));
        self.frame_index += 1;
        if frame.history_age > 0 && !schedule.plan.history.is_empty() {
            self.history_stats.frames_from_history += 1;
        }
        self.history_stats.run = frame.history_age;
        self.history_age += 1;
        Ok(frame.frame_index)
    }

    fn check_inputs_of(inputs: &inputs::InputStore, plan: &Plan) -> Result<(), RuntimeError> {
        for (name, kind) in &plan.inputs {
            let used = plan.steps.iter().any(|s| {
                s.ports.iter().any(|p| matches!(&p.binding, Binding::Input(n) | Binding::InputVoxels(n) if n == name))
            });
            if used && !inputs.is_bound(name) {
                let (kind, hint) = match kind {
                    InputKind::Volume => ("Volume", "bind it with Runtime::bind_volume"),
                    InputKind::TransferFunction => ("TransferFunction", "bind the LUT with Runtime::bind_lut"),
                    InputKind::Scalar(_) | InputKind::Data(_) => ("Scalar", "scalars are compile-time scene values"),
                };
                return Err(RuntimeError::UnboundInput {
                    name: name.clone(),
                    kind: kind.to_string(),
                    hint: hint.to_string(),
                });
            }
        }
        Ok(())
    }

    /// Submits a frame and waits for it: its stats.
    pub fn render(&mut self, camera: CameraData) -> Result<FrameStats, RuntimeError> {
        let index = self.submit(camera, None)?;
        let stats = self.finish();
        stats
            .into_iter()
            .find(|s| s.frame_index == index)
            .ok_or_else(|| RuntimeError::Readback(format!("frame {index} finished without stats")))
    }

    /// What each of the plan's bypasses (a graph's `bypass:`) did: left out or not in the last
    /// submitted frame, its newest measure per pixel, frames counted since the plan was applied.
    pub fn bypass_status(&self) -> Vec<BypassStatus> {
        self.bypasses.status()
    }

    /// Stats of the frames the GPU has finished, without blocking.
    pub fn poll(&mut self) -> Vec<FrameStats> {
        self.frames.poll(&self.gpu)
    }

    /// Waits for every frame in flight: their stats, oldest first.
    pub fn finish(&mut self) -> Vec<FrameStats> {
        self.frames.finish(&self.gpu)
    }

    /// Frames submitted and not yet collected.
    pub fn in_flight(&self) -> usize {
        self.frames.in_flight()
    }

    /// Reads back a graph output of the last frame (waits for it).
    pub fn read_output(&mut self, name: &str) -> Result<Image, RuntimeError> {
        let schedule = self.schedule.as_ref().ok_or(RuntimeError::NoPlan)?;
        let Some(&rid) = schedule.plan.outputs.get(name) else {
            return Err(RuntimeError::UnknownOutput {
                name: name.to_string(),
                known: schedule.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
            });
        };
        self.read_resource(rid)
    }

    /// Reads back any target resource of the last frame (valid while its slot was not reused
    /// later in the frame: outputs and the last holder of a slot).
    pub fn read_resource(&mut self, rid: usize) -> Result<Image, RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let schedule = self.schedule.as_ref().ok_or(RuntimeError::NoPlan)?;
        let r = &schedule.plan.resources[rid];
        let (Some(slot), ResourceDesc::Target { format, extent, .. }) = (r.slot, &r.desc) else {
            return Err(RuntimeError::Readback(format!("\"{}\" is not a target", r.name)));
        };
        let texture = match &schedule.slots[slot] {
            SlotTexture::Transient(t) => t.texture.clone(),
            SlotTexture::Buffer(_) => return Err(RuntimeError::Readback(format!("\"{}\" is a buffer", r.name))),
            SlotTexture::History(name) => self
                .history
                .get(name)
                .map(|e| e.current().texture.clone())
                .ok_or_else(|| RuntimeError::Readback(format!("history \"{name}\" is gone")))?,
        };
        readback::read_texture(&self.gpu, &texture, *format, *extent).map_err(RuntimeError::Readback)
    }

    /// What a window of `format` and `size` shows of `output` after the last frame: the same
    /// blit, drawn into an offscreen texture and read back as `format`'s bytes (a screenshot
    /// without the overlay). Waits for the frame.
    pub fn capture(
        &mut self,
        output: &str,
        format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> Result<Vec<u8>, RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let schedule = self.schedule.as_ref().ok_or(RuntimeError::NoPlan)?;
        let (source, encoded) = output_view(schedule, &self.history, output)?;
        let texture = self.gpu.checked(
            || format!("creating a {}x{} {format:?} capture", size.0, size.1),
            || {
                self.gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("capture"),
                    size: wgpu::Extent3d { width: size.0.max(1), height: size.1.max(1), depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            },
        )?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let target = PresentTarget { view: &view, format, size, output };
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("capture") });
        self.blitter.record(&self.gpu, &mut encoder, &source, encoded, &target)?;
        self.gpu.queue.submit([encoder.finish()]);
        readback::read_texture_bytes(&self.gpu, &texture).map_err(RuntimeError::Readback)
    }

    /// Reads back the bytes of a buffer output of the last frame (waits for it).
    pub fn read_buffer_output(&mut self, name: &str) -> Result<Vec<u8>, RuntimeError> {
        let schedule = self.schedule.as_ref().ok_or(RuntimeError::NoPlan)?;
        let rid = *schedule.plan.outputs.get(name).ok_or_else(|| RuntimeError::UnknownOutput {
            name: name.to_string(),
            known: schedule.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
        })?;
        self.read_buffer_resource(rid)
    }

    /// Reads back the bytes of buffer resource `rid` after the last frame (valid while its slot
    /// was not reused later in the frame; a pass's unread output keeps its slot).
    pub fn read_buffer_resource(&mut self, rid: usize) -> Result<Vec<u8>, RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let schedule = self.schedule.as_ref().ok_or(RuntimeError::NoPlan)?;
        let name = schedule.plan.resources.get(rid).map_or_else(String::new, |r| r.name.clone());
        match schedule.plan.resources[rid].slot.map(|s| &schedule.slots[s]) {
            Some(SlotTexture::Buffer(b)) => {
                readback::read_buffer(&self.gpu, &b.buffer, 0, b.size).map_err(RuntimeError::Readback)
            }
            _ => Err(RuntimeError::Readback(format!("\"{name}\" is not a buffer"))),
        }
    }

    /// Memory held, for reports and soak tests.
    pub fn memory(&self) -> MemoryInUse {
        MemoryInUse {
            transient_bytes: self.plan().map_or(0, |p| p.memory().pooled_bytes),
            pooled_free_bytes: self.textures.free_bytes(),
            history_bytes: self.history.bytes(),
            input_bytes: self.inputs.bytes(),
            pipelines: self.pipelines.len(),
            textures_created: self.textures.created(),
            bind_groups_created: self.schedule.as_ref().map_or(0, |s| s.bind_groups.borrow().created()),
        }
    }
}

/// The view of output `name` and whether it holds sRGB-encoded values (an 8-bit target).
fn output_view(
    schedule: &Schedule,
    history: &history::HistoryStore,
    name: &str,
) -> Result<(wgpu::TextureView, bool), RuntimeError> {
    let Some(&rid) = schedule.plan.outputs.get(name) else {
        return Err(RuntimeError::UnknownOutput {
            name: name.to_string(),
            known: schedule.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
        });
    };
    let r = &schedule.plan.resources[rid];
    let (Some(slot), ResourceDesc::Target { format, .. }) = (r.slot, &r.desc) else {
        return Err(RuntimeError::Readback(format!("output \"{name}\" is not a target")));
    };
    let view = match &schedule.slots[slot] {
        SlotTexture::Transient(t) => t.view.clone(),
        SlotTexture::Buffer(_) => return Err(RuntimeError::Readback(format!("output \"{name}\" is a buffer"))),
        SlotTexture::History(h) => history
            .get(h)
            .map(|e| e.current().view.clone())
            .ok_or_else(|| RuntimeError::Readback(format!("history \"{h}\" is gone")))?,
    };
    Ok((view, *format == crate::format::TargetFormat::Rgba8Unorm))
}

#[allow(clippy::too_many_arguments, reason = "the frame's parts, each borrowed separately")]
fn record_steps(
    gpu: &Gpu,
    schedule: &mut Schedule,
    history: &history::HistoryStore,
    inputs: &inputs::InputStore,
    system: &SystemBindings,
    (frame, footprint): (&FrameData, &footprint::Footprint),
    encoder: &mut wgpu::CommandEncoder,
    timestamps: Option<&(wgpu::QuerySet, u32)>,
    mut clock: Option<&mut step_clock::StepClock<'_>>,
    bypassing: &bypass::FrameBypass<'_>,
) -> Result<(), RuntimeError> {
    let Schedule { plan, nodes, slots, owned, bind_groups, skippable, owned_versions, next_version, .. } = schedule;
    for (i, step) in plan.steps.iter().enumerate() {
        // Profiling: what came before this step is done before its clock starts.
        if let Some(clock) = clock.as_deref_mut() {
            clock.lap(encoder);
        }
        // A pass that runs only when its inputs change: the versions of what it reads (None when
        // it reads something made every frame).
        let read_versions = if skippable[i] { input_versions(plan, step, inputs, owned_versions) } else { None };
        let mut ports = Vec::with_capacity(step.ports.len());
        for bp in &step.ports {
            let mut buffer = None;
            let (mut voxels, mut table) = (None, None);
            let version = match &bp.binding {
                Binding::Input(name) | Binding::InputVoxels(name) => inputs.version(name),
                Binding::Resource { id, .. } if matches!(plan.resources[*id].desc, ResourceDesc::Owned(_)) => {
                    owned_versions.get(&plan.resources[root_owned(plan, *id)].name).copied()
                }
                _ => None,
            };
            let (view, extent) = match &bp.binding {
                Binding::Resource { id, written } => {
                    let rid = if bp.access == Access::Modify { written.unwrap_or(*id) } else { *id };
                    let r = &plan.resources[rid];
                    let extent = match &r.desc {
                        ResourceDesc::Target { extent, .. } => Some(*extent),
                        ResourceDesc::Buffer { .. } | ResourceDesc::Owned(_) => None,
                    };
                    let view = match r.slot {
                        Some(s) => match &slots[s] {
                            SlotTexture::Transient(t) => Some(&t.view),
                            SlotTexture::Buffer(b) => {
                                buffer = Some(&b.buffer);
                                None
                            }
                            SlotTexture::History(name) => history.get(name).map(|e| &e.current().view),
                        },
                        None => owned.get(&root_owned(plan, rid)),
                    };
                    (view, extent)
                }
                Binding::Input(name) => {
                    table = inputs.table(name);
                    (inputs.get(name).map(|t| &t.view), None)
                }
                Binding::InputVoxels(name) => {
                    voxels = inputs.voxels(name);
                    (None, None)
                }
                Binding::History(name) => (history.get(name).map(|e| &e.previous().view), None),
                Binding::Unbound => (None, None),
            };
            let zeroed = bp.access == Access::Read
                && matches!(bp.binding, Binding::Resource { id, .. }
                    if bypassing.left_out.get(plan.resources[id].producer).copied().unwrap_or(false));
            ports.push(BoundPort {
                zeroed,
                name: bp.port.clone(),
                access: bp.access,
                view,
                buffer,
                extent,
                version,
                voxels,
                table,
            });
        }
        let entry = nodes.get_mut(&step.pass_id).ok_or_else(|| ApplyError::UnknownKind(step.kind.clone()))?;
        let outputs_published = step.ports.iter().all(|bp| match &bp.binding {
            Binding::Resource { id, .. } if bp.access == Access::Write => owned.contains_key(id),
            _ => true,
        });
        let unchanged = read_versions.is_some() && read_versions == entry.last_inputs && outputs_published;
        let left_out = bypassing.left_out.get(i).copied().unwrap_or(false);
        if left_out {
            // A graph's bypass leaves this step out: what the running steps read of it is zero.
            bypass::clear_for_left_out(plan, i, encoder, |rid| match plan.resources[rid].slot.map(|s| &slots[s]) {
                Some(SlotTexture::Transient(t)) => (Some(t.view.clone()), None),
                Some(SlotTexture::Buffer(b)) => (None, Some(b.buffer.clone())),
                _ => (None, None),
            });
        }
        let mut ctx = RecordContext {
            gpu,
            encoder,
            label: &step.label,
            iteration: step.iteration,
            params: &step.params,
            viewport: plan.viewport,
            frame,
            footprint,
            ports,
            system,
            timestamps: timestamps.map(|(set, base)| (set, base + 2 * i as u32)),
            began_pass: false,
            bind_groups,
        };
        if unchanged || left_out {
            // Nothing it reads changed (its Owned outputs still hold what it wrote), or a
            // bypass leaves it out. An empty pass keeps the step's label and timestamps.
            drop(ctx.begin_compute_pass());
            continue;
        }
        entry.node.record(&mut ctx)?;
        // A bypass's measure leaves its pooled slot for a read-back buffer right away.
        for &(_, rid, readback, bytes) in bypassing.copies.iter().filter(|c| c.0 == i) {
            if let Some(SlotTexture::Buffer(b)) = plan.resources[rid].slot.map(|s| &slots[s]) {
                encoder.copy_buffer_to_buffer(&b.buffer, 0, readback, 0, bytes);
            }
        }
        entry.last_inputs = read_versions;
        for bp in &step.ports {
            if let Binding::Resource { id, .. } = &bp.binding
                && bp.access != Access::Read
                && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
            {
                owned_versions.insert(plan.resources[root_owned(plan, *id)].name.clone(), *next_version);
                *next_version += 1;
            }
        }
        // Owned outputs created or replaced while recording (sized by a graph input).
        for bp in &step.ports {
            if let Binding::Resource { id, written: None } = &bp.binding
                && bp.access == Access::Write
                && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
            {
                let view = entry.node.owned_output(&bp.port).ok_or_else(|| PassError {
                    pass: step.label.clone(),
                    message: format!("declares owned output \"{}\" but its node provides no texture for it", bp.port),
                })?;
                owned.insert(*id, view);
            }
        }
    }
    Ok(())
}

/// Versions of what `step` reads — graph inputs' content, Owned resources' versions, 0 for an
/// unwired port — or `None` when it reads a transient target or history, which change every
/// frame.
fn input_versions(
    plan: &Plan,
    step: &crate::plan::Step,
    inputs: &inputs::InputStore,
    owned_versions: &HashMap<String, u64>,
) -> Option<Vec<u64>> {
    let mut versions = Vec::new();
    for bp in step.ports.iter().filter(|bp| bp.access != Access::Write) {
        versions.push(match &bp.binding {
            Binding::Input(name) | Binding::InputVoxels(name) => inputs.version(name).unwrap_or(0),
            Binding::Resource { id, .. } if matches!(plan.resources[*id].desc, ResourceDesc::Owned(_)) => {
                owned_versions.get(&plan.resources[root_owned(plan, *id)].name).copied().unwrap_or(0)
            }
            Binding::Unbound => 0,
            Binding::Resource { .. } | Binding::History(_) => return None,
        });
    }
    Some(versions)
}

/// The resource an Owned value's chain starts at (Modify ports on owned resources keep the
/// producer's texture).
fn root_owned(plan: &Plan, mut rid: usize) -> usize {
    while let Some(prev) = plan.resources[rid].modifies {
        rid = prev;
    }
    rid
}
