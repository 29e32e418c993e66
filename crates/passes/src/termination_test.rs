//! `termination_test`: Krüger & Westermann 2003 §2.1 "intermediate passes" (and §2.3 with
//! empty-space skipping). Runs after each `raycast_segment` and writes the early-z buffer for
//! the next segment: depth 1 (the paper's MAX, rejected by the segments' GREATER test) where
//! the accumulated alpha has reached the threshold T or the ray has no sample left, and — when
//! the optional `empty` port carries `empty_space`'s block flags — where every sample of the
//! next segment lies in an empty block; depth 0 elsewhere, which re-enables a ray after an
//! empty segment. A fullscreen pass that reads RES and writes `@builtin(frag_depth)` through a
//! Modify depth port (depth compare Always); it has no colour targets.
//!
//! Error bound of termination: stopping a ray once its accumulated alpha `A ≥ T` drops what the
//! rest of the ray would add, at most `(1 - A) ≤ (1 - T)` per premultiplied channel.
//!
//! `step_voxels`, `max_steps`, `jitter` and `segment_steps` must equal the segment pass's (the
//! test recomputes where the next segment's samples lie), and `block_size` the `minmax_grid`
//! pass's. Shader: `shaders/termination_test.wgsl`.

use crate::raycast_params::sampling_block;
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::footprint::FAN_DRAW_VERTICES;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    CreateContext, DepthSpec, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use crate::empty_space::EMPTY_BLOCKS;
use crate::raycast_params::RaycastParamsGpu;
#[cfg(feature = "gpu")]
use crate::raycast_segment::segment_index;
use crate::raycast_segment::{SegmentParams, SegmentSteps};
use crate::shared::{ACCUM_FORMATS, BlockSize, FLOAT_TARGETS};

/// The plugin.
pub struct TerminationTest;

volgraph_compiler::pass_params! {
    /// The test's threshold: the `threshold` of the shared termination block (the segment
    /// pass's), with the paper's T = 0.95 as its default.
    pub struct TestThreshold {
        threshold: f32 = 0.95, 0.0..=1.0,
            "T: rays whose accumulated alpha is >= T stop (1 = only fully opaque rays, lossless)";
    }
}

/// The segment's quad (with and without the alpha-only culling) and the two tests, declared
/// once for `shaders()` and `create`.
fn stages() -> [ShaderUse; 4] {
    ["vs_segment", "vs_terminate_alpha", "fs_terminate", "fs_terminate_empty"].map(|entry| {
        ShaderUse::new("termination_test.wgsl", entry)
            .uniform(RaycastParamsGpu::bound("params"))
            .uniform(SegmentParams::layout())
    })
}

impl PassDecl for TerminationTest {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "termination_test"
    }

    fn summary(&self) -> &'static str {
        "early-z buffer for the next segment: saturated, finished or empty rays rejected (Krüger–Westermann 2003 §2.1, \
         §2.3); its sampling, segment_steps and block_size must be the segment pass's (share Scalar inputs)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The segment pass's sampling, segment length and block grid (they must match it; a
        // graph shares them through Scalar inputs), and the test's own threshold; written once,
        // when the node is built.
        vec![
            sampling_block(OnChange::Rebuild),
            TestThreshold::block(OnChange::Rebuild),
            SegmentSteps::block(OnChange::Rebuild),
            BlockSize::block(OnChange::Rebuild),
        ]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("accum", PortKind::target(&ACCUM_FORMATS)),
            PortSpec::read("empty", PortKind::Owned(EMPTY_BLOCKS)).optional(),
            PortSpec::modify("depth", PortKind::target(&[TargetFormat::Depth32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        stages().to_vec()
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for TerminationTest {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = crate::effects::jitter_defines(ctx.params);
        let [segment_vs, alpha_vs, terminate, terminate_empty] = stages();
        // RC-a never re-enables a ray, so its test is culled by early-z itself (see the shader).
        let alpha_only = ctx.render_pipeline(&RenderPipelineSpec {
            depth: Some(DepthSpec { port: "depth", write: true, compare: wgpu::CompareFunction::Greater }),
            defines: &defines,
            ..RenderPipelineSpec::drawing(&alpha_vs, &terminate)
        })?;
        let with_empty = ctx.render_pipeline(&RenderPipelineSpec {
            depth: Some(DepthSpec { port: "depth", write: true, compare: wgpu::CompareFunction::Always }),
            defines: &defines,
            ..RenderPipelineSpec::drawing(&segment_vs, &terminate_empty)
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let segment = ctx.uniform_from_bytes("segment", &SegmentParams::of(ctx.params).uniform_bytes());
        Ok(Box::new(TerminationTestNode { alpha_only, with_empty, params, segment }))
    }
}

#[cfg(feature = "gpu")]
struct TerminationTestNode {
    alpha_only: RenderPassPipeline,
    with_empty: RenderPassPipeline,
    params: wgpu::Buffer,
    segment: wgpu::Buffer,
}

#[cfg(feature = "gpu")]
impl PassNode for TerminationTestNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // This pass decides for the segment after the one just drawn.
        let next = segment_index(ctx) + 1;
        let pipeline = if ctx.is_bound("empty") { &self.with_empty } else { &self.alpha_only };
        let bg = ctx.bind_group(
            pipeline,
            &[("params", self.params.as_entire_binding()), ("segment", self.segment.as_entire_binding())],
        )?;
        let mut pass = ctx.begin_render_pass(pipeline, None)?;
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..FAN_DRAW_VERTICES, next..next + 1);
        Ok(())
    }
}
