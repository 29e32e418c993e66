//! `mip`: maximum-intensity projection. Each pixel's ray meets the volume box analytically
//! (volgraph's `common/analytic_ray.wgsl`) and keeps the largest normalized scalar of its
//! samples (the same samples as volgraph's raycasters); the output is that value as grey,
//! windowed by `level` and `width` like a radiology viewer, alpha 1 where the ray hits the box.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    ComputePipelineSpec, CreateContext, Gpu, PassError, PassPipeline, PipelineKind, RecordContext,
};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};
use volgraph_passes::raycast_params::RaycastParamsGpu;

/// The plugin.
pub struct Mip;

/// Rust twin of `struct MipParams` in `shaders/mip.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MipParams {
    level: f32,
    width: f32,
    _pad: [f32; 2],
}

impl MipParams {
    fn of(p: &Params) -> Self {
        Self { level: p.float("level") as f32, width: p.float("width") as f32, _pad: [0.0; 2] }
    }
}

/// The shared raycasting parameters (`params` in volgraph's `common/raycast_params.wgsl`): the
/// step and the bound on samples, so the samples are those of volgraph's raycasters.
fn ray_params(p: &Params) -> RaycastParamsGpu {
    RaycastParamsGpu {
        step_voxels: p.float("step_voxels") as f32,
        max_steps: p.uint("max_steps") as u32,
        threshold: 1.0,
        ..Default::default()
    }
}

impl PassPlugin for Mip {
    fn kind(&self) -> &'static str {
        "mip"
    }

    fn summary(&self) -> &'static str {
        "maximum-intensity projection, windowed by level and width (examples/radiology)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::float("step_voxels", 0.5, 0.01, 16.0, "sample distance in units of the smallest voxel side"),
            ParamSpec::float("level", 0.5, 0.0, 1.0, "window centre, in normalized scalar units"),
            ParamSpec::float("width", 1.0, 0.001, 2.0, "window width, in normalized scalar units"),
            ParamSpec::uint("max_steps", 4096, 1, 1 << 20, "upper bound on samples per ray"),
        ]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse { file: "mip.wgsl", entry_point: "cs_main" }]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            shader: "mip.wgsl",
            entry: "cs_main",
            extra_bindings: &["mip", "params"],
            constants: &[],
            defines: &[],
        })?;
        let uniform = ctx.uniform_with("mip", &MipParams::of(ctx.params));
        let rays = ctx.uniform_with("params", &ray_params(ctx.params));
        Ok(Box::new(MipNode { pipeline, uniform, rays }))
    }
}

struct MipNode {
    pipeline: PassPipeline,
    uniform: wgpu::Buffer,
    rays: wgpu::Buffer,
}

impl PassNode for MipNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let extra = [("mip", self.uniform.as_entire_binding()), ("params", self.rays.as_entire_binding())];
        let bg = ctx.bind_group(&self.pipeline, &extra)?;
        let (w, h) = ctx.extent("color");
        let mut pass = ctx.begin_compute_pass();
        if let PipelineKind::Compute(p) = &self.pipeline.pipeline {
            pass.set_pipeline(p);
        }
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&MipParams::of(params)));
        gpu.queue.write_buffer(&self.rays, 0, bytemuck::bytes_of(&ray_params(params)));
    }
}
