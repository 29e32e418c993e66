//! `segment_init`: before Krüger & Westermann 2003 §2.1's segment loop, a cleared accumulation
//! target RES (0,0,0,0) and an early-z buffer cleared to 0, "every ray live". They are the
//! initial values the repeat group carries into its first iteration, so the segments can blend
//! into RES and test against the depth buffer through Modify/Read ports from the start.
//! Shader: `shaders/segment_init.wgsl`.

use volgraph_core::executor::{CreateContext, DepthSpec, PassError, PassPipeline, RecordContext, RenderPipelineSpec};
use volgraph_core::plugin::ShaderUse;
use volgraph_core::{Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

/// The plugin.
pub struct SegmentInit;

/// Formats an accumulation target may have (blendable float formats).
pub(crate) const ACCUM_FORMATS: [TargetFormat; 2] = [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float];

/// The value the early-z buffer holds for a live ray (the paper's "z = 0").
pub(crate) const DEPTH_LIVE: f32 = 0.0;

impl PassPlugin for SegmentInit {
    fn kind(&self) -> &'static str {
        "segment_init"
    }

    fn summary(&self) -> &'static str {
        "cleared accumulation target and early-z buffer before the segment loop (Krüger–Westermann 2003 §2.1)"
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::write("accum", PortKind::target(&ACCUM_FORMATS)),
            PortSpec::write("depth", PortKind::target(&[TargetFormat::Depth32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse { file: "segment_init.wgsl", entry_point: "fs_init" }]
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: "segment_init.wgsl",
            vertex: "vs_fullscreen",
            fragment: "fs_init",
            depth: Some(DepthSpec { port: "depth", write: true, compare: wgpu::CompareFunction::Always }),
            ..Default::default()
        })?;
        Ok(Box::new(SegmentInitNode { pipeline }))
    }
}

struct SegmentInitNode {
    pipeline: PassPipeline,
}

impl PassNode for SegmentInitNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // The Write colour port is cleared by the render pass; nothing is drawn.
        let _pass = ctx.begin_render_pass(&self.pipeline, Some(DEPTH_LIVE))?;
        Ok(())
    }
}
