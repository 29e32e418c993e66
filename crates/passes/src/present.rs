//! `present`: turns a linear, premultiplied float image into the 8-bit sRGB image a person
//! looks at — composited over a grey background and encoded with the sRGB transfer function.
//! Writing files (PNG from this output, EXR from the float input) is the application's job.
//! A compute pass (a third of the fullscreen draw's time on llvmpipe; compute is the fast path on
//! data-centre GPUs too). Shader: `shaders/present.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    ComputePipelineSpec, CreateContext, Gpu, PassError, PassPipeline, PipelineKind, RecordContext,
};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

/// The plugin.
pub struct Present;

/// Rust twin of `PresentParams` in `shaders/present.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct PresentParamsGpu {
    background: f32,
    _pad: [f32; 3],
}

const _: () = assert!(std::mem::size_of::<PresentParamsGpu>() == 16);

impl PassPlugin for Present {
    fn kind(&self) -> &'static str {
        "present"
    }

    fn summary(&self) -> &'static str {
        "linear premultiplied colour → 8-bit sRGB over a background, for display and PNG"
    }

    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::float("background", 0.0, 0.0, 1.0, "linear grey level behind the volume")]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
            PortSpec::write("display", PortKind::target(&[TargetFormat::Rgba8Unorm])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse { file: "present.wgsl", entry_point: "cs_present" }]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            shader: "present.wgsl",
            entry: "cs_present",
            extra_bindings: &["params"],
            ..Default::default()
        })?;
        let params = ctx.uniform_buffer("params", 16);
        let p = PresentParamsGpu { background: ctx.params.float("background") as f32, _pad: [0.0; 3] };
        ctx.gpu.queue.write_buffer(&params, 0, bytemuck::bytes_of(&p));
        Ok(Box::new(PresentNode { pipeline, params }))
    }
}

struct PresentNode {
    pipeline: PassPipeline,
    params: wgpu::Buffer,
}

impl PassNode for PresentNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[("params", self.params.as_entire_binding())])?;
        let (w, h) = ctx.extent("display");
        let mut pass = ctx.begin_compute_pass();
        if let PipelineKind::Compute(p) = &self.pipeline.pipeline {
            pass.set_pipeline(p);
        }
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        let p = PresentParamsGpu { background: params.float("background") as f32, _pad: [0.0; 3] };
        gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
    }
}
