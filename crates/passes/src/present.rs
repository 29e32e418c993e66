//! `present`: turns a linear, premultiplied float image into the 8-bit sRGB image a person
//! looks at — composited over a grey background and encoded with the sRGB transfer function.
//! Writing files (PNG from this output, EXR from the float input) is the application's job.
//! A compute pass (a third of the fullscreen draw's time on llvmpipe; compute is the fast path on
//! data-centre GPUs too). Shader: `shaders/present.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

/// The plugin.
pub struct Present;

volgraph_core::pass_params! {
    /// The parameters, declared once: the spec, typed values and `PresentParams` of
    /// `shaders/present.wgsl` (checked against the shader by a test).
    pub struct PresentParams {
        background: f32 = 0.0, 0.0..=1.0, "linear grey level behind the volume";
    }
}

/// Its one pipeline, declared once: `volgraph plan` checks the bindings of what `create` builds.
fn shader() -> ShaderUse {
    ShaderUse::new("present.wgsl", "cs_present").uniform(PresentParams::bound_as("params"))
}

impl PassDecl for Present {
    fn kind(&self) -> &'static str {
        "present"
    }

    fn summary(&self) -> &'static str {
        "linear premultiplied colour → 8-bit sRGB over a background, for display and PNG"
    }

    fn params(&self) -> Vec<ParamSpec> {
        PresentParams::specs()
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
            PortSpec::write("display", PortKind::target(&[TargetFormat::Rgba8Unorm])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }
}

impl PassPlugin for Present {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(&shader()))?;
        let params = ctx.uniform_from_bytes("params", &PresentParams::from_params(ctx.params).uniform_bytes());
        Ok(Box::new(PresentNode { pipeline, params }))
    }
}

struct PresentNode {
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
}

impl PassNode for PresentNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        ctx.dispatch_over(&self.pipeline, &[("params", self.params.as_entire_binding())], "display", (8, 8))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &PresentParams::from_params(params).uniform_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::PresentParams;

    /// The shader's `PresentParams` is the struct `pass_params!` uploads.
    #[test]
    fn the_shader_struct_matches_the_declaration() {
        PresentParams::check_shader(&crate::shared::assembled("present.wgsl"), "PresentParams").expect("same layout");
        assert!(PresentParams::wgsl_struct().starts_with("struct PresentParams {\n    background: f32,"));
    }
}
