//! `raycast_ess`: the single-pass fragment raycaster (`raycast`, DVR) with empty-space leaping
//! over the blocks `empty_space` flags — the modern, single-pass counterpart of Krüger &
//! Westermann 2003 §2.3, which skips empty segments through an extra termination pass. On
//! entering an empty block the ray jumps to its first sample past the block's box (a DDA over
//! the block grid that only stops in non-empty blocks). Same samples as `raycast` otherwise, so
//! the image is equal up to f32 rounding (the blocks are conservative); early ray termination
//! at `threshold` as in `raycast`. Shader: `shaders/raycast_ess.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

use crate::effects::{
    EffectState, SHADING_PARAMS, effect_defines, effect_param_specs, same_effects, with_effect_bindings,
};
use crate::empty_space::{EMPTY_BLOCKS, check_block_grid};
use crate::minmax_grid::bound_size;
use crate::raycast_params::{RaycastParamsGpu, raycast_param_specs};
use crate::shared::{FLOAT_TARGETS, block_size_spec};

/// The plugin.
pub struct RaycastEss;

/// Rust twin of `struct EssParams` in `shaders/raycast_ess.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct EssParamsGpu {
    block_size: u32,
    _pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<EssParamsGpu>() == 16);

impl PassPlugin for RaycastEss {
    fn kind(&self) -> &'static str {
        "raycast_ess"
    }

    fn summary(&self) -> &'static str {
        "single-pass fragment raycaster leaping over empty blocks (DDA over Krüger–Westermann 2003 §2.3's block grid)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        // DVR only: the isosurface parameters of `raycast` do not apply (its shading
        // coefficients do, for the shading effect).
        let mut p: Vec<ParamSpec> = raycast_param_specs()
            .into_iter()
            .filter(|s| {
                matches!(s.name, "step_voxels" | "threshold" | "max_steps" | "jitter" | "jitter_per_frame")
                    || SHADING_PARAMS.contains(&s.name)
            })
            .collect();
        p.push(block_size_spec());
        p.extend(effect_param_specs());
        p
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
        let own =
            ShaderUse { file: "raycast_ess.wgsl", entry_point: "fs_dvr", extra: &["params", "ess", "preintegrated"] };
        [vec![own], crate::effects::effect_shader_uses(params)].concat()
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // Every parameter but the effects is a uniform value (the block size too).
        same_effects(old, new)
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = effect_defines(ctx.params);
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: "raycast_ess.wgsl",
            vertex: "vs_fullscreen",
            fragment: "fs_dvr",
            extra_bindings: &with_effect_bindings(&["params", "ess"]),
            defines: &defines,
            ..Default::default()
        })?;
        let params = ctx.uniform_buffer("params", std::mem::size_of::<RaycastParamsGpu>() as u64);
        ctx.gpu.queue.write_buffer(&params, 0, bytemuck::bytes_of(&RaycastParamsGpu::from_params(ctx.params)));
        let block_size = ctx.params.uint("block_size").max(1) as u32;
        let ess = ctx.uniform_buffer("ess", 16);
        ctx.gpu.queue.write_buffer(&ess, 0, bytemuck::bytes_of(&EssParamsGpu { block_size, _pad: [0; 3] }));
        let effects = EffectState::new(ctx)?;
        let step_voxels = ctx.params.float("step_voxels");
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
        gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&RaycastParamsGpu::from_params(params)));
        self.step_voxels = params.float("step_voxels");
        self.effects.invalidate();
        self.block_size = params.uint("block_size").max(1) as u32;
        let ess = EssParamsGpu { block_size: self.block_size, _pad: [0; 3] };
        gpu.queue.write_buffer(&self.ess, 0, bytemuck::bytes_of(&ess));
    }
}
