//! `segment_init`: before Krüger & Westermann 2003 §2.1's segment loop, a cleared accumulation
//! target RES (0,0,0,0) and an early-z buffer cleared to 0, "every ray live". They are the
//! initial values the repeat group carries into its first iteration, so the segments can blend
//! into RES and test against the depth buffer through Modify/Read ports from the start.
//! Shader: `shaders/segment_init.wgsl`.

use crate::shared::{ACCUM_FORMATS, HIT_FORMATS};
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    CreateContext, DepthSpec, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

volgraph_compiler::pass_params! {
    /// The pass's parameters, declared once.
    pub struct InitSettings {
        with_hit: bool = false, "also clear a hit-position target for isosurface segments";
    }
}

/// The plugin.
pub struct SegmentInit;

fn fragment(params: &Params) -> &'static str {
    if InitSettings::from_params(params).with_hit { "fs_init_hit" } else { "fs_init" }
}

/// The value the early-z buffer holds for a live ray (the paper's "z = 0").
pub(crate) const DEPTH_LIVE: f32 = 0.0;

/// The pass's fragment entry point over the fullscreen triangle, declared once.
fn shader(params: &Params) -> ShaderUse {
    ShaderUse::new("segment_init.wgsl", fragment(params))
}

impl PassDecl for SegmentInit {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "segment_init"
    }

    fn summary(&self) -> &'static str {
        "cleared accumulation target and early-z buffer before the segment loop (Krüger–Westermann 2003 §2.1)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![InitSettings::block(OnChange::Rebuild)]
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::write("accum", PortKind::target(&ACCUM_FORMATS)),
            PortSpec::write("depth", PortKind::target(&[TargetFormat::Depth32Float])),
        ];
        if InitSettings::from_params(params).with_hit {
            ports.push(PortSpec::write("hit", PortKind::target(&HIT_FORMATS)));
        }
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        vec![shader(params)]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for SegmentInit {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            depth: Some(DepthSpec { port: "depth", write: true, compare: wgpu::CompareFunction::Always }),
            ..RenderPipelineSpec::fullscreen(&shader(ctx.params))
        })?;
        Ok(Box::new(SegmentInitNode { pipeline }))
    }
}

#[cfg(feature = "gpu")]
struct SegmentInitNode {
    pipeline: RenderPassPipeline,
}

#[cfg(feature = "gpu")]
impl PassNode for SegmentInitNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // The Write colour port is cleared by the render pass; nothing is drawn.
        let _pass = ctx.begin_render_pass(&self.pipeline, Some(DEPTH_LIVE))?;
        Ok(())
    }
}
