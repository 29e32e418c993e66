//! The `#if` names the built-in passes assemble their shaders with, typed once: a pass names a
//! define through these constants, never a bare string, and `tests/shader_defines.rs` fails when
//! a WGSL `#if NAME` under `shaders/` has no constant here (or in the compiler's frame defines,
//! `volgraph_compiler::cut_effects`) or a constant here is used by no shader. Grouped by what
//! turns them on.

// Scene effects (`effects.rs`): compiled in only when a scene asks for them.
/// Blinn–Phong shading of every DVR sample (`effects::EffectFlags::shading`).
pub const SHADING: &str = "SHADING";
/// Pre-integrated classification (Engel et al. 2001; `effects::EffectFlags::preintegration`).
pub const PREINTEGRATION: &str = "PREINTEGRATION";
/// Tricubic B-spline reconstruction (`effects::EffectFlags::tricubic`; the min/max grid's apron).
pub const TRICUBIC: &str = "TRICUBIC";
/// Shadows from the illumination volume (`effects::EffectFlags::shadows`, `shadows.rs`).
pub const SHADOWS: &str = "SHADOWS";
/// Ambient occlusion from the illumination volume (`effects::EffectFlags::ambient_occlusion`).
pub const AMBIENT_OCCLUSION: &str = "AMBIENT_OCCLUSION";
/// A per-pixel sample offset (`raycast_params::Sampling::jitter`).
pub const JITTER: &str = "JITTER";
/// The offset changes every frame (`Sampling::jitter_per_frame`).
pub const JITTER_PER_FRAME: &str = "JITTER_PER_FRAME";

// The shared march's settings and wiring (`march.rs`).
/// Rays met with the box in the shader (`rays: "analytic"`) instead of entry/direction targets.
pub const ANALYTIC: &str = "ANALYTIC";
/// Sample counting (benchmarks).
pub const COUNT: &str = "COUNT";
/// Empty-space leaping, with one of its providers below.
pub const LEAP: &str = "LEAP";
/// … over the empty-block flags (`empty`).
pub const LEAP_BLOCKS: &str = "LEAP_BLOCKS";
/// … over cubes of empty blocks (a `distance` map).
pub const LEAP_CUBES: &str = "LEAP_CUBES";
/// Rays start at per-pixel estimates (`start`; Klein et al. 2005 §4.2).
pub const START: &str = "START";
/// Rays start at per-tile depth bounds (`start_tiles`, `reprojection_tiles`).
pub const START_TILES: &str = "START_TILES";

// The streaming raycaster (`raycast_stream.rs`).
/// A run's opacity is corrected for its level's step (`step_multiple`, common/raymarch.wgsl).
pub const LEVEL_STEPS: &str = "LEVEL_STEPS";

// The path tracer's choices (`path_trace.rs`).
/// Delta and ratio tracking block by block against per-block majorants (`majorant_grid`).
pub const BLOCK_MAJORANTS: &str = "BLOCK_MAJORANTS";
/// Each pixel's mean continued across camera moves where its surface was (`reproject`).
pub const REPROJECT: &str = "REPROJECT";
/// Empty blocks crossed a cube at a time by the Chebyshev distance map (`leap`).
pub const MAJORANT_LEAP: &str = "MAJORANT_LEAP";

// The fragment raycaster's Klein variant (`raycast.rs`).
/// Write `leap_hit`, where the next frame's ray starts.
pub const LEAP_HITS: &str = "LEAP_HITS";
/// Report the first visible DVR sample.
pub const FIRST_VISIBLE: &str = "FIRST_VISIBLE";
/// Count the samples a perfect start estimate would leap over (a bypass's measure).
pub const COUNT_LEAPABLE: &str = "COUNT_LEAPABLE";

// Several volumes in one march (`fusion.rs`, `shaders/common/fusion.wgsl`).
/// Samples classify several volumes (`fusion` set).
pub const FUSION: &str = "FUSION";
/// … the frame volume is a label map (`fusion: "labels"`).
pub const FUSION_LABELS: &str = "FUSION_LABELS";
/// … the second volume is a label map (`tint`, `inside`).
pub const FUSION_LABEL_MAP: &str = "FUSION_LABEL_MAP";
/// … the second volume is scalar, with its own TF (`fuse`, `add`).
pub const FUSION_SCALAR: &str = "FUSION_SCALAR";
/// … and a third scalar volume (`channels` 3 or 4).
pub const FUSION_THIRD: &str = "FUSION_THIRD";
/// … and a fourth (`channels` 4).
pub const FUSION_FOURTH: &str = "FUSION_FOURTH";
/// … and a label map lies over the scalar pair (`overlay`: `tint`, `inside`).
pub const FUSION_OVERLAY: &str = "FUSION_OVERLAY";
/// A label map is sampled (`FUSION_LABELS`, `FUSION_LABEL_MAP` or `FUSION_OVERLAY`).
pub const FUSION_LABEL_READS: &str = "FUSION_LABEL_READS";
/// Label maps read at the nearest voxel (`label_filter: "nearest"`).
pub const LABELS_NEAREST: &str = "LABELS_NEAREST";

// Other passes.
/// The compute raycaster classifies through the pre-corrected TF table (`raycast_compute.rs`).
pub const CORRECTED_TABLE: &str = "CORRECTED_TABLE";
/// The sample loop's pipelined variant: the TF in workgroup memory (`raycast_params.rs`).
pub const TF_WORKGROUP: &str = "TF_WORKGROUP";
/// … and the next sample fetched ahead.
pub const PREFETCH: &str = "PREFETCH";
/// A compute march writes f32 colour (`shared::color_precision_defines`).
pub const COLOR_F32: &str = "COLOR_F32";
/// The classification of pre-integrated segments (`empty_space.rs`).
pub const SEGMENTS: &str = "SEGMENTS";
/// The splats written by a compute scatter (`reprojection_splat.rs`).
pub const SCATTER: &str = "SCATTER";
/// A slice with a label map over it (`reslice.rs`, `labels: true`).
pub const RESLICE_LABELS: &str = "RESLICE_LABELS";

/// Every `#if` name of the built-in passes.
pub const BUILT_IN: [&str; 37] = [
    SHADING,
    PREINTEGRATION,
    TRICUBIC,
    SHADOWS,
    AMBIENT_OCCLUSION,
    JITTER,
    JITTER_PER_FRAME,
    ANALYTIC,
    COUNT,
    LEAP,
    LEAP_BLOCKS,
    LEAP_CUBES,
    START,
    START_TILES,
    LEVEL_STEPS,
    LEAP_HITS,
    FIRST_VISIBLE,
    COUNT_LEAPABLE,
    CORRECTED_TABLE,
    TF_WORKGROUP,
    PREFETCH,
    COLOR_F32,
    SEGMENTS,
    SCATTER,
    FUSION,
    FUSION_LABELS,
    FUSION_LABEL_MAP,
    FUSION_SCALAR,
    FUSION_THIRD,
    FUSION_FOURTH,
    FUSION_OVERLAY,
    FUSION_LABEL_READS,
    LABELS_NEAREST,
    BLOCK_MAJORANTS,
    REPROJECT,
    MAJORANT_LEAP,
    RESLICE_LABELS,
];
