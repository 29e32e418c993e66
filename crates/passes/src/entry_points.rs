//! `entry_points`: Krüger & Westermann 2003 §2.1, pass 1 — the volume box's front faces
//! rasterized into a float target of texture-space entry positions `(u, 1)`; `(0,0,0,0)` where
//! the ray misses. With the camera inside the volume the front faces are clipped, and a
//! screen-covering triangle writes each ray's near-plane point instead (at any pixel at most one
//! of the two writes, so both are always drawn). Shader: `shaders/entry_points.wgsl`.

use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct EntryPoints;

/// The box's faces, the entry on its front faces, and the near plane where the eye is inside:
/// declared once for `shaders()` and `create`.
const BOX: ShaderUse = ShaderUse::new("entry_points.wgsl", "vs_box");
const FRONT_FACES: ShaderUse = ShaderUse::new("entry_points.wgsl", "fs_entry");
const NEAR_PLANE: ShaderUse = ShaderUse::new("entry_points.wgsl", "fs_near_plane");

impl PassDecl for EntryPoints {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "entry_points"
    }

    fn summary(&self) -> &'static str {
        "texture-space ray entry points from the box's front faces (Krüger–Westermann 2003 §2.1, pass 1)"
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("entry", PortKind::target(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float]))]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![BOX, FRONT_FACES, NEAR_PLANE]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for EntryPoints {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let faces = ctx.render_pipeline(&RenderPipelineSpec {
            cull: Some(wgpu::Face::Back),
            ..RenderPipelineSpec::drawing(&BOX, &FRONT_FACES)
        })?;
        let near_plane = ctx.render_pipeline(&RenderPipelineSpec::fullscreen(&NEAR_PLANE))?;
        Ok(Box::new(EntryPointsNode { faces, near_plane }))
    }
}

#[cfg(feature = "gpu")]
struct EntryPointsNode {
    faces: RenderPassPipeline,
    near_plane: RenderPassPipeline,
}

#[cfg(feature = "gpu")]
impl PassNode for EntryPointsNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let faces_bg = ctx.bind_group(&self.faces, &[])?;
        let near_bg = ctx.bind_group(&self.near_plane, &[])?;
        let mut pass = ctx.begin_render_pass(&self.faces, None)?;
        crate::draw(&mut pass, &self.near_plane, &near_bg, 0..3);
        crate::draw(&mut pass, &self.faces, &faces_bg, 0..36);
        Ok(())
    }
}
