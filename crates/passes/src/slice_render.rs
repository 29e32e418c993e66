//! `slice_render`: slice-based volume rendering (SBVR), the baseline of Krüger & Westermann
//! 2003 Table 1 (§1.1, Figure 1) — view-aligned planes `slice_voxels` apart, each drawn as its
//! polygon of intersection with the box (computed in the vertex shader, one instance per
//! plane) and blended front to back into `color` with the same opacity correction as the
//! raycasters (for the distance between planes along each pixel's ray), so it approximates the
//! same integral with a different sampling pattern. `max_slices` bounds the instance count;
//! planes past the box draw nothing. Shader: `shaders/slice_render.wgsl`.

#[cfg(feature = "gpu")]
use crate::shared::front_to_back_blend;
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec, UniformBlocks,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct SliceRender;

volgraph_compiler::pass_params! {
    /// The plane spacing, declared once: spec, typed value and `SliceParams` of
    /// `shaders/slice_render.wgsl` (a test compares the two).
    pub struct SliceParams {
        slice_voxels: f32 = 0.5, 0.01..=16.0, "distance between planes in units of the smallest voxel side";
    }
}

volgraph_compiler::pass_params! {
    /// What stays on the CPU: the instance count bound.
    pub struct SliceLimits {
        max_slices: u32 = 8192, 1..=1048576,
            "upper bound on planes drawn; the default covers a 2048³ volume's diagonal at 0.5 voxel spacing";
    }
}

/// The slices' vertex and fragment entry points, declared once.
fn stages() -> [ShaderUse; 2] {
    ["vs_slice", "fs_slice"]
        .map(|entry| ShaderUse::new("slice_render.wgsl", entry).uniform(SliceParams::bound_as("slices")))
}

impl PassDecl for SliceRender {
    fn kind(&self) -> &'static str {
        "slice_render"
    }

    fn summary(&self) -> &'static str {
        "view-aligned slices through the box blended front to back: the SBVR baseline (Krüger–Westermann 2003 §1.1, Table 1)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The plane spacing is a uniform value; the slice count sizes the draw (a rebuild).
        vec![SliceParams::block(OnChange::InPlace), SliceLimits::block(OnChange::Rebuild)]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        stages().to_vec()
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for SliceRender {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let [vertex, fragment] = stages();
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            blend: Some(front_to_back_blend()),
            ..RenderPipelineSpec::drawing(&vertex, &fragment)
        })?;
        let uniforms = UniformBlocks::create(ctx, &self.shaders(ctx.params));
        Ok(Box::new(SliceRenderNode {
            pipeline,
            uniforms,
            max_slices: SliceLimits::from_params(ctx.params).max_slices,
        }))
    }
}

#[cfg(feature = "gpu")]
struct SliceRenderNode {
    pipeline: RenderPassPipeline,
    uniforms: UniformBlocks,
    max_slices: u32,
}

#[cfg(feature = "gpu")]
impl PassNode for SliceRenderNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &self.uniforms.bindings())?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..12, 0..self.max_slices);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.uniforms.write(gpu, params);
    }
}
