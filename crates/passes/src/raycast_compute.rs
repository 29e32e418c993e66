//! `raycast_compute`: the same integral as `raycast` in a compute shader writing a storage
//! texture, one invocation per pixel — the DirectCompute thesis's compute raycaster
//! (`RAYCASTSIMPLE_CS`). The workgroup size is a parameter (pipeline-overridable constants).
//! Shader: `shaders/raycast_compute.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    ComputePipelineSpec, CreateContext, Gpu, PassError, PassPipeline, PipelineKind, RecordContext,
};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortSpec, TargetFormat};

use crate::raycast::raycast_ports;
use crate::raycast_params::{RaycastParamsGpu, is_iso, raycast_param_specs};

/// The plugin.
pub struct RaycastCompute;

impl PassPlugin for RaycastCompute {
    fn kind(&self) -> &'static str {
        "raycast_compute"
    }

    fn summary(&self) -> &'static str {
        "compute-shader raycaster writing a storage texture (DirectCompute thesis, RAYCASTSIMPLE_CS)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        let mut p = raycast_param_specs();
        p.push(ParamSpec::uint("workgroup_x", 8, 1, 256, "workgroup width in pixels"));
        p.push(ParamSpec::uint("workgroup_y", 8, 1, 256, "workgroup height in pixels"));
        p
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        // The storage formats are fixed by the shader: rgba16float colour, rgba32float hits.
        raycast_ports(params, &[TargetFormat::Rgba16Float], &[TargetFormat::Rgba32Float])
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let entry = if is_iso(params) { "cs_iso" } else { "cs_dvr" };
        vec![ShaderUse { file: "raycast_compute.wgsl", entry_point: entry }]
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // The mode picks the entry point and the workgroup size is a pipeline constant.
        is_iso(old) == is_iso(new)
            && old.uint("workgroup_x") == new.uint("workgroup_x")
            && old.uint("workgroup_y") == new.uint("workgroup_y")
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let wg = (ctx.params.uint("workgroup_x") as u32, ctx.params.uint("workgroup_y") as u32);
        if wg.0 * wg.1 > ctx.gpu.limits.max_compute_invocations_per_workgroup {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "workgroup {}x{} has {} invocations, over this GPU's limit of {}",
                    wg.0,
                    wg.1,
                    wg.0 * wg.1,
                    ctx.gpu.limits.max_compute_invocations_per_workgroup
                ),
            });
        }
        let entry = if is_iso(ctx.params) { "cs_iso" } else { "cs_dvr" };
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            shader: "raycast_compute.wgsl",
            entry,
            extra_bindings: &["params"],
            constants: &[("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)],
        })?;
        let params = ctx.uniform_with("params", &RaycastParamsGpu::from_params(ctx.params));
        Ok(Box::new(RaycastComputeNode { pipeline, params, workgroup: wg }))
    }
}

struct RaycastComputeNode {
    pipeline: PassPipeline,
    params: wgpu::Buffer,
    workgroup: (u32, u32),
}

impl PassNode for RaycastComputeNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[("params", self.params.as_entire_binding())])?;
        let (w, h) = ctx.extent("color");
        let mut pass = ctx.begin_compute_pass();
        if let PipelineKind::Compute(p) = &self.pipeline.pipeline {
            pass.set_pipeline(p);
        }
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(w.div_ceil(self.workgroup.0), h.div_ceil(self.workgroup.1), 1);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&RaycastParamsGpu::from_params(params)));
    }
}
