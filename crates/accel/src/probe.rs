//! What lies under a pixel (the viewer's "look": issue 24 §4): the first point along the
//! pixel's ray where the transfer function makes the volume visible, and the data value there in
//! the data's own units. One ray marched on the CPU with the rendering model's samples
//! (`docs/rendering_model.md`): the same segment, step grid and cuts as every raycaster.

use glam::DVec3;

use crate::camera::OrbitCamera;
use crate::cuts::Cuts;
use crate::reference::{lut_sample, ray_segment, step_tex};
use crate::volume::Volume;

/// The first visible sample under a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// The data value there (the file's units: HU for CT, the stored value otherwise).
    pub value: f64,
    /// Where, in voxel coordinates (voxel centres at integer + 0.5).
    pub voxel: DVec3,
    /// The TF's opacity there.
    pub alpha: f64,
}

/// The first sample along pixel `(x, y)`'s ray (of a `width × height` image seen by `camera`)
/// whose TF opacity is above zero, marching `step_voxels` apart within what `cuts` keep; `None`
/// when the ray misses the volume or stays transparent.
#[allow(clippy::too_many_arguments, reason = "one ray's inputs, each needed")]
pub fn first_visible(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    (width, height): (u32, u32),
    (x, y): (u32, u32),
    step_voxels: f64,
    cuts: &Cuts,
) -> Option<Probe> {
    if x >= width || y >= height || volume.voxel_count() == 0 {
        return None;
    }
    let frame = camera.frame(width, height);
    let seg = ray_segment(volume, camera, &frame, x, y)?;
    let step = step_tex(volume, seg.d_tex, step_voxels.max(1e-3));
    if !(step > 0.0 && step.is_finite()) {
        return None;
    }
    let (begin, end) = cuts.keeps_interval(seg.u0, seg.d_tex, 0.0, seg.len_tex);
    let first = ((begin / step - 0.5).ceil()).max(0.0) as u64;
    let count = ((end / step - 0.5).ceil()).max(0.0) as u64;
    let (lo, hi) = volume.value_range;
    for k in first..count.min(first + 1_000_000) {
        let u = seg.u0 + (k as f64 + 0.5) * step * seg.d_tex;
        let s = volume.sample_trilinear(u);
        let alpha = lut_sample(lut, s)[3];
        if alpha > 0.0 {
            return Some(Probe { value: lo + s * (hi - lo), voxel: u * volume.dims.as_dvec3(), alpha });
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Through the centre of a sphere of radius 0.25 (half box widths: 8 voxels of 64) with only its
    /// inside visible, the first visible sample lies on its surface, facing the camera.
    #[test]
    fn the_first_visible_sample_is_on_the_near_surface() {
        let n = 64;
        let volume = crate::generate::sphere(n, 0.25);
        // Visible above the middle of the value range only.
        let lut: Vec<[f32; 4]> = (0..256).map(|i| [1.0, 1.0, 1.0, if i >= 128 { 1.0 } else { 0.0 }]).collect();
        let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 3.0, ..OrbitCamera::default() };
        let p = first_visible(&volume, &lut, &camera, (65, 65), (32, 32), 0.25, &Cuts::NONE).expect("a hit");
        let centre = DVec3::splat(n as f64 / 2.0);
        let r = (p.voxel - centre).length();
        // Within a voxel: trilinear filtering puts the 0.5 level of a binary sphere within half a
        // voxel of its radius, and the first sample past it is at most a 0.25-voxel step on.
        assert!((r - 0.25 * n as f64 / 2.0).abs() < 1.0, "on the surface: r = {r}, at {:?}", p.voxel);
        assert!(p.voxel.z > centre.z, "on the side facing the camera (+z): {:?}", p.voxel);
        assert!(p.value >= volume.value_range.0 + 0.49 * (volume.value_range.1 - volume.value_range.0));
        // A crop that removes the near half moves the first visible point to the crop face.
        let half =
            Cuts::new(Some(crate::cuts::CropBox::new(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.5)).expect("box")), &[])
                .expect("cuts");
        let q = first_visible(&volume, &lut, &camera, (65, 65), (32, 32), 0.25, &half).expect("a hit");
        // The first kept sample lies within one step (0.25 voxel) of the face; 0.6 allows the
        // step's slant along this nearly axial ray.
        assert!((q.voxel.z - n as f64 / 2.0).abs() < 0.6, "at the crop face: {:?}", q.voxel);
        // A ray past the sphere stays transparent.
        assert_eq!(first_visible(&volume, &lut, &camera, (65, 65), (1, 1), 0.25, &Cuts::NONE), None);
    }
}
