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

/// Adds this crate's Rust pass kinds to `registry` (the WGSL-only one needs no registration).
pub fn register(registry: &mut Registry) {
    registry.register(mip::Mip);
}
