//! `fetch_probe`: the fetch ceiling of `volgraph bench fetch` — a compute pass that takes every
//! sample a raycaster with the same step would take along each pixel's ray (the analytic ray of
//! `raycast_compute` with `rays: "analytic"`, no leaping, no termination) and does nothing else with them (no
//! classification, no compositing). Its trilinear samples per second bound any raycaster's on
//! the same device, volume and texture format, so `volgraph bench graphs` reports each graph's
//! counted samples per second as a fraction of it. Writes the mean scalar along the ray (an
//! average-intensity projection) to `color`, and with `count_samples` the samples it took to
//! `samples`. Shader: `shaders/fetch_probe.wgsl`.

use crate::raycast_params::sampling_block;
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use crate::march::SAMPLE_ROWS;
use crate::raycast_params::{RaycastParamsGpu, Workgroup};

/// The plugin.
pub struct FetchProbe;

volgraph_compiler::pass_params! {
    /// Whether the probe counts its samples.
    pub struct Counting {
        count_samples: bool = false, "write the number of samples taken to the `samples` buffer";
    }
}

/// The pass's entry point (counting samples or not), declared once for `shaders()` and `create`.
fn shader(params: &Params) -> ShaderUse {
    let entry_point = if Counting::from_params(params).count_samples { "cs_counted" } else { "cs_main" };
    ShaderUse::new("fetch_probe.wgsl", entry_point).uniform(RaycastParamsGpu::bound("params"))
}

impl PassDecl for FetchProbe {
    fn kind(&self) -> &'static str {
        "fetch_probe"
    }

    fn summary(&self) -> &'static str {
        "fetch ceiling: every raycast sample along each pixel's ray, no classification or compositing (benchmarks)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![sampling_block(OnChange::InPlace), Counting::block(OnChange::Rebuild), Workgroup::block(OnChange::Rebuild)]
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float])),
        ];
        if Counting::from_params(params).count_samples {
            ports.push(PortSpec::write("samples", PortKind::buffer(4 * SAMPLE_ROWS)));
        }
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        vec![shader(params)]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for FetchProbe {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let wg = Workgroup::checked_size(ctx)?;
        let counted = Counting::from_params(ctx.params).count_samples;
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            constants: &[("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)],
            defines: &self.shader_defines(ctx.params),
            ..ComputePipelineSpec::of(&shader(ctx.params))
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        Ok(Box::new(FetchProbeNode { pipeline, params, workgroup: wg, counted }))
    }
}

#[cfg(feature = "gpu")]
struct FetchProbeNode {
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
    workgroup: (u32, u32),
    counted: bool,
}

#[cfg(feature = "gpu")]
impl PassNode for FetchProbeNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        if self.counted {
            ctx.clear_buffer("samples")?;
        }
        ctx.dispatch_over(
            &self.pipeline,
            &[("params", self.params.as_entire_binding())],
            "color",
            (self.workgroup.0, self.workgroup.1),
        )
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
    }
}
