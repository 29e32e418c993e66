//! `hole_fill`: Klein et al. 2005 §4.4's two hole-filling steps — a pixel that no reprojected
//! splat reached first takes the start nearest the eye among the splats within `extend` pixels
//! (an extended splat drawn only into holes; `reprojection_splat`'s own `splat_size` is the
//! paper's extended point size), and a pixel still without one starts its ray at the box's
//! front face, met analytically (the entry of a raycaster with `rays: "analytic"`). Also
//! every pixel within `silhouette_band` pixels of the footprint's edge: while the volume turns,
//! a k×k splat can carry a neighbour's hit across the silhouette into a pixel whose ray, newly
//! in view, meets the box in front of that hit (`crates/passes/tests/klein_2005.rs` measures
//! it). Reads the splats' `splats` start target, writes `start`. Shader: `shaders/hole_fill.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
use volgraph_core::{ParamSpec, Params, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

/// The plugin.
pub struct HoleFill;

/// Rust twin of `HoleParams` in `shaders/hole_fill.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct HoleParamsGpu {
    band: i32,
    extend: i32,
    _pad: [i32; 2],
}

impl HoleParamsGpu {
    fn from_params(params: &Params) -> Self {
        Self { band: params.uint("silhouette_band") as i32, extend: params.uint("extend") as i32, _pad: [0; 2] }
    }
}

const _: () = assert!(std::mem::size_of::<HoleParamsGpu>() == 16);

impl PassPlugin for HoleFill {
    fn kind(&self) -> &'static str {
        "hole_fill"
    }

    fn summary(&self) -> &'static str {
        "pixels without a reprojected start, or near the silhouette, begin at the box's front faces (Klein et al. 2005 §4.4)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::uint(
                "silhouette_band",
                2,
                0,
                8,
                "pixels this close to the footprint's edge start at the box (at least the splat's half size)",
            ),
            ParamSpec::uint(
                "extend",
                1,
                0,
                4,
                "a hole takes the nearest start among the splats this many pixels around it",
            ),
        ]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("splats", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("start", PortKind::target(&[TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse { file: "hole_fill.wgsl", entry_point: "fs_hole", extra: &["holes"] }]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }

    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: "hole_fill.wgsl",
            vertex: "vs_fullscreen",
            fragment: "fs_hole",
            extra_bindings: &["holes"],
            ..Default::default()
        })?;
        let uniform = ctx.uniform_with("holes", &HoleParamsGpu::from_params(ctx.params));
        Ok(Box::new(HoleFillNode { pipeline, uniform }))
    }
}

struct HoleFillNode {
    pipeline: RenderPassPipeline,
    uniform: wgpu::Buffer,
}

impl PassNode for HoleFillNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[("holes", self.uniform.as_entire_binding())])?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        crate::draw(&mut pass, &self.pipeline, &bg, 0..3);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&HoleParamsGpu::from_params(params)));
    }
}
