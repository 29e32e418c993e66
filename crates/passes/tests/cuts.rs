//! Crop boxes and clip planes (issue 24 §3; `volgraph_accel::cuts`, `shaders/common/ray_box.wgsl`
//! `cut_segment`): every raycaster family against the f64 reference with the same cuts, and a
//! crop against the volume with the cut-away part zeroed.
//!
//! Tolerances, per channel of premultiplied linear RGBA:
//! - against the reference, as `gpu_vs_reference.rs` bounds the uncut images (f32 on the GPU,
//!   f64 on the CPU), plus the cut itself: a sample that lies within f32 rounding of a crop face
//!   or clip plane is kept on one side and dropped on the other, which moves that pixel by one
//!   sample's contribution. Such rays are rare (the grid would have to land within ~1e-6 of the
//!   face), so at most 0.5 % of pixels may differ by more than 2/255 and the mean stays under
//!   0.5/255.
//! - crop vs zeroed: the same GPU, the same sample positions and the same data wherever a ray
//!   stays clear of the cut by the filters' reach (trilinear, plus one voxel for the
//!   isosurface's central-difference gradient), so those pixels agree to f32 rounding (1e-5);
//!   rays that pass within the reach are exempt (there the zeroed volume still blends the last
//!   kept voxel layer with zeros, the crop drops the samples).

use glam::DVec3;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};
use volgraph_accel::image_diff::{fraction_over, image_diff};
use volgraph_accel::reference::{ray_segment, render_reference};
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::runtime::{CameraData, Image, VolumeDesc, VolumeWindow, scene_values_of};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

mod support;

use support::{gpu, graph_source};

const SIZE: u32 = 96;

/// `graph` rendered on the GPU with `cuts` and scene `features` under the headlight, and the
/// reference settings of its "march" pass (`support::render_in_scene`).
fn render_cut(
    gpu: &std::sync::Arc<volgraph_core::runtime::Gpu>,
    graph: &str,
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    cuts: Cuts,
    features: &[&str],
) -> (Image, volgraph_accel::reference::RaycastSettings) {
    let scene = (volgraph_accel::light::Light::Headlight, cuts);
    support::render_in_scene(gpu, (graph, SIZE), (volume, lut), camera, scene, features)
}

fn cuts_to_test() -> Vec<(&'static str, Cuts)> {
    let crop = CropBox::new(DVec3::new(0.1, 0.2, 0.0), DVec3::new(0.7, 0.9, 0.6)).expect("box");
    let oblique = ClipPlane::new(DVec3::new(1.0, 1.0, 0.0), 0.9).expect("plane");
    let back = ClipPlane::new(DVec3::new(0.0, 0.0, -1.0), -0.8).expect("plane");
    vec![
        ("crop", Cuts::new(Some(crop), &[]).expect("cuts")),
        ("clip", Cuts::new(None, &[oblique]).expect("cuts")),
        ("crop+2 clips", Cuts::new(Some(crop), &[oblique, back]).expect("cuts")),
    ]
}

/// Every raycaster family — fragment, compute with leaping, multipass segments with their
/// termination test, bricks with an octree, Klein's isosurface with leaping — crops and clips
/// like the f64 reference.
#[test]
fn every_raycaster_crops_and_clips_like_the_reference() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(64);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    for graph in [
        "basic/fragment_raycast.ron",
        "modern/fastest.ron",
        "kruger_westermann_2003/rc_b_leap.ron",
        "ruijters_vilanova_2006/bricks_octree_ert.ron",
        "basic/isosurface.ron",
        "klein_2005/leap_iso.ron",
    ] {
        for (name, cuts) in cuts_to_test() {
            let (image, settings) = render_cut(&gpu, graph, &volume, &lut, &OrbitCamera::default(), cuts, &[]);
            let reference = render_reference(&volume, &lut, &OrbitCamera::default(), SIZE, SIZE, &settings);
            let uncut = render_reference(
                &volume,
                &lut,
                &OrbitCamera::default(),
                SIZE,
                SIZE,
                &volgraph_accel::reference::RaycastSettings { cuts: Cuts::NONE, ..settings },
            );
            let got = image.to_rgba_f64();
            let diff = image_diff(&got, &reference.color).expect("same size");
            let over = fraction_over(&got, &reference.color, 2.0 / 255.0).expect("same size");
            // The cut changed the picture: a test that passes without cutting proves nothing.
            let changed = fraction_over(&uncut.color, &reference.color, 8.0 / 255.0).expect("same size");
            eprintln!(
                "{graph} {name}: max {:.2}/255 mean {:.3}/255, {:.2}% over 2/255; the cut changed {:.0}% of pixels",
                diff.max_abs * 255.0,
                diff.mean_abs * 255.0,
                over * 100.0,
                changed * 100.0
            );
            assert!(changed > 0.05, "{graph} {name}: the cut must change the image ({:.1}%)", changed * 100.0);
            assert!(over <= 0.005, "{graph} {name}: {:.2}% of pixels over 2/255", over * 100.0);
            assert!(diff.mean_abs <= 0.5 / 255.0, "{graph} {name}: mean {:.3}/255", diff.mean_abs * 255.0);
        }
    }
}

/// Shaded DVR with cuts: the cut faces are capped (shaded with the plane they were cut along,
/// `Cuts::cap_normal`) on the GPU as in the reference, within the bounds above. The engine's
/// opaque material makes the faces visible; the blend toward the face normal is continuous, so
/// f32 and f64 differ only by rounding there.
#[test]
fn shaded_cut_faces_are_capped_like_the_reference() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(64);
    // Opaque material: rays end a few samples behind a cut face, so its shading is what shows.
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    for graph in ["basic/fragment_raycast.ron", "modern/fastest.ron"] {
        for (name, cuts) in cuts_to_test() {
            let (image, settings) = render_cut(&gpu, graph, &volume, &lut, &camera, cuts, &["shading"]);
            assert!(settings.effects.shading, "{graph}: shading reaches the reference settings");
            let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
            let got = image.to_rgba_f64();
            let visible = got.iter().filter(|p| p[3] > 0.05).count() as f64 / got.len() as f64;
            let extra = format!(", {:.0}% of pixels visible", visible * 100.0);
            support::assert_shaded_like_reference(&format!("{graph} {name} shaded"), &got, &reference.color, &extra);
            assert!(visible > 0.1, "{graph} {name}: the shaded, cut volume is on screen");
        }
    }
}

/// A crop to the half x < 0.5 renders like the whole volume with the other half zeroed: on the
/// GPU, pixel for pixel wherever the ray stays clear of the cut by the filter's reach.
#[test]
fn a_crop_to_half_renders_like_the_other_half_zeroed() {
    let gpu = gpu();
    let n = 64u32;
    let volume = volgraph_accel::generate::marschner_lobb_f32(n);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    assert_eq!(lut[0][3], 0.0, "zero must be transparent for zeroing to mean removing");
    // Samples at x < 0.5 read voxels up to index 32 (trilinear between centres 31.5/64 and
    // 32.5/64): zero from 33 on, and samples past 33.5/64 read zeros only.
    let reach_end = 33.5 / n as f64;
    let VoxelData::F32(data) = &volume.data else { panic!("an f32 volume") };
    let mut zeroed_data = data.clone();
    for (i, v) in zeroed_data.iter_mut().enumerate() {
        if i as u32 % n >= 33 {
            *v = 0.0;
        }
    }
    let zeroed = Volume { data: VoxelData::F32(zeroed_data), ..volume.clone() };
    let half = Cuts::new(Some(CropBox::new(DVec3::ZERO, DVec3::new(0.5, 1.0, 1.0)).expect("box")), &[]).expect("cuts");
    // Looking down -z with a narrow field: most rays stay on one side of x = 0.5.
    let camera =
        OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 4.0, fov_y_deg: 20.0, ..OrbitCamera::default() };
    let frame = camera.frame(SIZE, SIZE);
    for graph in ["basic/fragment_raycast.ron", "modern/fastest.ron", "basic/isosurface.ron"] {
        let (cropped, _) = render_cut(&gpu, graph, &volume, &lut, &camera, half, &[]);
        let (zeroed_image, _) = render_cut(&gpu, graph, &zeroed, &lut, &camera, Cuts::NONE, &[]);
        let (a, b) = (cropped.to_rgba_f64(), zeroed_image.to_rgba_f64());
        let (mut compared, mut worst, mut visible) = (0usize, 0.0f64, 0usize);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let i = (y * SIZE + x) as usize;
                let clear = match ray_segment(&volume, &camera, &frame, x, y) {
                    None => true,
                    Some(seg) => {
                        let x0 = seg.u0.x;
                        let x1 = (seg.u0 + seg.len_tex * seg.d_tex).x;
                        let (lo, hi) = (x0.min(x1), x0.max(x1));
                        // The shading gradient's central differences reach one voxel further.
                        let gradient = 1.0 / n as f64;
                        hi < 0.5 - gradient - 1e-3 || lo > reach_end + gradient + 1e-3
                    }
                };
                if !clear {
                    continue;
                }
                compared += 1;
                visible += usize::from(a[i][3] > 0.01);
                for c in 0..4 {
                    worst = worst.max((a[i][c] - b[i][c]).abs());
                }
            }
        }
        eprintln!("{graph}: {compared} pixels clear of the cut ({visible} visible), worst {worst:.2e}");
        assert!(compared as u32 > SIZE * SIZE / 3, "{graph}: most rays stay clear of the cut ({compared})");
        assert!(visible > 200, "{graph}: the kept half shows something ({visible})");
        assert!(worst <= 1e-5, "{graph}: worst {worst:.2e} where the rays stay clear of the cut");
    }
}

/// A cut the runtime was not compiled for is refused at the next frame, never drawn uncut.
#[test]
fn cuts_set_after_the_plan_are_refused_until_it_is_applied_again() {
    let gpu = gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(32);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let source = graph_source("basic/fragment_raycast.ron");
    let mut options = CompileOptions::new(32, 32);
    options.scene = scene_values_of(&VolumeDesc::of(&volume));
    let plan = compile("fragment_raycast", &source, &registry, &options).expect("compiles");
    let mut runtime = support::runtime(&gpu);
    runtime.bind_scene(&plan.inputs, &volume, &lut).expect("binds");
    runtime.apply(plan.clone(), &registry).expect("applies");
    let crop = Cuts::new(Some(CropBox::new(DVec3::ZERO, DVec3::splat(0.5)).expect("box")), &[]).expect("cuts");
    runtime.set_cuts(crop);
    let err =
        runtime.render(CameraData::from_orbit(&OrbitCamera::default(), (32, 32))).expect_err("not compiled for a crop");
    assert!(err.to_string().contains("crop") && err.to_string().contains("apply the plan again"), "{err}");
    runtime.apply(plan, &registry).expect("applies with the crop");
    runtime.render(CameraData::from_orbit(&OrbitCamera::default(), (32, 32))).expect("renders cropped");
}

/// A sort-last window is compiled in like a cut (the `WINDOW` define, so that frames without one
/// pay nothing for it): a window set after the plan is refused at the next frame, never drawn
/// as the whole volume; applied again, the frame renders the window's half only.
#[test]
fn a_window_set_after_the_plan_is_refused_until_it_is_applied_again() {
    let gpu = gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(32);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let source = graph_source("modern/fastest.ron");
    let mut options = CompileOptions::new(32, 32);
    options.scene = scene_values_of(&VolumeDesc::of(&volume));
    let plan = compile("fastest", &source, &registry, &options).expect("compiles");
    let mut runtime = support::runtime(&gpu);
    runtime.bind_scene(&plan.inputs, &volume, &lut).expect("binds");
    runtime.apply(plan.clone(), &registry).expect("applies");
    let camera = CameraData::from_orbit(&OrbitCamera::default(), (32, 32));
    runtime.render(camera).expect("renders the whole volume");
    let whole = runtime.read_output("image").expect("image");
    // This rank owns the low half in x of the 32³ volume (all of whose voxels it holds).
    let dims = glam::UVec3::splat(32);
    let window =
        VolumeWindow::new(dims, DVec3::ONE, glam::UVec3::ZERO, glam::UVec3::ZERO, glam::UVec3::new(16, 32, 32));
    runtime.set_volume_window(Some(window));
    let err = runtime.render(camera).expect_err("not compiled for a window");
    assert!(err.to_string().contains("window") && err.to_string().contains("apply the plan again"), "{err}");
    runtime.apply(plan, &registry).expect("applies with the window");
    runtime.render(camera).expect("renders the window");
    let half = runtime.read_output("image").expect("image");
    let alpha = |image: &Image| -> f64 {
        (0..image.height)
            .flat_map(|y| (0..image.width).map(move |x| (x, y)))
            .map(|(x, y)| image.rgba(x, y)[3] as f64)
            .sum()
    };
    let (whole_alpha, half_alpha) = (alpha(&whole), alpha(&half));
    assert!(whole_alpha > 1.0, "the volume is in view ({whole_alpha})");
    assert!(
        half_alpha > 0.05 * whole_alpha && half_alpha < 0.95 * whole_alpha,
        "the window renders part of the volume: {half_alpha} of {whole_alpha}"
    );
}

/// A graph with a pass that samples the volume its own way (slice-based rendering) is refused
/// with a cut, naming the pass: it would draw the cut-away part.
#[test]
fn a_pass_that_cannot_cut_is_refused_by_name() {
    let registry = builtin_registry();
    let source = graph_source("kruger_westermann_2003/sbvr.ron");
    let options = CompileOptions::new(32, 32).with_features(["crop"]);
    let err = compile("sbvr", &source, &registry, &options).expect_err("slices cannot crop").to_string();
    assert!(err.contains("cannot crop") && err.contains("slice"), "{err}");
}
