//! The pre-integration table of Engel et al. 2001 for the `preintegration` effect: for every pair
//! of front and back scalars, the premultiplied colour of one step along which the scalar runs
//! linearly between them, so a thin feature of the transfer function between two samples is
//! integrated instead of missed. Not a pass: each raycaster that classifies through it owns one
//! and rebuilds it on the GPU only when the transfer function's content (its input version) or
//! the step changes, so table and march always agree. Shader: `shaders/preintegration.wgsl`.

use volgraph_compiler::ShaderUse;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError, RecordContext};

#[cfg(feature = "gpu")]
use crate::tf_table::TfTable;
use crate::tf_table::table_shaders;

/// Texels per side: one per scalar value of an 8-bit volume.
pub const TABLE_SIZE: u32 = 256;

/// The entry points that fill the table: Rgba32Float, Rgba16Float.
pub fn table_shader_uses() -> [ShaderUse; 2] {
    table_shaders("preintegration.wgsl")
}

/// The pre-integration tables a raycaster reads, by the port of the transfer function each
/// integrates and the binding it is read through: the frame volume's, and with several scalar
/// volumes (`fuse`, `add`: `common/fusion.wgsl`) each partner's.
pub const TABLES: [(&str, &str); 4] = [
    ("tf", "preintegrated"),
    ("second_tf", "second_preintegrated"),
    ("third_tf", "third_preintegrated"),
    ("fourth_tf", "fourth_preintegrated"),
];

#[cfg(feature = "gpu")]
/// A raycaster's pre-integration table of one transfer function and what it was built for.
pub struct PreintegrationTable {
    /// The table.
    pub table: TfTable,
    /// The port of the transfer function it integrates (one of [`TABLES`]).
    pub port: &'static str,
    /// The binding the march reads it through.
    pub binding: &'static str,
    /// (TF version, step exponent) of the last build.
    built_for: Option<(u64, f32)>,
    /// How many times it was built (tests, the viewer).
    pub builds: u64,
}

#[cfg(feature = "gpu")]
impl PreintegrationTable {
    /// The pipeline (binding `params`: the raycaster's uniform) and the table texture of the
    /// transfer function on `port`, read through `binding` (one of [`TABLES`]).
    pub fn new(ctx: &CreateContext<'_>, (port, binding): (&'static str, &'static str)) -> Result<Self, PassError> {
        let table = TfTable::new(ctx, &table_shader_uses(), (TABLE_SIZE, TABLE_SIZE), (8, 8), "pre-integration table")?;
        Ok(Self { table, port, binding, built_for: None, builds: 0 })
    }

    /// Rebuilds the table from its port's TF when the TF's content or the step exponent
    /// (`step_voxels` over the frame's opacity unit) changed since the last build.
    pub fn update(
        &mut self,
        ctx: &mut RecordContext<'_>,
        params: &wgpu::Buffer,
        step_voxels: f64,
    ) -> Result<(), PassError> {
        let unit = ctx.frame.volume.map_or(1.0, |v| v.opacity_unit_voxels);
        let key = (ctx.input_version(self.port).unwrap_or(0), (step_voxels / unit) as f32);
        if self.built_for == Some(key) {
            return Ok(());
        }
        self.table.fill(ctx, params, self.port)?;
        self.built_for = Some(key);
        self.builds += 1;
        Ok(())
    }

    /// Forgets the last build (after new parameters were written).
    pub fn invalidate(&mut self) {
        self.built_for = None;
    }
}
