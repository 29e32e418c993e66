//! The pre-integration table of Engel et al. 2001 for the `preintegration` effect: for every pair
//! of front and back scalars, the premultiplied colour of one step along which the scalar runs
//! linearly between them, so a thin feature of the transfer function between two samples is
//! integrated instead of missed. Not a pass: each raycaster that classifies through it owns one
//! and rebuilds it on the GPU only when the transfer function's content (its input version) or
//! the step changes, so table and march always agree. Shader: `shaders/preintegration.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};

/// Texels per side: one per scalar value of an 8-bit volume.
pub const TABLE_SIZE: u32 = 256;

/// The entry points that fill the table: Rgba32Float, Rgba16Float.
pub const TABLE_SHADERS: [ShaderUse; 2] = [
    ShaderUse { file: "preintegration.wgsl", entry_point: "cs_table32", extra: &["params", "table32"] },
    ShaderUse { file: "preintegration.wgsl", entry_point: "cs_table16", extra: &["params", "table16"] },
];

/// A raycaster's pre-integration table, its pipeline and what it was built for.
pub struct PreintegrationTable {
    pipeline: ComputePassPipeline,
    storage: wgpu::TextureView,
    binding: &'static str,
    /// The table, bound as `preintegrated`.
    pub view: wgpu::TextureView,
    /// (TF version, step exponent) of the last build.
    built_for: Option<(u64, f32)>,
    /// How many times it was built (tests, the viewer).
    pub builds: u64,
}

impl PreintegrationTable {
    /// The pipeline (binding `params`: the raycaster's uniform) and the table texture.
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
            label: Some(&format!("{} pre-integration table", ctx.pass_id)),
            size: wgpu::Extent3d { width: TABLE_SIZE, height: TABLE_SIZE, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Ok(Self { pipeline, storage: view.clone(), binding, view, built_for: None, builds: 0 })
    }

    /// Rebuilds the table from the pass's `tf` port when the TF's content or the step exponent
    /// (`step_voxels` over the frame's opacity unit) changed since the last build.
    pub fn update(
        &mut self,
        ctx: &mut RecordContext<'_>,
        params: &wgpu::Buffer,
        step_voxels: f64,
    ) -> Result<(), PassError> {
        let unit = ctx.frame.volume.map_or(1.0, |v| v.opacity_unit_voxels);
        let key = (ctx.input_version("tf").unwrap_or(0), (step_voxels / unit) as f32);
        if self.built_for == Some(key) {
            return Ok(());
        }
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
        pass.dispatch_workgroups(TABLE_SIZE.div_ceil(8), TABLE_SIZE.div_ceil(8), 1);
        self.built_for = Some(key);
        self.builds += 1;
        Ok(())
    }

    /// Forgets the last build (after new parameters were written).
    pub fn invalidate(&mut self) {
        self.built_for = None;
    }
}
