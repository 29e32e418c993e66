//! The technique plugins of volgraph, one module per pass kind with its WGSL beside it by name
//! in `shaders/` (`entry_points.rs` ↔ `shaders/entry_points.wgsl`). Each registers through the
//! same public `volgraph_core::Registry` API an external crate would use.
//!
//! Each module holds a kind's declaration (`PassDecl`: blocks, ports, shader uses) and, with the
//! `gpu` feature (on by default), its node (`PassPlugin::create`, the wgpu code). Without the
//! feature the crate is the declarations alone — [`builtin_kinds`], the parameter blocks, the
//! shaders and their generated structs — and links no wgpu: what `volgraph plan` and the golden
//! plans need.

// The declarations-only build (no `gpu`) leaves the imports and helpers only nodes use unused.
#![cfg_attr(not(feature = "gpu"), allow(unused_imports, dead_code))]

pub mod antialias;
#[cfg(feature = "gpu")]
pub mod brick_pool;
pub mod defines;
pub mod effects;
pub mod empty_distance;
pub mod empty_space;
pub mod entry_points;
pub mod fetch_probe;
pub mod fusion;
#[cfg(feature = "gpu")]
pub mod grid_tap;
pub mod hole_fill;
pub mod majorant_grid;
pub mod march;
pub mod minmax_grid;
pub mod opacity_lut;
pub mod path_trace;
pub mod preintegration;
pub mod present;
pub mod ray_directions;
pub mod raycast;
pub mod raycast_bricks;
pub mod raycast_compute;
pub mod raycast_params;
pub mod raycast_segment;
pub mod raycast_stream;
pub mod reprojection_splat;
pub mod reprojection_tiles;
pub mod reslice;
pub mod segment_init;
pub mod shadows;
pub mod shared;
pub mod slice_render;
pub mod stream_cache;
pub mod stream_loader;
pub mod termination_test;
pub mod tf_table;

use volgraph_compiler::shader_source::ShaderSources;
use volgraph_compiler::{KindLookup, Kinds};
#[cfg(feature = "gpu")]
use volgraph_core::Registry;

include!(concat!(env!("OUT_DIR"), "/embedded_shaders.rs"));

/// The built-in shaders as a source layer, compiled into the binary. Put a folder on disk in
/// front of it ([`ShaderSources::prepend_disk`]) to read (and hot-reload) a working copy.
pub fn builtin_shaders() -> ShaderSources {
    ShaderSources::new().with_embedded(EMBEDDED_SHADERS).with_generated(uniform_imports())
}

/// The WGSL struct of every uniform block the built-in kinds' shader uses declare, as the
/// generated files `params/NAME.wgsl` the shaders import: each struct is written once, in Rust
/// (`pass_params!`), and gathered from the declarations ([`KindLookup::uniform_imports`]).
pub fn uniform_imports() -> Vec<(String, String)> {
    builtin_kinds().uniform_imports()
}

/// Registers every built-in kind with `$target` (a `Registry` or `Kinds`): one list for the
/// registry and the declarations alike.
macro_rules! builtin_kinds {
    ($target:expr) => {
        $target
            .register(entry_points::EntryPoints)
            .register(ray_directions::RayDirections)
            .register(raycast::Raycast)
            .register(raycast_compute::RaycastCompute)
            .register(segment_init::SegmentInit)
            .register(raycast_segment::RaycastSegment::default())
            .register(termination_test::TerminationTest)
            .register(minmax_grid::MinMaxGridPass::default())
            .register(empty_space::EmptySpace::default())
            .register(empty_distance::EmptyDistance::default())
            .register(fetch_probe::FetchProbe)
            .register(slice_render::SliceRender)
            .register(reprojection_splat::ReprojectionSplat)
            .register(hole_fill::HoleFill)
            .register(reprojection_tiles::ReprojectionTiles)
            .register(antialias::Antialias)
            .register(majorant_grid::MajorantGrid)
            .register(path_trace::PathTrace)
            .register(raycast_bricks::RaycastBricks)
            .register(raycast_stream::RaycastStream)
            .register(present::Present)
            .register(reslice::Reslice)
    };
}

/// The built-in kinds as declarations alone (no device): what `volgraph plan`, the golden
/// plans and the generated imports read. Builds without the `gpu` feature.
pub fn builtin_kinds() -> Kinds {
    let mut kinds = Kinds::new();
    builtin_kinds!(kinds);
    kinds
}

/// Adds every built-in pass kind to `registry`.
#[cfg(feature = "gpu")]
pub fn register_builtin(registry: &mut Registry) {
    builtin_kinds!(registry);
}

/// A registry holding the built-in pass kinds.
#[cfg(feature = "gpu")]
pub fn builtin_registry() -> Registry {
    let mut r = Registry::new();
    register_builtin(&mut r);
    r
}

#[cfg(feature = "gpu")]
/// Sets `pipeline` and bind group 0 and draws `vertices` (no vertex buffers: every built-in
/// render pass pulls its vertices from `vertex_index`).
pub(crate) fn draw(
    pass: &mut wgpu::RenderPass<'_>,
    pipeline: &volgraph_core::runtime::RenderPassPipeline,
    bind_group: &wgpu::BindGroup,
    vertices: std::ops::Range<u32>,
) {
    pass.set_pipeline(&pipeline.pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(vertices, 0..1);
}
