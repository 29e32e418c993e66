//! `present`: turns a linear, premultiplied float image into the 8-bit sRGB image a person
//! looks at — composited over a grey background and encoded with the sRGB transfer function.
//! Writing files (PNG from this output, EXR from the float input) is the application's job.
//! A compute pass (a third of the fullscreen draw's time on llvmpipe; compute is the fast path on
//! data-centre GPUs too). Shader: `shaders/present.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, UniformBlocks,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct Present;

volgraph_compiler::pass_params! {
    /// The parameters, declared once: the spec, typed values, the uniform bytes and the struct
    /// `shaders/present.wgsl` imports (`params/PresentParams.wgsl`).
    pub struct PresentParams {
        background: f32 = 0.0, 0.0..=1.0, "linear grey level behind the volume";
    }
}

/// Its one pipeline, declared once: `volgraph plan` checks the bindings of what `create` builds.
fn shader() -> ShaderUse {
    ShaderUse::new("present.wgsl", "cs_present").uniform(PresentParams::bound_as("params"))
}

impl PassDecl for Present {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "present"
    }

    fn summary(&self) -> &'static str {
        "linear premultiplied colour → 8-bit sRGB over a background, for display and PNG"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // A uniform the node rewrites (its `UniformBlocks`).
        vec![PresentParams::block(OnChange::InPlace)]
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
}

#[cfg(feature = "gpu")]
impl PassPlugin for Present {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let shader = shader();
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(&shader))?;
        Ok(Box::new(PresentNode { pipeline, uniforms: UniformBlocks::create(ctx, &[shader]) }))
    }
}

#[cfg(feature = "gpu")]
struct PresentNode {
    pipeline: ComputePassPipeline,
    uniforms: UniformBlocks,
}

#[cfg(feature = "gpu")]
impl PassNode for PresentNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        ctx.dispatch_over(&self.pipeline, &self.uniforms.bindings(), "display", (8, 8))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.uniforms.write(gpu, params);
    }
}
