//! The wgpu executor: opens the GPU, builds each pass's pipelines (checking shader bindings
//! against ports by name), allocates the plan's pooled targets and runs frames.

pub mod context;
pub mod frame_uniforms;
pub mod gpu;
pub mod readback;
pub mod reflect;
pub mod run;
pub mod shaders;
pub mod upload;

pub use context::{
    ComputePipelineSpec, CreateContext, DepthSpec, PassError, PassPipeline, PipelineKind, PortInfo, RecordContext,
    RenderPipelineSpec,
};
pub use frame_uniforms::FrameUniforms;
pub use gpu::{Gpu, GpuError, GpuFault, GpuFaultKind, GpuOptions};
pub use readback::Image;
pub use run::{Executor, ExecutorError, FrameStats};
pub use shaders::ShaderLibrary;
pub use upload::{
    UploadError, UploadedVolume, VolumeFormat, VolumeTexels, upload_lut, upload_volume, volume_format_for,
};
