//! DVR in the f64 reference renderer against closed forms (`docs/rendering_model.md`,
//! "Classification and compositing"; Krüger & Westermann 2003 §2.1).
//!
//! Through a constant field with a constant transfer function every sample has the same
//! corrected opacity `α = 1 - (1-α_tf)^step`, so after `n` samples `A = 1 - (1-α_tf)^(n·step)`
//! and the premultiplied colour is `rgb·A`; `n` is the number of `t_k = (k+0.5+j)·step_tex`
//! below `len_tex`.

use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{
    RaycastSettings, lut_sample, pcg_hash, pixel_jitter, ray_segment, render_reference, step_tex,
};
use volgraph_accel::volume::{Volume, VoxelData};

fn constant_volume(dims: UVec3, spacing: DVec3, value: u8) -> Volume {
    let n = (dims.x * dims.y * dims.z) as usize;
    Volume {
        dims,
        spacing,
        data: VoxelData::U8(vec![value; n]),
        name: "constant".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    }
}

/// A camera looking down -z through the box centre (azimuth 0, elevation 0).
fn front_camera() -> OrbitCamera {
    OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 2.2, ..Default::default() }
}

const RGBA: [f32; 4] = [0.8, 0.4, 0.2, 0.1];

#[test]
fn centre_ray_through_a_cube_has_the_closed_form_opacity() {
    // 8³ unit voxels: unit_world = 1/8, step 0.5 voxel = 1/16 world = 1/16 texture along z, the
    // ray crosses len_tex = 1, so n = 16 samples and A = 1 - 0.9^(16·0.5) = 1 - 0.9^8.
    let volume = constant_volume(UVec3::splat(8), DVec3::ONE, 200);
    let image = render_reference(&volume, &[RGBA; 2], &front_camera(), 1, 1, &RaycastSettings::default());
    let expected_a = 1.0 - 0.9f64.powi(8);
    // f32 LUT values widen exactly to f64, but 0.1f32 is not 0.1: compare with its f64 value.
    let a_tf = RGBA[3] as f64;
    let exact_a = 1.0 - (1.0 - a_tf).powf(8.0);
    assert_eq!(image.samples, 16);
    // 1e-12: 16 compounding steps of f64 rounding; the 0.1f32 vs 0.1 gap is ~1.5e-9·8, so the
    // decimal check gets 1e-7.
    assert!((image.color[0][3] - exact_a).abs() < 1e-12, "A = {}, want {exact_a}", image.color[0][3]);
    assert!((image.color[0][3] - expected_a).abs() < 1e-7, "A = {}, want {expected_a}", image.color[0][3]);
    for (c, (&got, &rgb)) in image.color[0].iter().zip(&RGBA[..3]).enumerate() {
        let want = rgb as f64 * exact_a;
        assert!((got - want).abs() < 1e-12, "channel {c}: {got} vs {want}");
    }
}

#[test]
fn every_pixel_matches_the_closed_form_for_several_views() {
    // Non-cubic volume with anisotropic spacing, so step_tex differs per ray and per axis.
    let volume = constant_volume(UVec3::new(6, 5, 4), DVec3::new(1.0, 1.5, 2.0), 77);
    let lut = [RGBA; 3];
    let settings = RaycastSettings { step_voxels: 0.7, ..Default::default() };
    let (w, h) = (24, 18);
    for (az, el, jitter) in [(0.0, 0.0, false), (30.0, 20.0, false), (-130.0, -55.0, true), (90.0, 89.0, true)] {
        let camera = OrbitCamera { azimuth_deg: az, elevation_deg: el, distance: 2.0, ..Default::default() };
        let frame = camera.frame(w, h);
        let settings = RaycastSettings { jitter, ..settings };
        let image = render_reference(&volume, &lut, &camera, w, h, &settings);
        let (mut total, mut hits) = (0u64, 0);
        for y in 0..h {
            for x in 0..w {
                let got = image.color[image.index(x, y)];
                let Some(seg) = ray_segment(&volume, &camera, &frame, x, y) else {
                    assert_eq!(got, [0.0; 4], "({x},{y}) has no ray and must stay transparent");
                    continue;
                };
                let st = step_tex(&volume, seg.d_tex, settings.step_voxels);
                let j = if jitter { pixel_jitter(x, y, w) } else { 0.0 };
                // n = #{k >= 0 : (k + 0.5 + j)·st < len}
                let n = ((seg.len_tex / st - 0.5 - j).ceil()).max(0.0) as u64;
                total += n;
                hits += (n > 0) as u32;
                let a = 1.0 - (1.0 - RGBA[3] as f64).powf(n as f64 * settings.step_voxels);
                // 1e-12: at most ~40 compounding f64 steps; ceil() could differ from the loop
                // only for a sample exactly at len_tex, which would show up as a ~0.07 error.
                assert!((got[3] - a).abs() < 1e-12, "az {az} el {el} ({x},{y}): A {} vs {a} (n {n})", got[3]);
                assert!((got[0] - RGBA[0] as f64 * a).abs() < 1e-12);
            }
        }
        assert_eq!(image.samples, total, "az {az} el {el}: sample count");
        assert!(hits > w * h / 10, "az {az} el {el}: the box covers part of the image ({hits} rays)");
    }
}

#[test]
fn opacity_correction_makes_the_result_independent_of_the_step() {
    // Centre ray, len_tex = 1 in an 8³ cube: step 0.25 → 32 samples, 0.5 → 16, 1.0 → 8; each
    // covers 8 voxels, so A = 1 - (1-α_tf)^8 in all three.
    let volume = constant_volume(UVec3::splat(8), DVec3::ONE, 255);
    let a = [0.9f32, 0.9, 0.9, 0.3];
    let want = 1.0 - (1.0 - 0.3f32 as f64).powi(8);
    for (step, n) in [(0.25, 32), (0.5, 16), (1.0, 8)] {
        let settings = RaycastSettings { step_voxels: step, ..Default::default() };
        let image = render_reference(&volume, &[a], &front_camera(), 1, 1, &settings);
        assert_eq!(image.samples, n, "step {step}");
        // 1e-12: f64 rounding of up to 32 compounding steps.
        assert!((image.color[0][3] - want).abs() < 1e-12, "step {step}: A = {}", image.color[0][3]);
    }
}

#[test]
fn empty_transfer_function_gives_an_all_zero_image() {
    let volume = constant_volume(UVec3::new(5, 7, 3), DVec3::ONE, 128);
    let camera = OrbitCamera::default();
    let image = render_reference(&volume, &[[0.0; 4]; 16], &camera, 20, 16, &RaycastSettings::default());
    assert!(image.color.iter().all(|c| *c == [0.0; 4]), "zero opacity adds nothing, exactly");
    assert!(image.hit.iter().all(|c| *c == [0.0; 4]), "DVR writes no hits");
    assert!(image.samples > 0, "rays were still marched");
}

#[test]
fn early_termination_stops_after_the_sample_reaching_the_threshold() {
    // α_tf = 0.5 per voxel, step 1 → α = 0.5 per sample; A_k = 1 - 0.5^k reaches 0.9 at k = 4
    // (0.9375), so 4 of the 8 samples are taken.
    let volume = constant_volume(UVec3::splat(8), DVec3::ONE, 255);
    let settings = RaycastSettings { step_voxels: 1.0, threshold: 0.9, ..Default::default() };
    let image = render_reference(&volume, &[[1.0, 1.0, 1.0, 0.5]], &front_camera(), 1, 1, &settings);
    assert_eq!(image.samples, 4);
    assert_eq!(image.color[0], [0.9375; 4], "powers of two are exact in f64");
}

#[test]
fn max_steps_caps_the_samples_per_ray() {
    let volume = constant_volume(UVec3::splat(8), DVec3::ONE, 255);
    let settings = RaycastSettings { step_voxels: 1.0, max_steps: 3, ..Default::default() };
    let image = render_reference(&volume, &[[1.0, 1.0, 1.0, 0.5]], &front_camera(), 1, 1, &settings);
    assert_eq!(image.samples, 3);
    assert_eq!(image.color[0][3], 0.875, "1 - 0.5³, exact in f64");
}

#[test]
fn lut_is_read_like_a_linear_clamp_sampler() {
    let lut = [[0.0, 0.0, 0.0, 0.0], [1.0, 0.5, 0.25, 1.0]];
    // Texel centres at 0.25 and 0.75; clamped outside, linear between: s = 0.5 is halfway.
    assert_eq!(lut_sample(&lut, 0.0), [0.0; 4]);
    assert_eq!(lut_sample(&lut, 0.25), [0.0; 4]);
    assert_eq!(lut_sample(&lut, 0.5), [0.5, 0.25, 0.125, 0.5]);
    assert_eq!(lut_sample(&lut, 0.75), [1.0, 0.5, 0.25, 1.0]);
    assert_eq!(lut_sample(&lut, 1.0), [1.0, 0.5, 0.25, 1.0]);
    assert_eq!(lut_sample(&lut, -3.0), [0.0; 4]);
    assert_eq!(lut_sample(&[], 0.5), [0.0; 4], "an empty LUT reads as transparent");
    assert_eq!(lut_sample(&lut, f64::NAN), [0.0; 4], "NaN reads as s = 0");
}

#[test]
fn jitter_matches_the_pcg_hash_values() {
    // Values computed independently (Python, wrapping 32-bit) from O'Neill's pcg_hash.
    assert_eq!(pcg_hash(0), 129_708_002);
    assert_eq!(pcg_hash(1), 2_831_084_092);
    assert_eq!(pcg_hash(12345), 4_099_845_390);
    // pixel (1, 0) and (0, 1) of a 1-pixel-wide image both hash index 1.
    assert_eq!(pixel_jitter(1, 0, 7), 2_831_084_092.0 / 4_294_967_296.0 - 0.5);
    assert_eq!(pixel_jitter(0, 1, 1), pixel_jitter(1, 0, 7));
    assert_eq!(pixel_jitter(4, 1763, 7), 4_099_845_390.0 / 4_294_967_296.0 - 0.5, "4 + 1763·7 = 12345");
}
