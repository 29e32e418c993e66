//! `ray_directions`: Krüger & Westermann 2003 §2.1, pass 2 — the box's back faces give each
//! ray's exit point; with the entry point from pass 1 this writes the normalized texture-space
//! direction and, in alpha, the ray length. Shader: `shaders/ray_directions.wgsl`.

use crate::shared::FLOAT_TARGETS;
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct RayDirections;

/// The box's back faces and the direction each pixel's ray takes, declared once.
const VERTEX: ShaderUse = ShaderUse::new("ray_directions.wgsl", "vs_box");
const FRAGMENT: ShaderUse = ShaderUse::new("ray_directions.wgsl", "fs_dir");

impl PassDecl for RayDirections {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "ray_directions"
    }

    fn summary(&self) -> &'static str {
        "texture-space ray direction and length from the box's back faces (Krüger–Westermann 2003 §2.1, pass 2)"
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::write("dir", PortKind::target(&FLOAT_TARGETS)),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![VERTEX, FRAGMENT]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for RayDirections {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            cull: Some(wgpu::Face::Front),
            ..RenderPipelineSpec::drawing(&VERTEX, &FRAGMENT)
        })?;
        Ok(Box::new(RayDirectionsNode { pipeline }))
    }
}

#[cfg(feature = "gpu")]
struct RayDirectionsNode {
    pipeline: RenderPassPipeline,
}

#[cfg(feature = "gpu")]
impl PassNode for RayDirectionsNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[])?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        crate::draw(&mut pass, &self.pipeline, &bg, 0..36);
        Ok(())
    }
}
