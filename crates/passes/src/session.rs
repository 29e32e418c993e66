//! A compiled graph wired to CPU scene data: what the CLI, the benchmarks and the end-to-end
//! tests use to go from (graph file, volume, transfer function, camera) to images.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::Volume;
use volgraph_core::executor::{Executor, ExecutorError, FrameStats, Gpu, Image, ShaderLibrary};
use volgraph_core::graph::ast::InputKind;
use volgraph_core::{CompileOptions, Diagnostics, Plan, Registry, compile};

use crate::scene::{frame_uniforms, upload_lut_texture, upload_volume_texture};

/// Why a session could not be set up or run.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The graph file has problems.
    #[error("{0}")]
    Graph(Diagnostics),
    /// The GPU side failed.
    #[error(transparent)]
    Executor(#[from] ExecutorError),
    /// The volume could not be uploaded.
    #[error(transparent)]
    Upload(#[from] volgraph_core::executor::UploadError),
    /// The GPU rejected an upload.
    #[error(transparent)]
    Gpu(#[from] volgraph_core::executor::GpuFault),
}

/// One graph ready to render frames of one volume.
pub struct RenderSession {
    executor: Executor,
    volume_dims: Volume,
    viewport: (u32, u32),
    volume_format: Option<volgraph_core::executor::VolumeFormat>,
}

impl RenderSession {
    /// Compiles `source` (named `file` in messages) for `options`, builds its passes, and binds
    /// `volume` and `lut` to the graph's Volume and TransferFunction inputs.
    #[allow(clippy::too_many_arguments, reason = "the GPU context, the graph and the scene, each needed once")]
    pub fn new(
        gpu: &Gpu,
        shaders: &ShaderLibrary,
        registry: &Registry,
        file: &str,
        source: &str,
        options: &CompileOptions,
        volume: &Volume,
        lut: &[[f32; 4]],
    ) -> Result<Self, SessionError> {
        let plan = compile(file, source, registry, options).map_err(SessionError::Graph)?;
        Self::from_plan(gpu, shaders, registry, plan, volume, lut)
    }

    /// Like [`Self::new`] for an already compiled plan.
    pub fn from_plan(
        gpu: &Gpu,
        shaders: &ShaderLibrary,
        registry: &Registry,
        plan: Plan,
        volume: &Volume,
        lut: &[[f32; 4]],
    ) -> Result<Self, SessionError> {
        let viewport = plan.viewport;
        let inputs = plan.inputs.clone();
        let mut executor = Executor::new(gpu, shaders, registry, plan)?;
        let mut volume_format = None;
        for (name, kind) in &inputs {
            match kind {
                InputKind::Volume => {
                    let uploaded = upload_volume_texture(gpu, volume)?;
                    volume_format = Some(uploaded.format);
                    executor.bind_input(name, uploaded.texture)
                }
                InputKind::TransferFunction => executor.bind_input(name, upload_lut_texture(gpu, lut)?),
                InputKind::Scalar(_) => {}
            }
        }
        let volume_dims = volume.clone_header();
        Ok(Self { executor, volume_dims, viewport, volume_format })
    }

    /// Renders one frame from `camera`.
    pub fn render(&mut self, gpu: &Gpu, camera: &OrbitCamera) -> Result<FrameStats, SessionError> {
        self.executor.set_frame(gpu, frame_uniforms(camera, &self.volume_dims, self.viewport));
        Ok(self.executor.run_frame(gpu)?)
    }

    /// Reads a graph output of the last frame.
    pub fn read(&self, gpu: &Gpu, output: &str) -> Result<Image, SessionError> {
        Ok(self.executor.read_output(gpu, output)?)
    }

    /// The executor (plan, history invalidation).
    pub fn executor_mut(&mut self) -> &mut Executor {
        &mut self.executor
    }

    /// The texture format the volume was uploaded in (None when the graph reads no volume).
    pub fn volume_format(&self) -> Option<volgraph_core::executor::VolumeFormat> {
        self.volume_format
    }

    /// The compiled plan.
    pub fn plan(&self) -> &Plan {
        self.executor.plan()
    }
}
