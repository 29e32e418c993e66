//! `hole_fill`: Klein et al. 2005 §4.4's two hole-filling steps — a pixel that no reprojected
//! splat reached first takes the start nearest the eye among the splats within `extend` pixels
//! (an extended splat drawn only into holes; `reprojection_splat`'s own `splat_size` is the
//! paper's extended point size), and a pixel still without one starts its ray at the box's
//! front face, met analytically (the entry of a raycaster with `rays: "analytic"`). Also
//! every pixel within `silhouette_band` pixels of the footprint's edge: while the volume turns,
//! a k×k splat can carry a neighbour's hit across the silhouette into a pixel whose ray, newly
//! in view, meets the box in front of that hit (`crates/passes/tests/klein_2005.rs` tests the
//! rule). Whether a pixel is that close comes from the footprint's convex polygon, which the
//! node turns into one span per image row each frame (`volgraph_core::runtime::footprint`;
//! the frame block holds the same polygon grown, for the draw). Reads the splats' `splats`
//! start target, writes `start`. Shader: `shaders/hole_fill.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec, UniformBlocks,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct HoleFill;

volgraph_compiler::pass_params! {
    /// The parameters, declared once: spec, typed values and `HoleParams` of
    /// `shaders/hole_fill.wgsl` (a test compares the two).
    pub struct HoleParams {
        silhouette_band: i32 = 2, 0..=8,
            "pixels this close to the footprint's edge start at the box (at least the splat's half size)";
        extend: i32 = 1, 0..=4, "a hole takes the nearest start among the splats this many pixels around it";
    }
}

/// Its one pipeline, declared once (file, entry point, the uniform block `holes`, the footprint's
/// row spans the node writes each frame).
fn shader() -> ShaderUse {
    ShaderUse::new("hole_fill.wgsl", "fs_hole").uniform(HoleParams::bound_as("holes")).binds(&["footprint_rows"])
}

/// How far inside the footprint (pixels) a pixel centre must lie for its row's span
/// (`volgraph_core::runtime::footprint`): the polygon is exact in f64 and the shader meets rays
/// with the box in f32, whose rounding moves a silhouette by far less than this at any viewport
/// the GPU can hold.
const FOOTPRINT_MARGIN: f64 = 1.0 / 64.0;

impl PassDecl for HoleFill {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "hole_fill"
    }

    fn summary(&self) -> &'static str {
        "pixels without a reprojected start, or near the silhouette, begin at the box's front faces (Klein et al. 2005 §4.4)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // A uniform the node rewrites (its `UniformBlocks`).
        vec![HoleParams::block(OnChange::InPlace)]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("splats", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("start", PortKind::target(&[TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for HoleFill {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let shader = shader();
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec::footprint(&shader))?;
        let uniforms = UniformBlocks::create(ctx, &[shader]);
        Ok(Box::new(HoleFillNode { pipeline, uniforms, rows: None }))
    }
}

#[cfg(feature = "gpu")]
struct HoleFillNode {
    pipeline: RenderPassPipeline,
    uniforms: UniformBlocks,
    /// The footprint's row spans (`vec2<f32>` per image row) and what they were written from.
    rows: Option<(wgpu::Buffer, Vec<[f32; 2]>)>,
}

#[cfg(feature = "gpu")]
impl HoleFillNode {
    /// This frame's row spans, written where they changed.
    fn footprint_rows(&mut self, ctx: &RecordContext<'_>) -> &wgpu::Buffer {
        let spans = ctx.footprint.row_spans(ctx.viewport.1.max(1), FOOTPRINT_MARGIN);
        if self.rows.as_ref().is_none_or(|(_, written)| written.len() != spans.len()) {
            let buffer = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{} footprint rows", ctx.label)),
                size: std::mem::size_of_val(spans.as_slice()) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.rows = Some((buffer, Vec::new()));
        }
        let (buffer, written) = self.rows.as_mut().expect("created above");
        if *written != spans {
            ctx.write_buffer(buffer, 0, bytemuck::cast_slice(&spans));
            *written = spans;
        }
        buffer
    }
}

#[cfg(feature = "gpu")]
impl PassNode for HoleFillNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let rows = self.footprint_rows(ctx).clone();
        let mut bindings = self.uniforms.bindings();
        bindings.push(("footprint_rows", rows.as_entire_binding()));
        let bg = ctx.bind_group(&self.pipeline, &bindings)?;
        ctx.draw_footprint(&self.pipeline, &bg)
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.uniforms.write(gpu, params);
    }
}
