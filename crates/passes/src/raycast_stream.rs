//! `raycast_stream`: ray-guided multiresolution DVR of a volume read brick by brick — an
//! OME-Zarr pyramid larger than memory, or any volume as an in-memory pyramid — after Hadwiger
//! et al. 2012 ("Interactive volume exploration of petascale microscopy data streams using a
//! visualization-driven virtual memory approach", §4 ray-guided brick requests, §5 the page
//! table and cache) and Crassin et al. 2009 (GigaVoxels §5: usage feedback, LRU).
//!
//! - **levels**: level l of the pyramid (`volgraph_accel::pyramid`) has voxels 2ˡ level-0 voxels
//!   wide; a sample takes the coarsest level whose voxel is at most `lod` pixels wide where it
//!   lies (about a pixel at rest; `lod_moving` while the camera moves, coarser), and a run of
//!   samples through a brick of level l takes every 2ˡ-th sample of the ray's grid with its
//!   opacity corrected for that step — so at rest, fully loaded, with every level 0, the samples
//!   and image are those of every raycaster.
//! - **page table and feedback** ([`crate::stream_cache`]): per brick of every level a word
//!   (resident slot, empty under the TF, or nothing yet); the march records the bricks it wanted
//!   and lacked, and those it drew, in a feedback buffer read back the next frame. A missing
//!   brick is drawn from the finest coarser level resident; the coarsest level is read first and
//!   pinned, so a frame never waits for disk.
//! - **readers** ([`crate::stream_loader`]): threads read the requested bricks, coarse before
//!   fine and near before far, while frames go on; each frame places what arrived (least
//!   recently drawn slots evicted, never one the last frame drew). A brick whose value range
//!   the source knows unread (an OME-Zarr store's chunk ranges) and the TF leaves transparent is
//!   never read.
//! - **bricks** keep an apron (one voxel, two with shading, three with tricubic, four with both),
//!   clamped at the level's faces, so filters near a brick face blend what the level holds and
//!   levels meet without seams.
//!
//! Effects: shading, tricubic and jitter, as the shared march does them; pre-integration,
//! shadows and ambient occlusion need the whole volume at once (a table for one step, a light
//! volume) and are not offered. Shader: `shaders/raycast_stream.wgsl`.

use crate::effects::{EffectFlags, effect_block};
use crate::raycast_params::{RaycastParamsGpu, SampleLoopChoice, Shading, Termination, Workgroup, sampling_block};
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};

#[cfg(feature = "gpu")]
mod node;

/// The plugin.
pub struct RaycastStream;

/// The scene effects this raycaster offers (the shared march's, where a brick at a time suffices).
pub const STREAM_EFFECTS: [&str; 3] = ["shading", "tricubic", "jitter"];

volgraph_compiler::pass_params! {
    /// The streaming raycaster's own parameters.
    pub struct StreamSettings {
        brick_cells: u32 = 64, 4..=256, "voxels per brick side at every level (an OME-Zarr store reads best at its chunk size)";
        lod: f32 = 1.0, 0.125..=64.0,
            "level of detail at rest: a sample takes the coarsest level whose voxel is at most this many pixels wide (0.125..1: finer than a pixel)";
        lod_moving: f32 = 4.0, 0.125..=64.0, "the same while the camera moves (coarser: faster frames)";
        pool_mb: u32 = 0, 0..=1048576,
            "brick pool budget in MiB (0: the runtime's --gpu-memory-mb, else 1 GiB), at most what every brick of every level needs";
        readers: u32 = 0, 0..=64, "threads reading bricks (0: one per core, at least 2)";
        uploads_per_frame: u32 = 1024, 1..=65536, "bricks placed in the pool per frame at most (the rest wait for the next)";
    }
}

volgraph_compiler::pass_params! {
    /// The `stream` block of `shaders/raycast_stream.wgsl`: the pool's shape, written by the node.
    struct StreamParams {
        brick: [u32; 4] = computed, "x = voxels per brick side, y = apron, z = voxels per slot side, w = levels.";
        atlas: [f32; 4] = computed, "Atlas size in texels (xyz).";
        lod: [f32; 4] = computed, "x = this frame's level of detail (pixels per level voxel).";
    }
}

impl StreamParams {
    const EMPTY: Self = Self { brick: [0, 0, 0, 1], atlas: [1.0; 4], lod: [1.0; 4] };
}

impl PassDecl for RaycastStream {
    fn kind(&self) -> &'static str {
        "raycast_stream"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &STREAM_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "compute DVR of a volume streamed brick by brick from a resolution pyramid (an OME-Zarr store larger than \
         memory): rays request the bricks and levels they need, readers load them while frames go on (Hadwiger et \
         al. 2012, Crassin et al. 2009)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![
            sampling_block(OnChange::InPlace),
            Termination::block(OnChange::InPlace),
            effect_block(),
            Shading::block(OnChange::InPlace),
            StreamSettings::block(OnChange::Rebuild),
            Workgroup::block(OnChange::Rebuild),
            SampleLoopChoice::rebuild_block(),
        ]
    }

    fn uses_gpu_memory_budget(&self) -> bool {
        true
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::VolumeVoxels),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![march_shader()]
    }

    fn takes_cuts(&self) -> bool {
        true
    }
}

/// The effects of `params` this raycaster cannot draw, with why: they need the whole volume at
/// once (a pre-integration table for one step, a light volume).
fn unoffered_effect(params: &Params) -> Option<String> {
    let flags = EffectFlags::of(params);
    [
        (flags.preintegration, "preintegration"),
        (flags.shadows, "shadows"),
        (flags.ambient_occlusion, "ambient_occlusion"),
    ]
    .into_iter()
    .find(|(on, _)| *on)
    .map(|(_, name)| {
        format!(
            "raycast_stream does not offer {name} (it needs the whole volume at once); it offers {}",
            STREAM_EFFECTS.join(", ")
        )
    })
}

/// The march's entry point and what it binds.
fn march_shader() -> ShaderUse {
    ShaderUse::new("raycast_stream.wgsl", "cs_main")
        .binds(&["level_grid", "level_scale", "page_table", "feedback", "occupancy", "volume"])
        .uniform(RaycastParamsGpu::bound("params"))
        .uniform(StreamParams::bound_as_with("stream", Vec::new(), |_| StreamParams::EMPTY.uniform_bytes()))
}

/// Voxels a brick keeps on every side of its own: what the filter taps near a brick face read
/// beyond it (as the brick pool's: one for trilinear samples, one more for shading's central
/// differences, two more for the tricubic B-spline).
fn apron(effects: EffectFlags) -> u32 {
    1 + u32::from(effects.shading) + 2 * u32::from(effects.tricubic)
}
