//! "Accuracy costs time": the CPU reference side of the benchmark. Samples per pixel come from
//! the f64 reference raycaster run with the graph's own raycast parameters (so early ray
//! termination is counted; empty-space skipping is not modelled, so for graphs that skip it is
//! the work of the ray integral, an upper bound of what the GPU samples). Error is measured
//! against a converged reference: the same integral at a very small step, no termination.

use std::collections::BTreeSet;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{RaycastSettings, render_reference};
use volgraph_accel::volume::Volume;
use volgraph_core::Plan;
use volgraph_core::runtime::Image;
use volgraph_passes::raycast_params::reference_settings;

/// The reference settings of the plan's raycast: the first step declaring `step_voxels`,
/// parameters it lacks taken from [`RaycastSettings::default`]. `None` when no step marches rays.
pub fn raycast_settings(plan: &Plan) -> Option<RaycastSettings> {
    let step = plan.steps.iter().find(|s| s.params.iter().any(|(name, _)| name == "step_voxels"))?;
    let declared: BTreeSet<&str> = step.params.iter().map(|(name, _)| name).collect();
    let mut settings = reference_settings(&step.params);
    let defaults = RaycastSettings::default();
    if !declared.contains("threshold") {
        settings.threshold = defaults.threshold;
    }
    if !declared.contains("max_steps") {
        settings.max_steps = defaults.max_steps;
    }
    if !declared.contains("mode") {
        settings.mode = defaults.mode;
    }
    Some(settings)
}

/// The converged version of `settings`: step `reference_step`, no early termination, no jitter,
/// enough steps for any ray.
pub fn converged(settings: &RaycastSettings, reference_step: f64) -> RaycastSettings {
    RaycastSettings { step_voxels: reference_step, threshold: 1.0, jitter: false, max_steps: 1 << 20, ..*settings }
}

/// Average volume samples per pixel of the reference with `settings` at `size`.
pub fn samples_per_pixel(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    size: (u32, u32),
    settings: &RaycastSettings,
) -> f64 {
    let image = render_reference(volume, lut, camera, size.0, size.1, settings);
    image.samples as f64 / (size.0 as f64 * size.1 as f64)
}

/// Error of a GPU image against a reference image: the project's one metric
/// ([`volgraph_accel::image_diff`], a NaN is an infinite error, never a small one).
pub type ImageError = volgraph_accel::image_diff::ImageDiff;

/// Compares `gpu` with `reference` (same size, row 0 at the top in both); `None` when the sizes
/// differ or the image is empty.
pub fn image_error(gpu: &Image, reference: &[[f64; 4]]) -> Option<ImageError> {
    if reference.is_empty() {
        return None;
    }
    volgraph_accel::image_diff::image_diff(&gpu.to_rgba_f64(), reference).ok()
}

/// Which points `(ms, error)` are on the Pareto front: no other point is at least as fast and at
/// least as accurate and strictly better in one of the two. Non-finite points are never on it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            t.is_finite() && e.is_finite() && !points.iter().any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_keeps_only_undominated_points() {
        let front = pareto_front(&[(1.0, 0.5), (2.0, 0.1), (3.0, 0.2), (1.5, 0.5), (f64::NAN, 0.0)]);
        assert_eq!(front, vec![true, true, false, false, false]);
    }

    /// The bench's error is the tests' metric: a NaN pixel is an infinite error.
    #[test]
    fn a_nan_pixel_is_an_infinite_error() {
        let image = Image { width: 2, height: 1, channels: 4, data: vec![0.5, 0.5, 0.5, f32::NAN, 0.5, 0.5, 0.5, 0.5] };
        let e = image_error(&image, &[[0.5; 4]; 2]).expect("same size");
        assert!(e.max_abs.is_infinite() && e.non_finite == 1 && e.psnr_db.is_none(), "{e:?}");
        assert!(image_error(&image, &[[0.5; 4]; 3]).is_none(), "sizes differ");
    }
}
