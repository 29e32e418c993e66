//! `raycast`: the single-pass fragment raycaster — Krüger & Westermann 2003 §2.1's ray
//! integration in one loop over the whole ray, front-to-back compositing with opacity
//! correction for the step size, early ray termination at a threshold, and §2.2's first-hit
//! isosurface with Blinn–Phong shading from central differences (mode `iso`, which also writes a
//! `hit` target of texture-space hit positions). The integral itself is
//! `shaders/common/raymarch.wgsl`, shared with `raycast_compute`; the conventions are
//! `docs/rendering_model.md`. Shader: `shaders/raycast.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CreateContext, Gpu, PassError, PassPipeline, RecordContext, RenderPipelineSpec};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

use crate::effects::{EffectState, effect_defines, effect_param_specs, same_effects, with_effect_bindings};
use crate::raycast_params::{RaycastParamsGpu, is_iso, raycast_param_specs};

/// The plugin.
pub struct Raycast;

const FLOAT_TARGETS: [TargetFormat; 2] = [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float];

/// The ports shared by both raycasters; `color_formats` differ (compute writes a storage texture
/// of one format).
pub(crate) fn raycast_ports(params: &Params, color: &[TargetFormat], hit: &[TargetFormat]) -> Vec<PortSpec> {
    let mut ports = vec![
        PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
        PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)),
        PortSpec::read("volume", PortKind::Volume),
        PortSpec::read("tf", PortKind::TransferFunction),
        PortSpec::write("color", PortKind::target(color)),
    ];
    if is_iso(params) {
        ports.push(PortSpec::write("hit", PortKind::target(hit)));
    }
    ports
}

impl PassPlugin for Raycast {
    fn kind(&self) -> &'static str {
        "raycast"
    }

    fn summary(&self) -> &'static str {
        "single-pass fragment raycaster, DVR or first-hit isosurface (Krüger–Westermann 2003 §2.1–2.2)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        let mut p = raycast_param_specs();
        p.extend(effect_param_specs());
        p
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        effect_defines(params)
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        raycast_ports(
            params,
            &[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float],
            &[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float],
        )
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let fragment = if is_iso(params) { "fs_iso" } else { "fs_dvr" };
        vec![ShaderUse { file: "raycast.wgsl", entry_point: fragment }]
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // Every parameter but the mode and the effects is a uniform value.
        is_iso(old) == is_iso(new) && same_effects(old, new)
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let fragment = if is_iso(ctx.params) { "fs_iso" } else { "fs_dvr" };
        let defines = effect_defines(ctx.params);
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: "raycast.wgsl",
            vertex: "vs_fullscreen",
            fragment,
            extra_bindings: &with_effect_bindings(&["params"]),
            defines: &defines,
            ..Default::default()
        })?;
        let params = ctx.uniform_with("params", &RaycastParamsGpu::from_params(ctx.params));
        let effects = EffectState::new(ctx)?;
        Ok(Box::new(RaycastNode { pipeline, params, effects, step_voxels: ctx.params.float("step_voxels") }))
    }
}

struct RaycastNode {
    pipeline: PassPipeline,
    params: wgpu::Buffer,
    effects: EffectState,
    step_voxels: f64,
}

impl PassNode for RaycastNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.effects.update(ctx, &self.params, self.step_voxels)?;
        let mut extra = vec![("params", self.params.as_entire_binding())];
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
    }
}
