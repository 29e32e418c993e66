//! `raycast_ess`: the single-pass fragment raycaster (`raycast`, DVR) with empty-space leaping
//! over the blocks `empty_space` flags — the modern, single-pass counterpart of Krüger &
//! Westermann 2003 §2.3, which skips empty segments through an extra termination pass. On
//! entering an empty block the ray jumps to its first sample past the block's box (a DDA over
//! the block grid that only stops in non-empty blocks). Same samples as `raycast` otherwise, so
//! the image is equal up to f32 rounding (the blocks are conservative); early ray termination
//! at `threshold` as in `raycast`. Shader: `shaders/raycast_ess.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

use crate::effects::{EffectState, effect_defines, same_effects};
use crate::empty_space::{EMPTY_BLOCKS, check_block_grid};
use crate::minmax_grid::bound_size;
use crate::raycast_fast::dvr_leap_specs;
use crate::raycast_params::{RaycastParamsGpu, Sampling};
use crate::shared::{BlockSize, FLOAT_TARGETS};

/// The plugin.
pub struct RaycastEss;

/// Its one pipeline.
const SHADER: ShaderUse =
    ShaderUse { file: "raycast_ess.wgsl", entry_point: "fs_dvr", extra: &["params", "ess", "preintegrated"] };

impl PassDecl for RaycastEss {
    fn kind(&self) -> &'static str {
        "raycast_ess"
    }

    fn summary(&self) -> &'static str {
        "single-pass fragment raycaster leaping over empty blocks (DDA over Krüger–Westermann 2003 §2.3's block grid)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        // DVR only: the isosurface parameters of `raycast` do not apply (its shading
        // coefficients do, for the shading effect).
        dvr_leap_specs()
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        effect_defines(params)
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::read("empty", PortKind::Owned(EMPTY_BLOCKS)),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        [vec![SHADER], crate::effects::effect_shader_uses(params)].concat()
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // Every parameter but the effects is a uniform value (the block size too).
        same_effects(old, new)
    }
}

impl PassPlugin for RaycastEss {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = effect_defines(ctx.params);
        let pipeline =
            ctx.render_pipeline(&RenderPipelineSpec { defines: &defines, ..RenderPipelineSpec::fullscreen(&SHADER) })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let block_size = BlockSize::of(ctx.params);
        // `EssParams` of the shader: the block edge, padded to 16 bytes.
        let ess = ctx.uniform_from_bytes("ess", &BlockSize { block_size }.uniform_bytes());
        let effects = EffectState::new(ctx)?;
        let step_voxels = Sampling::from_params(ctx.params).step_voxels;
        Ok(Box::new(RaycastEssNode { pipeline, params, ess, block_size, effects, step_voxels }))
    }
}

struct RaycastEssNode {
    pipeline: RenderPassPipeline,
    params: wgpu::Buffer,
    ess: wgpu::Buffer,
    block_size: u32,
    effects: EffectState,
    step_voxels: f64,
}

impl PassNode for RaycastEssNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let volume = bound_size(ctx, "volume")?;
        check_block_grid(ctx, "empty", self.block_size, volume)?;
        self.effects.update(ctx, &self.params, self.step_voxels)?;
        let mut extra = vec![("params", self.params.as_entire_binding()), ("ess", self.ess.as_entire_binding())];
        extra.extend(self.effects.bindings());
        let bg = ctx.bind_group(&self.pipeline, &extra)?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        crate::draw(&mut pass, &self.pipeline, &bg, 0..3);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
        self.step_voxels = Sampling::from_params(params).step_voxels;
        self.effects.invalidate();
        self.block_size = BlockSize::of(params);
        gpu.queue.write_buffer(&self.ess, 0, &BlockSize { block_size: self.block_size }.uniform_bytes());
    }
}
