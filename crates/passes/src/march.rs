//! The Rust side of the one sampling core (`shaders/common/raymarch.wgsl`,
//! `common/pixel_march.wgsl`): the settings the single-pass raycasters (`raycast`, fragment;
//! `raycast_compute`, compute) share and what each compiles in — where rays come from, empty-space
//! leaping from an optional `empty` (Krüger & Westermann 2003 §2.3's block flags) or `distance`
//! (`empty_distance`'s Chebyshev map) input, and sample counting. Declared once here, so the two
//! kinds cannot drift and a paper comparison between them is a comparison of settings.

use volgraph_compiler::{Params, PortKind, PortSpec};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext};

use crate::defines;
use crate::empty_distance::EMPTY_DISTANCE;
use crate::empty_space::EMPTY_BLOCKS;
#[cfg(feature = "gpu")]
use crate::empty_space::check_block_grid;
#[cfg(feature = "gpu")]
use crate::minmax_grid::bound_size;
use crate::shared::{BlockSize, FLOAT_TARGETS};

/// Rows of the `samples` buffer (`SAMPLE_ROWS` in the shaders): image row y counts into word
/// y mod SAMPLE_ROWS, so a word holds at most a row's samples.
pub const SAMPLE_ROWS: u64 = 4096;

volgraph_compiler::param_choice! {
    /// Where a ray's entry and direction come from.
    pub enum Rays {
        /// The `entry` and `dir` inputs (K-W 2003 §2.1).
        Raster = "raster",
        /// Met with the box in the shader, no inputs needed.
        Analytic = "analytic",
    }
}

volgraph_compiler::param_choice! {
    /// What a ray leaps out of when the empty-space input says it may.
    pub enum Leap {
        /// The largest cube of empty blocks around the sample (`distance` input).
        Cubes = "cubes",
        /// The sample's own block.
        Blocks = "blocks",
        /// Nothing: every sample is taken.
        None = "none",
    }
}

volgraph_compiler::pass_params! {
    /// The single-pass raycasters' rays, leaping and counting.
    pub struct MarchSettings {
        rays: Rays = Raster,
            "raster: entry and direction from the `entry` and `dir` inputs (K-W 2003 §2.1); analytic: met with the box in \
             the shader, no inputs needed";
        leap: Leap = Cubes,
            "with `empty` (block flags) or `distance` (distance map) wired: leap out of the largest cube of empty blocks \
             (distance map only), out of one block at a time, or take every sample (unwired: none)";
        check_every: u32 = 16, 1..=1024,
            "with leaping: samples in a run between two looks at the empty-space input (all lanes look together)";
        count_samples: bool = false, "add the samples taken to the `samples` buffer (benchmarks; one atomic per pixel)";
    }
}

impl MarchSettings {
    /// Whether the rays meet the box analytically (no `entry` / `dir` inputs).
    pub fn analytic(&self) -> bool {
        self.rays == Rays::Analytic
    }
}

/// The parameter blocks of the shared march: its settings (rays, leaping and counting pick
/// the pipeline and its `#if`s: a rebuild) and the block edge of the empty-space inputs (a
/// uniform).
pub fn march_blocks() -> Vec<volgraph_compiler::block::ParamBlock> {
    use volgraph_compiler::block::OnChange;
    vec![MarchSettings::block(OnChange::Rebuild).with_defines(march_defines), BlockSize::block(OnChange::InPlace)]
}

/// The ports the shared march adds: `entry`/`dir` for raster rays, the optional empty-space
/// inputs, and `samples` when counting.
pub fn march_ports(params: &Params) -> Vec<PortSpec> {
    let settings = MarchSettings::from_params(params);
    let mut ports = Vec::new();
    if !settings.analytic() {
        ports.push(PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)));
        ports.push(PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)));
    }
    // Leave both unwired to take every sample; wire one.
    ports.push(PortSpec::read("empty", PortKind::Owned(EMPTY_BLOCKS)).optional());
    ports.push(PortSpec::read("distance", PortKind::Owned(EMPTY_DISTANCE)).optional());
    if settings.count_samples {
        ports.push(PortSpec::write("samples", PortKind::buffer(4 * SAMPLE_ROWS)));
    }
    ports
}

/// The `#if` names of `params`' march that do not depend on the wiring (those that do:
/// [`wired_defines`]).
pub fn march_defines(params: &Params) -> Vec<&'static str> {
    let settings = MarchSettings::from_params(params);
    let mut defines = Vec::new();
    if settings.analytic() {
        defines.push(defines::ANALYTIC);
    }
    if settings.count_samples {
        defines.push(defines::COUNT);
    }
    defines
}

/// Which empty-space input a node leaps with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    None,
    /// `empty`: per-block flags.
    Blocks,
    /// `distance`: the Chebyshev map; `cubes` leaps out of cubes of blocks.
    Distance {
        cubes: bool,
    },
}

impl Source {
    /// From the settings and the wired ports; `None` when both inputs are wired.
    fn of(params: &Params, wired: &[&str]) -> Option<Self> {
        let leap = MarchSettings::from_params(params).leap;
        Some(match (wired.contains(&"empty"), wired.contains(&"distance"), leap) {
            (true, true, _) => return None,
            (_, _, Leap::None) | (false, false, _) => Source::None,
            (true, false, _) => Source::Blocks,
            (false, true, leap) => Source::Distance { cubes: leap == Leap::Cubes },
        })
    }

    /// The `#if` names of the leap (LEAP and the input's provider).
    fn defines(self) -> Vec<&'static str> {
        match self {
            Source::None => vec![],
            Source::Blocks => vec![defines::LEAP, defines::LEAP_BLOCKS],
            Source::Distance { .. } => vec![defines::LEAP, defines::LEAP_CUBES],
        }
    }
}

/// The `#if` names the wiring adds to the shared march: the leap over the wired empty-space
/// input, START for a wired `start` estimate, START_TILES for wired per-tile bounds (both empty-space inputs wired: no leap; node
/// creation reports it).
pub fn wired_defines(params: &Params, wired: &[&str]) -> Vec<&'static str> {
    let mut defines = Source::of(params, wired).map(Source::defines).unwrap_or_default();
    if wired.contains(&"start") {
        defines.push(defines::START);
    }
    if wired.contains(&"start_tiles") {
        defines.push(defines::START_TILES);
    }
    defines
}

#[cfg(feature = "gpu")]
/// A node's empty-space leaping: the input it reads, the block-edge uniform `blocks`, the
/// defines and constants its pipeline is built with, and the grid check every frame.
pub struct Leaping {
    source: Source,
    check_every: u32,
    block_size: u32,
    blocks: Option<wgpu::Buffer>,
}

#[cfg(feature = "gpu")]
impl Leaping {
    /// From the node's wiring and settings; both inputs wired is an error.
    pub fn new(ctx: &CreateContext<'_>) -> Result<Self, PassError> {
        let settings = MarchSettings::from_params(ctx.params);
        let source = Source::of(ctx.params, &ctx.wired()).ok_or_else(|| PassError {
            pass: ctx.pass_id.to_string(),
            message: "both \"empty\" and \"distance\" are wired; wire one empty-space input".into(),
        })?;
        let block_size = BlockSize::of(ctx.params);
        let blocks = (source != Source::None)
            .then(|| ctx.uniform_from_bytes("blocks", &BlockSize { block_size }.uniform_bytes()));
        Ok(Self { source, check_every: settings.check_every.max(1), block_size, blocks })
    }

    /// The pipeline constants of the leap.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        match self.source {
            Source::None => vec![],
            Source::Blocks => vec![("CHECK_EVERY", self.check_every as f64)],
            Source::Distance { cubes } => {
                vec![("CHECK_EVERY", self.check_every as f64), ("LEAP_CUBES", if cubes { 1.0 } else { 0.0 })]
            }
        }
    }

    /// The node's own bindings (the block-edge uniform).
    pub fn bindings(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        self.blocks.iter().map(|b| ("blocks", b.as_entire_binding())).collect()
    }

    /// The empty-space input must be `block_size`'s grid of the bound volume.
    pub fn check(&self, ctx: &RecordContext<'_>) -> Result<(), PassError> {
        let port = match self.source {
            Source::None => return Ok(()),
            Source::Blocks => "empty",
            Source::Distance { .. } => "distance",
        };
        check_block_grid(ctx, port, self.block_size, bound_size(ctx, "volume")?)
    }

    /// A parameter edit that kept the pipeline: the block edge may have changed.
    pub fn update(&mut self, gpu: &Gpu, params: &Params) {
        self.block_size = BlockSize::of(params);
        if let Some(b) = &self.blocks {
            gpu.queue.write_buffer(b, 0, &BlockSize { block_size: self.block_size }.uniform_bytes());
        }
    }
}
