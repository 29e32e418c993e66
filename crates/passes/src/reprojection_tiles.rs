//! `reprojection_tiles`: Klein et al. 2005 §4.3–4.4 with conservative per-tile depth bounds in
//! place of per-pixel splats and hole filling. Last frame's leap hits (a history of the
//! raycaster's `leap_hit`) are reprojected with this frame's camera; every `tile`×`tile`
//! screen tile keeps the nearest view depth among the hits that land on it or within `margin`
//! pixels of it (each tile by the hits near it alone, as if every hit were splatted on its
//! own), and a raycaster wired to `tiles` (its `start_tiles` input) starts each ray of the tile
//! at that depth, on the ray's own step grid, `step_back` samples early. A tile no hit reached,
//! or one within `silhouette_band` pixels of the volume's silhouette, starts at the box.
//!
//! Why tiles: per pixel, the splats and the hole fill cost as much as a third of the march they
//! shorten (9.0 + 2.8 ms against an 11.7 ms march for a tooth at 512², issue 47); here one
//! compute invocation reads a `hit_block`² block of hits, takes per tile the nearest of the hits
//! near it in registers and raises one atomic per tile the block touches — a few per block —
//! and the march reads one word per pixel. And a tile's bound is never farther than the
//! per-pixel splats of half size `margin` would put any of its pixels, so a start errs on the
//! early (exact) side where a surface appears between last frame's hits. Shader:
//! `shaders/reprojection_tiles.wgsl`; the layout the march reads:
//! `shaders/common/reprojected_tiles.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct ReprojectionTiles;

volgraph_compiler::pass_params! {
    /// The parameters, declared once: spec, typed values and `TileBoundsParams` of
    /// `shaders/reprojection_tiles.wgsl` (`tile` and `hit_block` are also its pipeline
    /// constants `TILE` and `HIT_BLOCK`).
    pub struct TileBoundsParams {
        tile: u32 = 4, 1..=32, "tile edge in pixels: every ray of a tile starts at the tile's nearest reprojected depth";
        hit_block: u32 = 4, 1..=16, "last frame's hits one invocation reads per side (fewer atomics, the same bounds)";
        margin: u32 = 4, 0..=16,
            "a hit bounds the tiles within this many pixels of where it lands (the paper's 4×4 splats reach 2; \
             4 leaves every test frame the plain raycast's)";
        silhouette_band: u32 = 2, 0..=16,
            "tiles this close to the volume's silhouette start at the box (rays newly in view enter it before any old hit)";
        rect_x: u32 = computed, "last frame's screen rectangle of the volume (pixels), where its hits can be: origin x";
        rect_y: u32 = computed, "… origin y";
        rect_w: u32 = computed, "… width";
        rect_h: u32 = computed, "… height";
    }
}

/// The two rounds: header and keys cleared (tiles near the silhouette marked), then the hits
/// scattered.
fn rounds() -> [ShaderUse; 2] {
    [
        ShaderUse::new("reprojection_tiles.wgsl", "cs_tiles_clear").uniform(TileBoundsParams::bound_as("tile_bounds")),
        ShaderUse::new("reprojection_tiles.wgsl", "cs_tiles_scatter")
            .uniform(TileBoundsParams::bound_as("tile_bounds")),
    ]
}

/// The workgroup of both rounds (`@workgroup_size`).
const WORKGROUP: (u32, u32) = (8, 8);

impl PassDecl for ReprojectionTiles {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "reprojection_tiles"
    }

    fn summary(&self) -> &'static str {
        "last frame's hit points reprojected as conservative per-tile depth bounds: ray starts without splats or \
         hole filling (Klein et al. 2005 §4.3–4.4)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![TileBoundsParams::block(OnChange::InPlace)]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        // One word per tile and a header: four bytes per pixel holds it for any tile edge.
        vec![
            PortSpec::read("hits", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("tiles", PortKind::Buffer { bytes: 16, bytes_per_pixel: 4 }),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        rounds().to_vec()
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // `tile` and `hit_block` are pipeline constants; the margin and the band uniforms.
        let constants = |p: &Params| {
            let block = TileBoundsParams::from_params(p);
            (block.tile, block.hit_block)
        };
        self.only_in_place_blocks_change(old, new) && constants(old) == constants(new)
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for ReprojectionTiles {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let settings = TileBoundsParams::from_params(ctx.params);
        let constants = [("TILE", f64::from(settings.tile)), ("HIT_BLOCK", f64::from(settings.hit_block))];
        let uses = rounds();
        let round = |shader: &ShaderUse| {
            ctx.compute_pipeline(&ComputePipelineSpec { constants: &constants, ..ComputePipelineSpec::of(shader) })
        };
        let [clear, scatter] = [round(&uses[0])?, round(&uses[1])?];
        let uniform = ctx.uniform_from_bytes("tile_bounds", &settings.uniform_bytes());
        Ok(Box::new(TilesNode { clear, scatter, uniform, settings, written: None }))
    }
}

#[cfg(feature = "gpu")]
struct TilesNode {
    clear: ComputePassPipeline,
    scatter: ComputePassPipeline,
    /// `tile_bounds`: the parameters and last frame's screen rectangle, written where it changed.
    uniform: wgpu::Buffer,
    settings: TileBoundsParams,
    written: Option<TileBoundsParams>,
}

#[cfg(feature = "gpu")]
impl PassNode for TilesNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // Last frame's hits lie in last frame's screen rectangle of the volume; without a last
        // frame history holds its initial value (no hits) and nothing is scattered.
        let rect = match (&ctx.frame.previous_camera, &ctx.frame.volume) {
            (Some(previous), Some(volume)) if ctx.frame.history_age > 0 => {
                crate::shared::screen_rect(previous, volume.half_extent, ctx.frame.viewport)
            }
            _ => [0; 4],
        };
        let block =
            TileBoundsParams { rect_x: rect[0], rect_y: rect[1], rect_w: rect[2], rect_h: rect[3], ..self.settings };
        if self.written != Some(block) {
            ctx.write_buffer(&self.uniform, 0, &block.uniform_bytes());
            self.written = Some(block);
        }
        let bindings = [("tile_bounds", self.uniform.as_entire_binding())];
        let clear_bg = ctx.bind_group(&self.clear, &bindings)?;
        let scatter_bg = ctx.bind_group(&self.scatter, &bindings)?;
        let (w, h) = ctx.viewport;
        let tiles = (w.div_ceil(self.settings.tile), h.div_ceil(self.settings.tile));
        let blocks = (rect[2].div_ceil(self.settings.hit_block), rect[3].div_ceil(self.settings.hit_block));
        let mut pass = ctx.begin_compute_pass();
        pass.set_pipeline(&self.clear.pipeline);
        pass.set_bind_group(0, &clear_bg, &[]);
        pass.dispatch_workgroups(tiles.0.div_ceil(WORKGROUP.0), tiles.1.div_ceil(WORKGROUP.1), 1);
        if blocks.0 * blocks.1 > 0 {
            pass.set_pipeline(&self.scatter.pipeline);
            pass.set_bind_group(0, &scatter_bg, &[]);
            pass.dispatch_workgroups(blocks.0.div_ceil(WORKGROUP.0), blocks.1.div_ceil(WORKGROUP.1), 1);
        }
        Ok(())
    }

    fn update_params(&mut self, _gpu: &Gpu, params: &Params) {
        // Only the uniforms: a new tile or block is a new pipeline (`updates_in_place`); the
        // block is written with this frame's rectangle when the pass next records.
        self.settings = TileBoundsParams::from_params(params);
        self.written = None;
    }
}

#[cfg(test)]
mod tests {
    use volgraph_compiler::{ParamValue, Params, PassDecl};

    use super::ReprojectionTiles;

    fn params(edits: &[(&str, ParamValue)]) -> Params {
        let mut params = Params::defaults(&ReprojectionTiles.params());
        for (name, value) in edits {
            params.set(name, value.clone());
        }
        params
    }

    /// The margin and the band are uniforms, edited in place; the tile edge and the hit block
    /// are pipeline constants, so editing either rebuilds the node.
    #[test]
    fn only_the_margin_and_band_update_in_place() {
        let base = params(&[]);
        assert!(ReprojectionTiles.updates_in_place(&base, &params(&[("margin", ParamValue::UInt(4))])));
        assert!(ReprojectionTiles.updates_in_place(&base, &params(&[("silhouette_band", ParamValue::UInt(0))])));
        assert!(!ReprojectionTiles.updates_in_place(&base, &params(&[("tile", ParamValue::UInt(8))])));
        assert!(!ReprojectionTiles.updates_in_place(&base, &params(&[("hit_block", ParamValue::UInt(2))])));
    }
}
