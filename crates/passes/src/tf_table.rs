//! A table a raycaster derives on the GPU from its transfer function and step, in a compute
//! pass of its own (the opacity-corrected table of [`crate::opacity_lut`], the pre-integration
//! table of [`crate::preintegration`]). Both come in two variants: Rgba32Float where the device
//! can filter it, else Rgba16Float (filterable everywhere); the shader has one entry point per
//! variant, writing the storage binding `table32` or `table16`, and reads the raycaster's
//! uniform `params` for the step.

use volgraph_compiler::ShaderUse;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};

#[cfg(feature = "gpu")]
/// A derived table, the pipeline that fills it and the texture it fills.
pub struct TfTable {
    pipeline: ComputePassPipeline,
    storage: wgpu::TextureView,
    /// The storage binding the pipeline writes (`table32` or `table16`).
    binding: &'static str,
    /// Workgroups of one fill.
    groups: (u32, u32),
    /// The table, for the raycaster to sample.
    pub view: wgpu::TextureView,
}

/// The two entry points that fill a table of `file`: `cs_table32` and `cs_table16`.
pub fn table_shaders(file: &'static str) -> [ShaderUse; 2] {
    let step = || crate::raycast_params::RaycastParamsGpu::bound("params");
    [
        ShaderUse::new(file, "cs_table32").binds(&["table32"]).uniform(step()),
        ShaderUse::new(file, "cs_table16").binds(&["table16"]).uniform(step()),
    ]
}

#[cfg(feature = "gpu")]
impl TfTable {
    /// The table of `size` texels filled by `shaders` (the [`table_shaders`] of its file) with
    /// workgroups of `workgroup`, in the precision the device filters.
    pub fn new(
        ctx: &CreateContext<'_>,
        shaders: &[ShaderUse; 2],
        size: (u32, u32),
        workgroup: (u32, u32),
        what: &str,
    ) -> Result<Self, PassError> {
        let (shader, format, binding) = match ctx.gpu.float32_filterable {
            true => (&shaders[0], wgpu::TextureFormat::Rgba32Float, "table32"),
            false => (&shaders[1], wgpu::TextureFormat::Rgba16Float, "table16"),
        };
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(shader))?;
        let texture = ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(&format!("{} {what}", ctx.pass_id)),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let groups = (size.0.div_ceil(workgroup.0), size.1.div_ceil(workgroup.1));
        Ok(Self { pipeline, storage: view.clone(), binding, groups, view })
    }

    /// Records one fill from the pass's transfer function on port `tf_port` (the shader's `tf`)
    /// with the step in `params`.
    pub fn fill(&self, ctx: &mut RecordContext<'_>, params: &wgpu::Buffer, tf_port: &str) -> Result<(), PassError> {
        let tf = ctx.view(tf_port)?;
        let bg = ctx.bind_group(
            &self.pipeline,
            &[
                ("params", params.as_entire_binding()),
                (self.binding, wgpu::BindingResource::TextureView(&self.storage)),
                ("tf", wgpu::BindingResource::TextureView(tf)),
            ],
        )?;
        let mut pass = ctx.begin_compute_pass();
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
        Ok(())
    }
}
