//! The hard cases of the reference renderer (`docs/rendering_model.md`, "Ray segment inside the
//! box"): axis-aligned and grazing rays, the camera inside the volume, tiny steps, degenerate
//! rays and volumes. Bad input gives transparent pixels, never NaN or a panic.

use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{
    RaycastSettings, ReferenceImage, intersect_box, ray_segment, render_reference, step_tex,
};
use volgraph_accel::volume::{Volume, VoxelData};

fn constant_volume(dims: UVec3, value: u8) -> Volume {
    let n = (dims.x * dims.y * dims.z) as usize;
    Volume {
        dims,
        spacing: DVec3::ONE,
        data: VoxelData::U8(vec![value; n]),
        name: "constant".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    }
}

const LUT: [[f32; 4]; 1] = [[1.0, 0.5, 0.25, 0.2]];

fn assert_finite_premultiplied(image: &ReferenceImage, what: &str) {
    for (i, c) in image.color.iter().enumerate() {
        assert!(c.iter().all(|v| v.is_finite()), "{what}: pixel {i} is {c:?}");
        assert!((0.0..=1.0).contains(&c[3]), "{what}: pixel {i} alpha {c:?}");
        // Premultiplied with LUT colours <= 1: no channel exceeds alpha (1e-12: f64 rounding).
        assert!(c[..3].iter().all(|v| *v <= c[3] + 1e-12), "{what}: pixel {i} not premultiplied {c:?}");
    }
}

/// `1 - (1-α)^(n·step)` with n from the pixel's segment, as in reference_dvr.rs.
fn closed_form_alpha(volume: &Volume, camera: &OrbitCamera, w: u32, h: u32, x: u32, y: u32, step: f64) -> f64 {
    let frame = camera.frame(w, h);
    let Some(seg) = ray_segment(volume, camera, &frame, x, y) else {
        return 0.0;
    };
    let st = step_tex(volume, seg.d_tex, step);
    let n = (seg.len_tex / st - 0.5).ceil().max(0.0);
    1.0 - (1.0 - LUT[0][3] as f64).powf(n * step)
}

#[test]
fn slab_test_handles_zero_direction_components() {
    let half = DVec3::splat(0.5);
    // Exactly axis-aligned: the y and z components are 0 (and -0), not tiny.
    assert_eq!(intersect_box(DVec3::new(-2.0, 0.0, 0.0), DVec3::X, half), Some((1.5, 2.5)));
    assert_eq!(intersect_box(DVec3::new(-2.0, 0.1, 0.2), DVec3::new(1.0, -0.0, 0.0), half), Some((1.5, 2.5)));
    // Lying in a face plane or along an edge: the box is closed, so these hit.
    assert_eq!(intersect_box(DVec3::new(-2.0, 0.5, 0.0), DVec3::X, half), Some((1.5, 2.5)));
    assert_eq!(intersect_box(DVec3::new(-2.0, 0.5, -0.5), DVec3::X, half), Some((1.5, 2.5)));
    // Just outside the face plane: a miss, not NaN.
    assert_eq!(intersect_box(DVec3::new(-2.0, 0.5 + 1e-12, 0.0), DVec3::X, half), None);
    // From inside: t_in is behind the origin.
    assert_eq!(intersect_box(DVec3::ZERO, DVec3::NEG_Z, half), Some((-0.5, 0.5)));
    // Degenerate directions give no ray.
    assert_eq!(intersect_box(DVec3::ZERO, DVec3::ZERO, half), None);
    assert_eq!(intersect_box(DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 1.0), half), None);
    // Touching only an edge: zero-length segment t_in = t_out = 0.5·√2 (1e-15: rounding of √2).
    let d = DVec3::new(1.0, 1.0, 0.0).normalize();
    let (t_in, t_out) = intersect_box(DVec3::new(-1.0, 0.0, 0.0), d, half).expect("touches the edge");
    assert!((t_in - 0.5f64.sqrt()).abs() < 1e-15 && (t_out - t_in).abs() < 1e-15, "({t_in}, {t_out})");
}

#[test]
fn axis_aligned_cameras_give_finite_images_with_the_exact_centre_value() {
    let volume = constant_volume(UVec3::splat(8), 255);
    // 33 × 33: the centre pixel (16, 16) looks exactly at the origin along an axis.
    for (az, el) in [(0.0, 0.0), (90.0, 0.0), (180.0, 0.0), (-90.0, 0.0), (0.0, 90.0), (0.0, -90.0)] {
        let camera = OrbitCamera { azimuth_deg: az, elevation_deg: el, ..Default::default() };
        let image = render_reference(&volume, &LUT, &camera, 33, 33, &RaycastSettings::default());
        assert_finite_premultiplied(&image, &format!("az {az} el {el}"));
        // len_tex = 1 along the axis, step 1/16 → 16 samples, A = 1 - 0.8^8 (1e-12: rounding
        // of the nearly axis-aligned direction and 16 compounding steps).
        let a = image.color[image.index(16, 16)][3];
        let want = 1.0 - (1.0 - 0.2f32 as f64).powi(8);
        assert!((a - want).abs() < 1e-12, "az {az} el {el}: centre A {a}, want {want}");
    }
}

#[test]
fn camera_inside_the_volume_starts_rays_at_the_near_plane() {
    let volume = constant_volume(UVec3::splat(8), 255);
    // Eye at (0, 0, 0.1), inside the box [-0.5, 0.5]³, looking down -z.
    let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 0.1, ..Default::default() };
    let (w, h) = (15, 11);
    let frame = camera.frame(w, h);
    let seg = ray_segment(&volume, &camera, &frame, 7, 5).expect("the centre ray starts inside");
    // Near plane at z = 0.1 - 0.01 = 0.09 → u0.z = 0.59; exit at z = -0.5 → len_tex = 0.59.
    // 1e-12: rounding of the unprojected direction.
    assert!((seg.u0 - DVec3::new(0.5, 0.5, 0.59)).length() < 1e-12, "u0 {}", seg.u0);
    assert!((seg.len_tex - 0.59).abs() < 1e-12, "len {}", seg.len_tex);
    let image = render_reference(&volume, &LUT, &camera, w, h, &RaycastSettings::default());
    assert_finite_premultiplied(&image, "inside");
    for y in 0..h {
        for x in 0..w {
            let a = image.color[image.index(x, y)][3];
            assert!(a > 0.5, "({x},{y}): every ray crosses at least ~0.4 of the box, A {a}");
            let want = closed_form_alpha(&volume, &camera, w, h, x, y, 0.5);
            assert!((a - want).abs() < 1e-12, "({x},{y}): A {a} vs closed form {want}");
        }
    }
}

#[test]
fn grazing_rays_at_the_silhouette_stay_finite() {
    // Corner-on view: many pixels graze edges and faces; compare every pixel to its closed form.
    let volume = constant_volume(UVec3::new(7, 5, 3), 255);
    let camera = OrbitCamera { azimuth_deg: 45.0, elevation_deg: 35.264389682754654, ..Default::default() };
    let (w, h) = (64, 64);
    let image = render_reference(&volume, &LUT, &camera, w, h, &RaycastSettings::default());
    assert_finite_premultiplied(&image, "corner-on");
    let mut nonzero = 0;
    for y in 0..h {
        for x in 0..w {
            let a = image.color[image.index(x, y)][3];
            nonzero += (a > 0.0) as u32;
            let want = closed_form_alpha(&volume, &camera, w, h, x, y, 0.5);
            assert!((a - want).abs() < 1e-12, "({x},{y}): A {a} vs closed form {want}");
        }
    }
    assert!(nonzero > 100 && nonzero < w * h, "the box covers part of the view ({nonzero} pixels)");
}

#[test]
fn tiny_steps_match_the_closed_form() {
    // 0.01 voxel on a 4³ volume: step_tex = 1/400, up to ~690 samples per ray.
    let volume = constant_volume(UVec3::splat(4), 255);
    let camera = OrbitCamera { azimuth_deg: 20.0, elevation_deg: 10.0, ..Default::default() };
    let settings = RaycastSettings { step_voxels: 0.01, ..Default::default() };
    let (w, h) = (6, 5);
    let image = render_reference(&volume, &LUT, &camera, w, h, &settings);
    assert_finite_premultiplied(&image, "tiny steps");
    for y in 0..h {
        for x in 0..w {
            let a = image.color[image.index(x, y)][3];
            let want = closed_form_alpha(&volume, &camera, w, h, x, y, 0.01);
            // 1e-10: ~700 compounding f64 steps each off by ~1e-16 relative.
            assert!((a - want).abs() < 1e-10, "({x},{y}): A {a} vs {want}");
        }
    }
    assert!(image.samples > 1000, "{} samples", image.samples);
}

#[test]
fn a_one_voxel_volume_renders_like_a_constant_box() {
    let volume = constant_volume(UVec3::ONE, 255);
    let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, ..Default::default() };
    let image = render_reference(&volume, &LUT, &camera, 1, 1, &RaycastSettings::default());
    // unit_world = 1 (the voxel is the box), step_tex = 0.5, len 1: samples at 0.25 and 0.75,
    // A = 1 - 0.8^(2·0.5) = 0.2 (to the f32 rounding of 0.2, compared in f64: 1e-12).
    assert_eq!(image.samples, 2);
    assert!((image.color[0][3] - 0.2f32 as f64).abs() < 1e-12, "{:?}", image.color[0]);
}

#[test]
fn degenerate_inputs_give_transparent_images_without_panicking() {
    let camera = OrbitCamera::default();
    let settings = RaycastSettings::default();
    let empty = Volume {
        dims: UVec3::ZERO,
        spacing: DVec3::ONE,
        data: VoxelData::U8(vec![]),
        name: "empty".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    };
    let image = render_reference(&empty, &LUT, &camera, 4, 3, &settings);
    assert_eq!((image.color.len(), image.samples), (12, 0));
    assert!(image.color.iter().all(|c| *c == [0.0; 4]));
    // Data shorter than dims claim.
    let short = Volume { data: VoxelData::U8(vec![1; 7]), ..constant_volume(UVec3::splat(2), 1) };
    assert_eq!(render_reference(&short, &LUT, &camera, 4, 3, &settings).samples, 0);
    // Zero-sized image.
    let volume = constant_volume(UVec3::splat(4), 255);
    let image = render_reference(&volume, &LUT, &camera, 0, 5, &settings);
    assert!(image.color.is_empty() && image.hit.is_empty());
    // Non-positive or NaN step: no samples rather than an endless or NaN march.
    for step_voxels in [0.0, -1.0, f64::NAN] {
        let image = render_reference(&volume, &LUT, &camera, 4, 3, &RaycastSettings { step_voxels, ..settings });
        assert_eq!(image.samples, 0, "step {step_voxels}");
        assert!(image.color.iter().all(|c| *c == [0.0; 4]));
    }
    // Eye at the origin: look-at is undefined (NaN matrices); every pixel must be transparent.
    let at_origin = OrbitCamera { distance: 0.0, ..camera };
    let image = render_reference(&volume, &LUT, &at_origin, 4, 3, &settings);
    assert!(image.color.iter().all(|c| *c == [0.0; 4]), "eye at the origin: {:?}", image.color);
    assert_eq!(image.samples, 0);
}
