//! The f64 reference of a maximum-intensity projection (the brightest sample along each pixel's
//! ray, what radiologists read angiography in): the same rays and sample positions as every
//! volgraph raycaster (`docs/rendering_model.md`, "Ray segment inside the box"), the largest
//! trilinear value instead of the compositing integral. The GPU MIPs — the stock graph
//! `graphs/basic/mip.ron` (a WGSL-only pass) and `examples/radiology`'s Rust pass — are checked
//! against it.

use crate::camera::{CameraFrame, OrbitCamera};
use crate::reference::{pixel_jitter, ray_segment, step_tex};
use crate::volume::Volume;

/// The MIP of pixel `(x, y)` of a `width`-pixel-wide image: the largest trilinear sample at
/// `(k + 0.5 + jitter)` steps of `step_voxels` voxels from the ray's entry (jitter 0 unless
/// `jittered`, else volgraph's per-pixel hash), or `None` where the ray misses the box.
pub fn mip_pixel(
    volume: &Volume,
    camera: &OrbitCamera,
    frame: &CameraFrame,
    (x, y, width): (u32, u32, u32),
    step_voxels: f64,
    jittered: bool,
) -> Option<f64> {
    let seg = ray_segment(volume, camera, frame, x, y)?;
    let step = step_tex(volume, seg.d_tex, step_voxels);
    let jitter = if jittered { pixel_jitter(x, y, width) } else { 0.0 };
    let count = (seg.len_tex / step - 0.5 - jitter).ceil().max(0.0) as u32;
    let at = |k: u32| seg.u0 + (k as f64 + 0.5 + jitter) * step * seg.d_tex;
    Some((0..count).map(|k| volume.sample_trilinear(at(k))).fold(0.0, f64::max))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A volume of one value projects to that value wherever a ray meets it, and misses outside.
    #[test]
    fn a_constant_volume_projects_its_value() {
        let volume =
            Volume::new("flat", glam::UVec3::splat(8), glam::DVec3::ONE, crate::volume::VoxelData::U8(vec![64; 512]));
        let camera = OrbitCamera::default();
        let frame = camera.frame(16, 16);
        let centre = mip_pixel(&volume, &camera, &frame, (8, 8, 16), 0.5, false).expect("the centre ray hits");
        assert!((centre - 64.0 / 255.0).abs() < 1e-9, "{centre}");
        assert_eq!(mip_pixel(&volume, &camera, &frame, (0, 0, 16), 0.5, false), None, "a corner ray misses");
    }
}
