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
//!
//! The `Runtime` type is defined here with its constructor and plain accessors; its methods are
//! spread over files by responsibility:
//! - `apply.rs`: compiling graph text, applying plans, shader reloads;
//! - `scene.rs`: the bound inputs (volume, LUT, textures) and the scene settings (opacity
//!   reference, volume window, cuts);
//! - `submit.rs`: the frame queue — submitting frames, history across frames, frame stats;
//! - `record_frame.rs`: recording one frame's steps (`StepRecorder`);
//! - `outputs.rs`: reading the last frame's outputs back, captures;
//! - `status.rs`: settings and status (step profiling, memory budget, counters, memory held).
//!
//! What a plan becomes on the GPU (nodes, slots, reuse across plans) is [`live_plan`]; what a
//! pass sees when it builds its node is [`create`] (its pipelines: `pipeline.rs`) and when it
//! records is [`record`].

mod apply;
mod bypass;
pub mod create;
mod fingerprint;
pub use volgraph_compiler::reflect;
pub mod footprint;
pub mod frame;
pub mod frames;
pub mod gpu;
pub mod history;
pub mod inputs;
pub mod live_plan;
mod outputs;
mod pipeline;
pub mod present;
pub mod readback;
pub mod record;
mod record_frame;
mod scene;
pub mod shaders;
mod status;
mod step_clock;
mod submit;
pub mod textures;
pub mod uniforms;
pub mod upload;

use std::sync::Arc;

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
pub use gpu::{Gpu, GpuError, GpuFault, GpuFaultKind, GpuOptions, SUBGROUPS_DEFINE};
pub use inputs::{upload_volume_texture, volume_region_bytes, volume_texture_format};
pub use live_plan::{ApplyError, ApplyReport};
pub use present::PresentTarget;
pub use readback::Image;
pub use record::{RecordContext, SystemBindings};
pub use shaders::ShaderLibrary;
pub use status::{HistoryStats, MemoryInUse};
pub use uniforms::UniformBlocks;
pub use upload::{
    UploadError, UploadedVolume, VolumeFormat, VolumeTexels, upload_lut, upload_volume, volume_format_for,
};

use crate::plan::Plan;
use live_plan::LivePlan;
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
    /// The applied plan made live ([`live_plan`]); `None` until a plan is applied.
    live: Option<LivePlan>,
    /// Shader modules edited since the current live plan was built.
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
    /// The scene's lights (`set_lights`).
    lights: volgraph_accel::light::Lights,
    /// The scene's environment map (`set_environment`).
    environment: Option<Arc<volgraph_accel::environment::EnvironmentMap>>,
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
            live: None,
            stale_modules: Vec::new(),
            frame_index: 0,
            history_age: 0,
            history_stats: HistoryStats::default(),
            last_camera: None,
            opacity_reference: OpacityReference::default(),
            window: None,
            cuts: Cuts::NONE,
            lights: volgraph_accel::light::Lights::one(volgraph_accel::light::Light::Headlight),
            environment: None,
            gpu_memory_budget: None,
            profile_steps: false,
            bypasses: bypass::Bypasses::default(),
        }
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
        self.live.as_ref().map(|s| &s.plan)
    }
}
