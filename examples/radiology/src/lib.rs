//! A worked external crate for volgraph (`docs/writing_a_pass.md`): two pass kinds the project
//! does not have, added through the public API only.
//!
//! - [`mip`]: a **Rust pass**, maximum-intensity projection (the brightest sample along each
//!   ray, the view radiologists read angiography in), a compute shader of its own
//!   (`shaders/mip.wgsl`) that reuses volgraph's shared WGSL (analytic rays, sampling).
//! - `edge_enhance`: a **WGSL-only pass** (`shaders/edge_enhance.wgsl`), declared in the graph
//!   file that uses it (`graphs/mip_enhanced.ron`) with no Rust at all.

pub mod mip;

use volgraph_core::Registry;
use volgraph_core::shader_source::EmbeddedShaders;

/// This crate's shaders, to put beside volgraph's (`ShaderSources::with_embedded`).
pub const SHADERS: EmbeddedShaders = &[
    ("mip.wgsl", include_str!("../shaders/mip.wgsl")),
    ("edge_enhance.wgsl", include_str!("../shaders/edge_enhance.wgsl")),
];

/// volgraph's shaders with this crate's in front, and the uniform structs its kinds declare
/// (`#import "params/MipParams.wgsl"`, gathered from [`register`]'s kinds): what its tests
/// compile from.
pub fn shader_sources() -> volgraph_core::shader_source::ShaderSources {
    use volgraph_core::KindLookup;
    let mut registry = Registry::new();
    register(&mut registry);
    volgraph_passes::builtin_shaders().prepend_embedded(SHADERS).with_generated(registry.uniform_imports())
}

/// Adds this crate's Rust pass kinds to `registry` (the WGSL-only one needs no registration).
pub fn register(registry: &mut Registry) {
    registry.register(mip::Mip);
}
