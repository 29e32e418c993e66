//! The transfer function pre-multiplied and opacity-corrected for the step, as a table denser
//! than the LUT, so a raycaster pays one filtered lookup and no `pow` per sample (the correction
//! depends only on the TF and the step: Engel et al. 2001). Not a pass of its own: a raycaster
//! that classifies through it (`raycast_compute`, `classify: "table"`) builds it in its own
//! compute pass from its own `step_voxels`, so table and march can never disagree on the step.
//! Rebuilding costs one dispatch of [`TABLE_SIZE`] invocations per frame. Read with a linear
//! sampler it equals the exact per-sample correction to second order in the table spacing;
//! stored as Rgba32Float where the device can filter it, else Rgba16Float (filterable on every
//! device). Shader: `shaders/opacity_lut.wgsl`.

use volgraph_compiler::ShaderUse;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError};

#[cfg(feature = "gpu")]
use crate::tf_table::TfTable;
use crate::tf_table::table_shaders;

/// Texels of the table: 16× the 256-entry LUT, so the table's own linear interpolation adds
/// < 0.1/255 to the image for the peer TFs (crates/passes/tests/fastest.rs).
pub const TABLE_SIZE: u32 = 4096;

/// The shader entry points that fill the table: Rgba32Float, Rgba16Float.
pub fn table_shader_uses() -> [ShaderUse; 2] {
    table_shaders("opacity_lut.wgsl")
}

#[cfg(feature = "gpu")]
/// The corrected table of a raycaster (binding `corrected`), filled from its `tf` port with the
/// step in its uniform `params` ([`TfTable::fill`], every frame).
pub fn opacity_table(ctx: &CreateContext<'_>) -> Result<TfTable, PassError> {
    TfTable::new(ctx, &table_shader_uses(), (TABLE_SIZE, 1), (64, 1), "opacity-corrected table")
}
