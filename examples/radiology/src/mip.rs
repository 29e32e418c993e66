//! `mip`: maximum-intensity projection. Each pixel's ray meets the volume box analytically
//! (volgraph's `common/analytic_ray.wgsl`) and keeps the largest normalized scalar of its
//! samples (the same samples as volgraph's raycasters); the output is that value as grey,
//! windowed by `level` and `width` like a radiology viewer, alpha 1 where the ray hits the box.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};
use volgraph_passes::raycast_params::RaycastParamsGpu;

/// The plugin.
pub struct Mip;

volgraph_core::pass_params! {
    /// The window, declared once: spec, typed values and the shader's `MipParams` (a test
    /// compares the two).
    pub struct MipParams {
        level: f32 = 0.5, 0.0..=1.0, "window centre, in normalized scalar units";
        width: f32 = 1.0, 0.001..=2.0, "window width, in normalized scalar units";
    }
}

volgraph_core::pass_params! {
    /// The sampling, declared once; it fills volgraph's shared raycasting block.
    pub struct Sampling {
        step_voxels: f32 = 0.5, 0.01..=16.0, "sample distance in units of the smallest voxel side";
        max_steps: u32 = 4096, 1..=1048576, "upper bound on samples per ray";
    }
}

/// The shared raycasting parameters (`params` in volgraph's `common/raycast_params.wgsl`), so the
/// samples are those of volgraph's raycasters.
fn ray_params(p: &Params) -> RaycastParamsGpu {
    let s = Sampling::from_params(p);
    RaycastParamsGpu { step_voxels: s.step_voxels, max_steps: s.max_steps, threshold: 1.0, ..Default::default() }
}

/// Its one pipeline, declared once: listed by `shaders()` (what `volgraph plan` checks) and
/// built by `create`.
const SHADER: ShaderUse = ShaderUse { file: "mip.wgsl", entry_point: "cs_main", extra: &["mip", "params"] };

impl PassPlugin for Mip {
    fn kind(&self) -> &'static str {
        "mip"
    }

    fn summary(&self) -> &'static str {
        "maximum-intensity projection, windowed by level and width (examples/radiology)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        [MipParams::specs(), Sampling::specs()].concat()
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![SHADER]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(&SHADER))?;
        let uniform = ctx.uniform_buffer("mip", 16);
        ctx.gpu.queue.write_buffer(&uniform, 0, &MipParams::from_params(ctx.params).uniform_bytes());
        let rays = ctx.uniform_with("params", &ray_params(ctx.params));
        Ok(Box::new(MipNode { pipeline, uniform, rays }))
    }
}

struct MipNode {
    pipeline: ComputePassPipeline,
    uniform: wgpu::Buffer,
    rays: wgpu::Buffer,
}

impl PassNode for MipNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let extra = [("mip", self.uniform.as_entire_binding()), ("params", self.rays.as_entire_binding())];
        ctx.dispatch_over(&self.pipeline, &extra, "color", (8, 8))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.uniform, 0, &MipParams::from_params(params).uniform_bytes());
        gpu.queue.write_buffer(&self.rays, 0, bytemuck::bytes_of(&ray_params(params)));
    }
}

#[cfg(test)]
mod tests {
    use super::MipParams;

    /// The shader's `MipParams` is the struct `pass_params!` uploads.
    #[test]
    fn the_shader_struct_matches_the_declaration() {
        let source = include_str!("../shaders/mip.wgsl");
        let fields: Vec<(&str, &str)> = MipParams::specs().iter().map(|s| (s.name, "f32")).collect();
        // The shader imports volgraph's shared files; check the struct on its own text.
        let start = source.find("struct MipParams").expect("declared");
        let end = start + source[start..].find('}').expect("closed") + 1;
        volgraph_core::declare::check_wgsl_struct(&source[start..end], "MipParams", &fields).expect("same layout");
    }
}
