//! The transfer function pre-multiplied and opacity-corrected for the step, as a table denser
//! than the LUT, so a raycaster pays one filtered lookup and no `pow` per sample (the correction
//! depends only on the TF and the step: Engel et al. 2001). Not a pass of its own: a raycaster
//! that classifies through it (`raycast_fast`, `classify: "table"`) builds it in its own
//! compute pass from its own `step_voxels`, so table and march can never disagree on the step.
//! Rebuilding costs one dispatch of [`TABLE_SIZE`] invocations per frame. Read with a linear
//! sampler it equals the exact per-sample correction to second order in the table spacing;
//! stored as Rgba32Float where the device can filter it, else Rgba16Float (filterable on every
//! device). Shader: `shaders/opacity_lut.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};

/// Texels of the table: 16× the 256-entry LUT, so the table's own linear interpolation adds
/// < 0.1/255 to the image for the peer TFs (crates/passes/tests/fastest.rs).
pub const TABLE_SIZE: u32 = 4096;

/// The shader entry points that fill the table: Rgba32Float, Rgba16Float.
pub const TABLE_SHADERS: [ShaderUse; 2] = [
    ShaderUse { file: "opacity_lut.wgsl", entry_point: "cs_table32", extra: &["params", "table32"] },
    ShaderUse { file: "opacity_lut.wgsl", entry_point: "cs_table16", extra: &["params", "table16"] },
];

/// A corrected table and the pipeline that fills it.
pub struct OpacityTable {
    pipeline: ComputePassPipeline,
    storage: wgpu::TextureView,
    /// The storage binding the pipeline writes (`table32` or `table16`).
    binding: &'static str,
    /// The table, for the raycaster to sample (binding `corrected`).
    pub view: wgpu::TextureView,
}

impl OpacityTable {
    /// The pipeline (binding `params`: the raycaster's uniform with `step_voxels`) and the
    /// table texture.
    pub fn new(ctx: &CreateContext<'_>) -> Result<Self, PassError> {
        let (shader, format, binding) = match ctx.gpu.float32_filterable {
            true => (&TABLE_SHADERS[0], wgpu::TextureFormat::Rgba32Float, "table32"),
            false => (&TABLE_SHADERS[1], wgpu::TextureFormat::Rgba16Float, "table16"),
        };
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            shader: shader.file,
            entry: shader.entry_point,
            extra_bindings: &["params", binding],
            ..Default::default()
        })?;
        let texture = ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(&format!("{} opacity-corrected table", ctx.pass_id)),
            size: wgpu::Extent3d { width: TABLE_SIZE, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Ok(Self { pipeline, storage: view.clone(), binding, view })
    }

    /// Records the table's rebuild from the pass's `tf` port with the step in `params`.
    pub fn record(&self, ctx: &mut RecordContext<'_>, params: &wgpu::Buffer) -> Result<(), PassError> {
        let bg = ctx.bind_group(
            &self.pipeline,
            &[
                ("params", params.as_entire_binding()),
                (self.binding, wgpu::BindingResource::TextureView(&self.storage)),
            ],
        )?;
        let mut pass = ctx.begin_compute_pass();
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(TABLE_SIZE.div_ceil(64), 1, 1);
        Ok(())
    }
}
