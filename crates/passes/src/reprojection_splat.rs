//! `reprojection_splat`: Klein et al. 2005 §4.3–4.4's first hole-filling step. Last frame's leap
//! hits (a history of the raycaster's `leap_hit`) are drawn with this frame's camera as k×k-pixel
//! splats — instanced quads pulling their point from the texture, since WebGPU has no point
//! size — depth-tested so the nearest start wins, only for the pixels of last frame's screen
//! rectangle of the volume (computed here from the previous camera). Writes `start` (xyz: the
//! texture-space start estimate, w = 1 where a splat landed) and its `depth`; `hole_fill`
//! completes the rest. With `block` b > 1 one quad stands for the nearest of b×b hits, drawn
//! over their projected bounding box grown by k/2: b² fewer quads (vertex work is most of a
//! splat's cost where the vertex stage is slow, as on lavapipe), starts never farther than the
//! hits they stand for. With `method: "scatter"` the same splats are written by a compute
//! pass instead of drawn (the nearest depth per pixel by an atomic, then the winner's point):
//! none of the rasterizer's per-quad setup, the same starts. Shader:
//! `shaders/reprojection_splat.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, DepthSpec, Gpu, PassError, RecordContext,
    RenderPassPipeline, RenderPipelineSpec,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct ReprojectionSplat;

volgraph_compiler::pass_params! {
    /// The `splat` block of `shaders/reprojection_splat.wgsl` (which imports it): what the node
    /// computes per frame.
    struct SplatParams {
        rect: [u32; 4] = computed,
            "Last frame's screen rectangle of the volume: origin x, y, width, height (pixels).";
        size: f32 = computed, "Splat edge in pixels (k).";
    }
}

volgraph_compiler::param_choice! {
    /// How the splats are drawn.
    pub enum SplatMethod {
        /// Instanced quads through the rasterizer, depth-tested (the paper's points).
        Quads = "quads",
        /// A compute pass writing each splat's pixels: nearest depth by atomicMax, then the point.
        Scatter = "scatter",
    }
}

volgraph_compiler::pass_params! {
    /// The pass's parameters, declared once (the GPU block adds the screen rectangle the node
    /// computes per frame, so it stays a struct of its own).
    pub struct SplatSettings {
        splat_size: u32 = 2, 1..=16, "splat edge k in pixels (the paper: two or four closes the gaps)";
        block: u32 = 1, 1..=4,
            "hits per splat side: one splat carries the nearest of a block×block of hits (block² fewer quads; the paper: 1)";
        method: SplatMethod = Quads,
            "quads: instanced quads through the rasterizer (the paper); scatter: a compute pass writes the same splats \
             (no per-quad setup: faster where the graphics pipeline is slow)";
    }
}

/// The splat quads and what they write, declared once for `shaders()` and `create`.
fn vertex() -> ShaderUse {
    ShaderUse::new("reprojection_splat.wgsl", "vs_splat").uniform(splat_layout())
}

fn fragment() -> ShaderUse {
    ShaderUse::new("reprojection_splat.wgsl", "fs_splat").uniform(splat_layout())
}

/// The scatter's rounds: clear every pixel, nearest depth per pixel, the winners' points.
fn scatter_rounds() -> [ShaderUse; 3] {
    [
        ShaderUse::new("reprojection_splat.wgsl", "cs_splat_clear"),
        ShaderUse::new("reprojection_splat.wgsl", "cs_splat_depth").uniform(splat_layout()),
        ShaderUse::new("reprojection_splat.wgsl", "cs_splat_point").uniform(splat_layout()),
    ]
}

/// The scatter's workgroup (`@workgroup_size` of both rounds): one invocation per block.
const SCATTER_WORKGROUP: (u32, u32) = (8, 8);

fn scatters(params: &Params) -> bool {
    SplatSettings::from_params(params).method == SplatMethod::Scatter
}

/// The `splat` block, checked against the shader's struct when the graph is planned. The node writes it per frame (last frame's screen
/// rectangle of the volume).
fn splat_layout() -> volgraph_compiler::UniformLayout {
    SplatParams::bound_as_with("splat", Vec::new(), |_| SplatParams { rect: [0; 4], size: 0.0 }.uniform_bytes())
}

impl PassDecl for ReprojectionSplat {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "reprojection_splat"
    }

    fn summary(&self) -> &'static str {
        "last frame's hit points reprojected as depth-tested k×k splats: ray start estimates (Klein et al. 2005 §4.3–4.4)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![
            SplatSettings::block(OnChange::InPlace)
                .with_defines(|p| if scatters(p) { vec![crate::defines::SCATTER] } else { Vec::new() }),
        ]
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        // The depth test's buffer: a depth target for quads, a u32 per pixel for the scatter.
        let depth = if scatters(params) {
            PortKind::Buffer { bytes: 0, bytes_per_pixel: 4 }
        } else {
            PortKind::target(&[TargetFormat::Depth32Float])
        };
        vec![
            PortSpec::read("hits", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("start", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("depth", depth),
        ]
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        if scatters(params) { scatter_rounds().to_vec() } else { vec![vertex(), fragment()] }
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // The edge is a uniform; the method picks other entry points (the blocks' rule) and
        // the block is a pipeline constant (`SPLAT_BLOCK`).
        let block = |p: &Params| SplatSettings::from_params(p).block;
        self.only_in_place_blocks_change(old, new) && block(old) == block(new)
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for ReprojectionSplat {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let settings = SplatSettings::from_params(ctx.params);
        let constants = [("SPLAT_BLOCK", f64::from(settings.block))];
        let draw = if scatters(ctx.params) {
            let defines = self.shader_defines(ctx.params);
            let [clear, depth, point] = scatter_rounds();
            let round = |shader: &ShaderUse| {
                ctx.compute_pipeline(&ComputePipelineSpec {
                    defines: &defines,
                    constants: &constants,
                    ..ComputePipelineSpec::of(shader)
                })
            };
            Draw::Scatter(Box::new(ScatterRounds {
                clear: round(&clear)?,
                depth: round(&depth)?,
                point: round(&point)?,
            }))
        } else {
            Draw::Quads(ctx.render_pipeline(&RenderPipelineSpec {
                depth: Some(DepthSpec { port: "depth", write: true, compare: wgpu::CompareFunction::Less }),
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                constants: &constants,
                ..RenderPipelineSpec::drawing(&vertex(), &fragment())
            })?)
        };
        let uniform = ctx.uniform_from_bytes("splat", &SplatParams { rect: [0; 4], size: 0.0 }.uniform_bytes());
        let (size, block) = (settings.splat_size as f32, settings.block);
        Ok(Box::new(SplatNode { draw, uniform, size, block, written: None }))
    }
}

#[cfg(feature = "gpu")]
/// The pipelines of a `method`.
enum Draw {
    Quads(RenderPassPipeline),
    Scatter(Box<ScatterRounds>),
}

#[cfg(feature = "gpu")]
/// The scatter's three compute pipelines (`scatter_rounds`).
struct ScatterRounds {
    clear: ComputePassPipeline,
    depth: ComputePassPipeline,
    point: ComputePassPipeline,
}

#[cfg(feature = "gpu")]
struct SplatNode {
    draw: Draw,
    uniform: wgpu::Buffer,
    size: f32,
    block: u32,
    written: Option<SplatParams>,
}

#[cfg(feature = "gpu")]
impl PassNode for SplatNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // Last frame's hits lie in last frame's rectangle; without a last frame history holds
        // its initial value (no hits) and nothing is drawn.
        let rect = match (&ctx.frame.previous_camera, &ctx.frame.volume) {
            (Some(previous), Some(volume)) if ctx.frame.history_age > 0 => {
                crate::shared::screen_rect(previous, volume.half_extent, ctx.frame.viewport)
            }
            _ => [0; 4],
        };
        let settings = SplatParams { rect, size: self.size };
        if self.written != Some(settings) {
            ctx.write_buffer(&self.uniform, 0, &settings.uniform_bytes());
            self.written = Some(settings);
        }
        let (bx, by) = (rect[2].div_ceil(self.block), rect[3].div_ceil(self.block));
        let splat = [("splat", self.uniform.as_entire_binding())];
        match &self.draw {
            Draw::Quads(pipeline) => {
                let bg = ctx.bind_group(pipeline, &splat)?;
                let mut pass = ctx.begin_render_pass(pipeline, Some(1.0))?;
                if bx * by > 0 {
                    pass.set_pipeline(&pipeline.pipeline);
                    pass.set_bind_group(0, &bg, &[]);
                    pass.draw(0..4, 0..bx * by);
                }
            }
            Draw::Scatter(rounds) => {
                let ScatterRounds { clear, depth, point } = rounds.as_ref();
                let clear_bg = ctx.bind_group(clear, &[])?;
                let (depth_bg, point_bg) = (ctx.bind_group(depth, &splat)?, ctx.bind_group(point, &splat)?);
                let mut pass = ctx.begin_compute_pass();
                // Every pixel starts without a splat: a round of its own, not a clear of the
                // target (lavapipe clears 128-bit texels one memcpy at a time, outside a draw).
                let (w, h) = ctx.viewport;
                pass.set_pipeline(&clear.pipeline);
                pass.set_bind_group(0, &clear_bg, &[]);
                pass.dispatch_workgroups(w.div_ceil(SCATTER_WORKGROUP.0), h.div_ceil(SCATTER_WORKGROUP.1), 1);
                if bx * by > 0 {
                    let groups = (bx.div_ceil(SCATTER_WORKGROUP.0), by.div_ceil(SCATTER_WORKGROUP.1));
                    for (pipeline, bg) in [(depth, &depth_bg), (point, &point_bg)] {
                        pass.set_pipeline(&pipeline.pipeline);
                        pass.set_bind_group(0, bg, &[]);
                        pass.dispatch_workgroups(groups.0, groups.1, 1);
                    }
                }
            }
        }
        Ok(())
    }

    fn update_params(&mut self, _gpu: &Gpu, params: &Params) {
        // Only the edge: a new block is a new pipeline (`updates_in_place`).
        self.size = SplatSettings::from_params(params).splat_size as f32;
        self.written = None;
    }
}

#[cfg(test)]
mod tests {
    use volgraph_compiler::{ParamValue, Params, PassDecl};

    use super::ReprojectionSplat;

    fn params(edits: &[(&str, ParamValue)]) -> Params {
        let mut params = Params::defaults(&ReprojectionSplat.params());
        for (name, value) in edits {
            params.set(name, value.clone());
        }
        params
    }

    /// The splat edge is a uniform, edited in place; the block is the pipeline constant
    /// `SPLAT_BLOCK` and the method a pipeline of its own, so editing either rebuilds the node.
    #[test]
    fn only_the_splat_edge_updates_in_place() {
        let base = params(&[]);
        assert!(ReprojectionSplat.updates_in_place(&base, &params(&[("splat_size", ParamValue::UInt(4))])));
        assert!(!ReprojectionSplat.updates_in_place(&base, &params(&[("block", ParamValue::UInt(2))])));
        assert!(
            !ReprojectionSplat.updates_in_place(&base, &params(&[("method", ParamValue::Choice("scatter".into()))]))
        );
    }
}
