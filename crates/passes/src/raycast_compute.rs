//! `raycast_compute`: the same integral as `raycast` in a compute shader writing a storage
//! texture, one invocation per pixel — the DirectCompute thesis's compute raycaster
//! (`RAYCASTSIMPLE_CS`). The workgroup size is a parameter (pipeline-overridable constants).
//! Shader: `shaders/raycast_compute.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortSpec, TargetFormat};

use crate::effects::{EffectFlags, EffectState, effect_defines, same_effects};
use crate::raycast::raycast_ports;
use crate::raycast_params::{RaycastParamsGpu, Sampling, Workgroup, is_iso, raycast_param_specs};
use crate::shared::color_is_f32;

/// The plugin.
pub struct RaycastCompute;

impl PassDecl for RaycastCompute {
    fn kind(&self) -> &'static str {
        "raycast_compute"
    }

    fn summary(&self) -> &'static str {
        "compute-shader raycaster writing a storage texture (DirectCompute thesis, RAYCASTSIMPLE_CS)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        [raycast_param_specs(), EffectFlags::specs(), Workgroup::specs()].concat()
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        effect_defines(params)
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        // Storage formats: rgba16float or (a scene's f32 precision) rgba32float colour, chosen by
        // a shader define; rgba32float hits.
        raycast_ports(params, &[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float], &[TargetFormat::Rgba32Float])
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let entry = if is_iso(params) { "cs_iso" } else { "cs_dvr" };
        let own = ShaderUse { file: "raycast_compute.wgsl", entry_point: entry, extra: &["params", "preintegrated"] };
        [vec![own], crate::effects::effect_shader_uses(params)].concat()
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // The mode picks the entry point and the workgroup size is a pipeline constant.
        is_iso(old) == is_iso(new)
            && same_effects(old, new)
            && Workgroup::from_params(old) == Workgroup::from_params(new)
    }
}

impl PassPlugin for RaycastCompute {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let wg = Workgroup::checked_size(ctx)?;
        let entry = if is_iso(ctx.params) { "cs_iso" } else { "cs_dvr" };
        let mut defines = effect_defines(ctx.params);
        if color_is_f32(ctx) {
            defines.push("COLOR_F32");
        }
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            shader: "raycast_compute.wgsl",
            entry,
            constants: &[("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)],
            defines: &defines,
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let effects = EffectState::new(ctx)?;
        Ok(Box::new(RaycastComputeNode {
            pipeline,
            params,
            workgroup: wg,
            effects,
            step_voxels: Sampling::from_params(ctx.params).step_voxels,
        }))
    }
}

struct RaycastComputeNode {
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
    workgroup: (u32, u32),
    effects: EffectState,
    step_voxels: f64,
}

impl PassNode for RaycastComputeNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.effects.update(ctx, &self.params, self.step_voxels)?;
        let mut extra = vec![("params", self.params.as_entire_binding())];
        extra.extend(self.effects.bindings());
        ctx.dispatch_over(&self.pipeline, &extra, "color", (self.workgroup.0, self.workgroup.1))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
        self.step_voxels = Sampling::from_params(params).step_voxels;
        self.effects.invalidate();
    }
}
