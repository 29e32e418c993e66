//! `mip`: maximum-intensity projection. Each pixel's ray meets the volume box analytically
//! (volgraph's `common/ray_box.wgsl`) and keeps the largest normalized scalar of its
//! samples (the same samples as volgraph's raycasters); the output is that value as grey,
//! windowed by `level` and `width` like a radiology viewer, alpha 1 where the ray hits the box.

use volgraph_core::block::{OnChange, ParamBlock};
use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, UniformBlocks,
};
use volgraph_core::{Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};
// volgraph's shared sampling block: the same step, sample count and jitter as its raycasters.
use volgraph_passes::raycast_params::{RaycastParamsGpu, sampling_block};

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

/// Its one pipeline, declared once: the file, the entry point and the uniform blocks it binds
/// by name with their layouts (`volgraph plan` checks the shader's structs against them; the
/// shader imports `MipParams` as generated, `params/MipParams.wgsl`). Listed by `shaders()`
/// and built by `create`.
fn shader() -> ShaderUse {
    ShaderUse::new("mip.wgsl", "cs_main").uniform(MipParams::bound_as("mip")).uniform(RaycastParamsGpu::bound("params"))
}

impl PassDecl for Mip {
    fn kind(&self) -> &'static str {
        "mip"
    }

    fn summary(&self) -> &'static str {
        "maximum-intensity projection, windowed by level and width (examples/radiology)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The window, and volgraph's sampling block, whose `jitter` brings its `#if` of the
        // shared ray code; the node rewrites both uniforms, so an edit of either rebuilds nothing.
        vec![MipParams::block(OnChange::InPlace), sampling_block(OnChange::InPlace)]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

impl PassPlugin for Mip {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = self.shader_defines(ctx.params);
        let shader = shader();
        let pipeline =
            ctx.compute_pipeline(&ComputePipelineSpec { defines: &defines, ..ComputePipelineSpec::of(&shader) })?;
        Ok(Box::new(MipNode { pipeline, uniforms: UniformBlocks::create(ctx, &[shader]) }))
    }
}

struct MipNode {
    pipeline: ComputePassPipeline,
    uniforms: UniformBlocks,
}

impl PassNode for MipNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        ctx.dispatch_over(&self.pipeline, &self.uniforms.bindings(), "color", (8, 8))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.uniforms.write(gpu, params);
    }
}

#[cfg(test)]
mod tests {
    use super::MipParams;

    /// The shader's `MipParams` is the struct `pass_params!` generates (imported, not restated).
    #[test]
    fn the_shader_struct_is_the_generated_one() {
        // Assembled as the GPU gets it: volgraph's shared files and the generated structs
        // imported, bindings numbered.
        let source = volgraph_core::shader_source::assemble(&crate::shader_sources(), "mip.wgsl").expect("assembles");
        MipParams::check_shader(&source.text, "MipParams").expect("same layout");
        assert!(source.text.contains(&MipParams::wgsl_struct()));
    }
}
