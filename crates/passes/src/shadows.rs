//! The `shadows` scene effect (issue "light that scatters", item 1; Behrens & Ratering 1998's
//! shadow volume): a light volume — at each voxel of a grid of up to 64³, the transmittance
//! toward the scene's light through the classified volume (`volgraph_accel::light::LightGrid`,
//! the very function the f64 reference calls) — that the march reads at every sample
//! (`shaders/common/shadows.wgsl`) to scale the light reaching it. Not a pass: each raycaster
//! that shades with it owns one, like the pre-integration table, and rebuilds it only when the
//! volume's or TF's content (their input versions), the light, the opacity unit or the
//! reconstruction change. With the headlight the light comes from the eye along the camera's
//! forward axis, so the volume follows the camera.
//!
//! The grid is computed on the CPU (rayon) from the voxels and LUT the runtime keeps for every
//! bound volume and TF, and uploaded as `R16Float` (filterable everywhere; T ∈ \[0, 1\] in f16 is
//! within 2⁻¹¹). That reaches every family at once — the brick raycaster's GPU volume is an
//! atlas of resident bricks, not the volume — at 64³ × (up to ~110 steps) trilinear samples per
//! rebuild.

#[cfg(feature = "gpu")]
use volgraph_core::runtime::{PassError, RecordContext};

#[cfg(feature = "gpu")]
/// A raycaster's light volume and what it was built for.
pub struct LightVolume {
    view: Option<wgpu::TextureView>,
    /// (volume version, TF version, light direction, opacity unit) of the last build.
    built_for: Option<(Option<u64>, Option<u64>, [u64; 3], u64)>,
    /// The field is the tricubic B-spline (the `tricubic` effect), as the march reconstructs it.
    tricubic: bool,
    /// Builds so far (tests, the viewer).
    pub builds: u64,
}

#[cfg(feature = "gpu")]
impl LightVolume {
    /// Not built yet; `tricubic`: reconstruct the field as the march does.
    pub fn new(tricubic: bool) -> Self {
        Self { view: None, built_for: None, tricubic, builds: 0 }
    }

    /// The light volume, once built.
    pub fn view(&self) -> Option<&wgpu::TextureView> {
        self.view.as_ref()
    }

    /// Rebuilds from the pass's `volume` and `tf` ports when they, the light or the opacity unit
    /// changed since the last build.
    pub fn update(&mut self, ctx: &RecordContext<'_>) -> Result<(), PassError> {
        let frame = ctx.frame;
        let toward = frame.light.toward().unwrap_or(-frame.camera.forward);
        let unit = frame.volume.map_or(1.0, |v| v.opacity_unit_voxels);
        let key =
            (ctx.input_version("volume"), ctx.input_version("tf"), toward.to_array().map(f64::to_bits), unit.to_bits());
        if self.built_for == Some(key) && self.view.is_some() {
            return Ok(());
        }
        let volume = ctx.voxels("volume")?.clone();
        let lut = ctx.table("tf")?.clone();
        let tricubic = self.tricubic;
        let field = |u: glam::DVec3| if tricubic { volume.sample_tricubic(u) } else { volume.sample_trilinear(u) };
        let grid = volgraph_accel::light::LightGrid::compute(&volume, &lut, toward, unit, &field);
        let values: Vec<f32> = grid.transmittance.iter().map(|&t| t as f32).collect();
        let texture =
            volgraph_core::runtime::upload::upload_f16_3d(ctx.gpu, "light_volume", grid.dims.to_array(), &values)
                .map_err(|e| PassError { pass: ctx.label.to_string(), message: e.to_string() })?;
        self.view = Some(texture.create_view(&wgpu::TextureViewDescriptor::default()));
        self.built_for = Some(key);
        self.builds += 1;
        Ok(())
    }
}
