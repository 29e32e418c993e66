//! Ruijters & Vilanova 2006 as graphs (`graphs/ruijters_vilanova_2006/`): the brick pool, the
//! per-brick octrees and early ray termination must not change the image. Every bricked graph
//! equals the single-texture raycast (`unoptimized.ron`, same samples and compositing) within
//! 1/255 for brick sizes 16³–64³ and node limits 4³–8³ on generated and real data, odd sizes
//! and anisotropic spacing included; a pool of a handful of bricks (LRU thrashing) gives the
//! same image; the camera may sit inside the volume; a TF change re-classifies without uploading
//! bricks already resident; a volume beyond the 3D texture limit renders through the pool and
//! matches the f64 reference. Failure images go to target/test-images.

use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{RaycastSettings, render_reference};
use volgraph_accel::transfer_function::{ControlPoint, Preset, TransferFunction};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::runtime::{CameraData, Gpu, Image, volume_texture_format};
use volgraph_core::{CompileOptions, Registry};
use volgraph_passes::builtin_registry;

mod support;

use support::{Live, as_reference, coverage, diff_reference, save_images};

const SIZE: u32 = 96;

/// A TF from `(value, rgb, alpha)` points.
fn tf_points(domain: (f64, f64), points: &[(f64, [f64; 3], f64)]) -> TransferFunction {
    let points = points.iter().map(|&(value, color, alpha)| ControlPoint { value, color, alpha }).collect();
    TransferFunction { domain, points }
}

/// `graphs/ruijters_vilanova_2006/<graph>.ron` applied with `volume` and `lut`.
fn live(
    gpu: &Arc<Gpu>,
    registry: &Registry,
    graph: &str,
    volume: &Volume,
    lut: &[[f32; 4]],
    options: &CompileOptions,
) -> Live {
    Live::new(gpu, registry, &format!("ruijters_vilanova_2006/{graph}.ron"), volume, lut, options)
}

fn camera(azimuth: f64, distance: f64) -> OrbitCamera {
    OrbitCamera { azimuth_deg: azimuth, elevation_deg: 25.0, distance, ..OrbitCamera::default() }
}

/// Bricking changes no pixel beyond rounding: 1/255 covers the f16 colour target's rounding of
/// the same samples. The ERT graph stops at alpha 1 - 1/255, so what it leaves out is at most
/// 1/255 more.
fn assert_same(name: &str, got: &Image, want: &Image, tolerance: f64) {
    assert_close(name, got, want, tolerance, 0.0);
}

/// As [`assert_same`], but a fraction `outliers` of the pixels may differ by up to 16/255: on
/// white noise under a steep TF (one value unit moves alpha by 0.04), the GPU's 8-bit trilinear
/// weights round differently for the same position addressed in the atlas and in the whole
/// volume — a neighbour 255 values away then shifts a sample by a value unit. A culled brick or
/// leaf would change every pixel of its footprint (tens of pixels) by far more.
fn assert_close(name: &str, got: &Image, want: &Image, tolerance: f64, outliers: f64) {
    let want = as_reference(want);
    let (max, _) = diff_reference(got, &want);
    let over = (0..got.height)
        .flat_map(|y| (0..got.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let w = want[(y * got.width + x) as usize];
            got.rgba(x, y).iter().zip(w).any(|(g, w)| (*g as f64 - w).abs() > tolerance)
        })
        .count() as f64
        / (got.width * got.height) as f64;
    if max > tolerance {
        save_images(name, got, &want);
    }
    let max_allowed = if outliers > 0.0 { 16.0 / 255.0 } else { tolerance };
    assert!(
        over <= outliers && max <= max_allowed,
        "{name}: {:.3}% of pixels differ by more than {:.3}/255 (max {:.3}/255)",
        over * 100.0,
        tolerance * 255.0,
        max * 255.0
    );
}

const SAME: f64 = 1.0 / 255.0;
const SAME_ERT: f64 = 2.0 / 255.0;

/// Generated and real datasets with a TF that shows something: the vessel tree (sparse like
/// the paper's angiography), the same with anisotropic spacing (vis_male-like 1:1:2.5), noise
/// with a narrow band (many tiny visible islands: nothing visible may be culled), and the
/// real lobster (301×324×56: bricks never divide it) and hydrogen_atom where the data folder
/// has them.
/// The volumes, their LUT and the fraction of pixels allowed past the tolerance (see
/// [`assert_close`]: white noise only).
fn datasets() -> Vec<(Volume, Vec<[f32; 4]>, f64)> {
    let vessels = volgraph_accel::vessels::vessel_tree(80, 3);
    let vessel_tf = TransferFunction::from_ron_str(
        &std::fs::read_to_string(support::graph_path("tf/vessels.ron")).expect("tf"),
        std::path::Path::new("graphs/tf/vessels.ron"),
    )
    .expect("vessel tf");
    let mut stretched = vessels.clone();
    stretched.name = "vessels_anisotropic".to_string();
    stretched.spacing = glam::DVec3::new(1.0, 1.0, 2.5);
    let noise = volgraph_accel::generate::noise(40, 11);
    let band = tf_points(
        (0.0, 255.0),
        &[(0.0, [0.0; 3], 0.0), (200.0, [0.0; 3], 0.0), (215.0, [1.0, 0.8, 0.2], 0.6), (230.0, [0.0; 3], 0.0)],
    );
    let mut out = vec![
        (vessels.clone(), vessel_tf.to_lut_for(&vessels, 256), 0.0),
        (stretched.clone(), vessel_tf.to_lut_for(&stretched, 256), 0.0),
        (noise.clone(), band.to_lut_for(&noise, 256), 0.002),
    ];
    for name in ["lobster", "hydrogen_atom"] {
        if volgraph_accel::data_dir::require_dataset(name).is_some() {
            let v = volgraph_accel::data_dir::load_dataset(name).expect("loads").volume;
            let lut = TransferFunction::default_for(&v).to_lut_for(&v, 256);
            out.push((v, lut, 0.0));
        }
    }
    out
}

#[test]
fn every_bricked_graph_equals_the_single_texture_raycast() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    for (volume, lut, outliers) in datasets() {
        let base_options = CompileOptions::new(SIZE, SIZE);
        let mut base = live(&gpu, &registry, "unoptimized", &volume, &lut, &base_options);
        let cams = [camera(30.0, 2.6), camera(200.0, 2.2)];
        let want: Vec<Image> = cams.iter().map(|c| base.frame(c)).collect();
        assert!(coverage(&want[0]) > 0.02, "{}: the volume is in view", volume.name);
        for brick in [16.0, 32.0, 64.0] {
            for (graph, nodes) in
                [("bricks", 0.0), ("bricks_octree", 4.0), ("bricks_octree", 8.0), ("bricks_octree_ert", 8.0)]
            {
                let options =
                    CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", brick).with_scalar("node_cells", nodes);
                let mut bricked = live(&gpu, &registry, graph, &volume, &lut, &options);
                let tolerance = if graph.ends_with("ert") { SAME_ERT } else { SAME };
                for (cam, w) in cams.iter().zip(&want) {
                    let got = bricked.frame(cam);
                    let name = format!("rv_{graph}_{}_b{brick}_n{nodes}_az{}", volume.name, cam.azimuth_deg);
                    assert_close(&name, &got, w, tolerance, outliers);
                }
                let visible = bricked.counter("visible_bricks");
                let total = bricked.counter("bricks");
                assert!(visible <= total && bricked.counter("batches") == 1.0, "{}: in core, one batch", volume.name);
            }
        }
    }
}

/// The brick march maps invocations to pixels like `raycast_compute` (`invocation_pixel`,
/// common/workgroup_pixel.wgsl: 4×2 tiles where the workgroup allows, rows otherwise), and its
/// per-pixel `acc` buffer is indexed by that pixel: every shape must write every pixel exactly
/// once with its own ray. Pixels share nothing, so the images are compared bit for bit against
/// one-invocation workgroups; a pixel written twice, never, or with another's colour shows.
#[test]
fn every_workgroup_shape_writes_every_brick_pixel_with_its_own_ray() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::vessels::vessel_tree(64, 5);
    let lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 256);
    let cam = camera(40.0, 2.6);
    let shaped = |x: u64, y: u64| {
        let mut options =
            CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0).with_scalar("node_cells", 4.0);
        options.param_overrides.insert("march.workgroup_x".into(), ron::Value::from(x));
        options.param_overrides.insert("march.workgroup_y".into(), ron::Value::from(y));
        live(&gpu, &registry, "bricks_octree", &volume, &lut, &options).frame(&cam)
    };
    let want = shaped(1, 1);
    assert!(coverage(&want) > 0.02, "the vessels are in view");
    // Tiled: 8×8 (the default), 4×2 (one tile), 12×6 (three tiles a row); rows: 6×3, 7×7 (96 is
    // no multiple of 7: partial groups at the edges).
    for (x, y) in [(8, 8), (4, 2), (12, 6), (6, 3), (7, 7)] {
        let got = shaped(x, y);
        let differ = (0..want.height)
            .flat_map(|py| (0..want.width).map(move |px| (px, py)))
            .filter(|&(px, py)| got.rgba(px, py) != want.rgba(px, py))
            .count();
        assert_eq!(differ, 0, "workgroup {x}×{y}: {differ} pixels differ from 1×1 workgroups");
    }
}

/// A pool of a handful of bricks: every frame streams the bricks in batches and evicts the least
/// recently used — slower, and the same image.
#[test]
fn a_pool_of_a_few_bricks_thrashes_but_gives_the_same_image() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::vessels::vessel_tree(64, 5);
    let tf = TransferFunction::preset(Preset::Sparse, (0.0, 255.0));
    let lut = tf.to_lut_for(&volume, 256);
    let mut base = live(&gpu, &registry, "unoptimized", &volume, &lut, &CompileOptions::new(SIZE, SIZE));
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0).with_scalar("node_cells", 4.0);
    let mut small = live(&gpu, &registry, "bricks_octree", &volume, &lut, &options);
    // (16 + 3)³ voxels per slot in the device's format (R16Unorm on lavapipe): room for three
    // bricks.
    let voxel_bytes = volume_texture_format(&gpu, &volume).bytes() as u64;
    small.runtime.set_gpu_memory_budget(Some(3 * 19 * 19 * 19 * voxel_bytes));
    for azimuth in [0.0, 40.0, 80.0] {
        let cam = camera(azimuth, 2.6);
        let want = base.frame(&cam);
        let got = small.frame(&cam);
        assert_same(&format!("rv_small_pool_az{azimuth}"), &got, &want, SAME);
        assert_eq!(small.counter("pool_slots"), 3.0);
        let visible = small.counter("visible_bricks");
        assert!(visible > 6.0, "the frame needs more bricks ({visible}) than the pool holds");
        assert_eq!(small.counter("batches"), (visible / 3.0).ceil());
        assert!(small.counter("uploaded_bricks") >= visible - 3.0, "thrashing re-uploads");
    }
}

/// The pipelined sample loop (`march.sample_loop: "pipelined"`, what `auto` picks on a GPU and
/// not on llvmpipe, so forced here) in the brick march: the LUT in workgroup memory and the next
/// sample fetched ahead — from the brick's slot in the atlas, where a run's last look-ahead falls
/// into a neighbouring slot and must not matter. The single-texture raycaster and the brick
/// march pipelined against the plain single-texture one, in core and streaming through a pool of
/// three bricks (several batches); and a LUT longer than the workgroup copy holds (256 texels),
/// which the pipelined loop reads from its texture instead.
#[test]
fn the_pipelined_loop_gives_the_same_image_through_the_brick_pool() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::vessels::vessel_tree(64, 5);
    let lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 256);
    let with_loop = |options: CompileOptions, sample_loop: &str| {
        let mut options = options;
        options.param_overrides.insert("march.sample_loop".into(), ron::Value::String(sample_loop.into()));
        options
    };
    let cam = camera(40.0, 2.6);
    let want =
        live(&gpu, &registry, "unoptimized", &volume, &lut, &with_loop(CompileOptions::new(SIZE, SIZE), "plain"))
            .frame(&cam);
    assert!(coverage(&want) > 0.02, "the vessels are in view");
    let unoptimized =
        live(&gpu, &registry, "unoptimized", &volume, &lut, &with_loop(CompileOptions::new(SIZE, SIZE), "pipelined"))
            .frame(&cam);
    assert_same("rv_pipelined_unoptimized", &unoptimized, &want, SAME);
    let bricks = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0).with_scalar("node_cells", 4.0);
    let mut in_core =
        live(&gpu, &registry, "bricks_octree_ert", &volume, &lut, &with_loop(bricks.clone(), "pipelined"));
    assert_same("rv_pipelined_in_core", &in_core.frame(&cam), &want, SAME_ERT);
    let mut small = live(&gpu, &registry, "bricks_octree_ert", &volume, &lut, &with_loop(bricks, "pipelined"));
    let voxel_bytes = volume_texture_format(&gpu, &volume).bytes() as u64;
    small.runtime.set_gpu_memory_budget(Some(3 * 19 * 19 * 19 * voxel_bytes));
    assert_same("rv_pipelined_small_pool", &small.frame(&cam), &want, SAME_ERT);
    assert!(small.counter("batches") > 1.0, "the pool streams the frame in batches");
    let long_lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 1024);
    let plain = CompileOptions::new(SIZE, SIZE);
    let want = live(&gpu, &registry, "unoptimized", &volume, &long_lut, &with_loop(plain.clone(), "plain")).frame(&cam);
    let got = live(&gpu, &registry, "unoptimized", &volume, &long_lut, &with_loop(plain, "pipelined")).frame(&cam);
    // The same texture lookups on both sides: only the order of the fetches differs.
    assert_same("rv_pipelined_long_lut", &got, &want, SAME);
}

#[test]
fn the_camera_inside_the_volume_sees_the_same_image() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::vessels::vessel_tree(64, 9);
    let lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 256);
    let cam = camera(15.0, 0.25);
    let want = live(&gpu, &registry, "unoptimized", &volume, &lut, &CompileOptions::new(SIZE, SIZE)).frame(&cam);
    assert!(coverage(&want) > 0.02, "something is in view from inside");
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0);
    let got = live(&gpu, &registry, "bricks_octree_ert", &volume, &lut, &options).frame(&cam);
    assert_same("rv_inside", &got, &want, SAME_ERT);
}

/// A new TF re-classifies bricks and octrees on the CPU; bricks already resident are not uploaded
/// again, and only bricks the new TF newly shows are.
#[test]
fn a_tf_change_reclassifies_without_uploading_resident_bricks() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(64);
    let band = |lo: f64, hi: f64| {
        tf_points(
            volume.value_range,
            &[(0.0, [0.0; 3], 0.0), (lo, [0.0; 3], 0.0), (hi, [0.9, 0.6, 0.3], 0.5), (255.0, [1.0; 3], 0.8)],
        )
        .to_lut_for(&volume, 256)
    };
    let wide = band(100.0, 140.0);
    let narrow = band(200.0, 230.0);
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0);
    let mut bricked = live(&gpu, &registry, "bricks_octree", &volume, &wide, &options);
    let cam = camera(20.0, 2.6);
    bricked.frame(&cam);
    let first = bricked.counter("uploaded_bricks");
    assert_eq!(first, bricked.counter("visible_bricks"), "the first frame uploads every visible brick");
    bricked.frame(&cam);
    assert_eq!(bricked.counter("uploaded_bricks"), 0.0, "a steady frame uploads nothing");
    // A narrower TF: fewer visible bricks, all resident already.
    bricked.runtime.bind_lut("tf", &narrow).expect("binds");
    let got = bricked.frame(&cam);
    assert_eq!(bricked.counter("uploaded_bricks"), 0.0, "no re-upload after a TF change");
    assert!(bricked.counter("visible_bricks") <= first);
    let mut base = live(&gpu, &registry, "unoptimized", &volume, &narrow, &CompileOptions::new(SIZE, SIZE));
    assert_same("rv_tf_change", &got, &base.frame(&cam), SAME);
}

/// A volume longer than the device's 3D texture limit cannot be one texture (the single-texture
/// graph says so), but renders through the brick pool and matches the f64 reference.
#[test]
fn a_volume_beyond_the_texture_limit_renders_through_the_brick_pool() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let long = gpu.limits.max_texture_dimension_3d + 1;
    let dims = glam::UVec3::new(long, 32, 32);
    // Smooth waves (sharp steps would measure the reference's f64 filtering against the GPU's
    // 8-bit weights, not bricking) inside a transparent rim, so no visible sample sits on a box
    // face that a grazing ray meets in f32 and misses in f64; voxels 8 thick across, a beam 8:1:1.
    let wave = |i: u32, period: f64| (i as f64 * std::f64::consts::TAU / period).sin();
    let data: Vec<u8> = (0..dims.x * 32 * 32)
        .map(|i| {
            let (x, y, z) = (i % long, (i / long) % 32, i / (long * 32));
            let rim = x < 4 || x + 4 >= long || !(2..30).contains(&y) || !(2..30).contains(&z);
            if rim { 30 } else { (150.0 + 60.0 * wave(x, 400.0) + 40.0 * wave(y, 32.0)).round() as u8 }
        })
        .collect();
    let volume = Volume::new("long".to_string(), dims, glam::DVec3::new(1.0, 8.0, 8.0), VoxelData::U8(data));
    let lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 256);
    // A step of 4 thin voxels (half a thick one) keeps rays to a few hundred samples, like the
    // other GPU-vs-reference tests.
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 64.0).with_scalar("step_voxels", 4.0);
    let cam = OrbitCamera { azimuth_deg: 20.0, elevation_deg: 15.0, distance: 1.6, ..OrbitCamera::default() };
    let mut base = live(&gpu, &registry, "unoptimized", &volume, &lut, &options);
    let err = base.runtime.render(CameraData::from_orbit(&cam, base.viewport)).expect_err("too large for one texture");
    assert!(err.to_string().contains("bricking"), "{err}");
    let mut bricked = live(&gpu, &registry, "bricks", &volume, &lut, &options);
    let got = bricked.frame(&cam);
    let settings = RaycastSettings { step_voxels: 4.0, threshold: 1.0, ..RaycastSettings::default() };
    let reference = render_reference(&volume, &lut, &cam, SIZE, SIZE, &settings);
    let (max, mean) = diff_reference(&got, &reference.color);
    let want = &reference.color;
    let over = (0..got.height)
        .flat_map(|y| (0..got.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            got.rgba(x, y)
                .iter()
                .zip(want[(y * got.width + x) as usize])
                .any(|(g, w)| (*g as f64 - w).abs() > 2.0 / 255.0)
        })
        .count() as f64
        / (got.width * got.height) as f64;
    if max > 2.0 / 255.0 {
        save_images("rv_long", &got, want);
    }
    assert!(coverage(&got) > 0.03, "the volume is in view");
    // Against f64, the tolerance of the GPU-vs-reference tests (tests/gpu_vs_reference.rs: f32
    // positions, 8-bit filtering weights, an f16 target) on all but a few pixels: at the steep
    // edges of these blobs a position rounded differently moves a sample across the TF's ramp
    // (up to 8/255, on about 0.5 % of the pixels; the single-texture raycast does the same on a
    // half-length copy, where the next test shows bricking itself changes nothing).
    assert!(
        over <= 0.01 && max <= 10.0 / 255.0 && mean <= 0.5 / 255.0,
        "{:.2}% over 2/255, max {:.3}/255 mean {:.4}/255",
        over * 100.0,
        max * 255.0,
        mean * 255.0
    );
    // The same beam at a length one texture holds: bricks equal the single-texture raycast.
    let half = long / 2;
    let short = Volume::new(
        "half".to_string(),
        glam::UVec3::new(half, 32, 32),
        volume.spacing,
        VoxelData::U8(match &volume.data {
            VoxelData::U8(v) => v.chunks(long as usize).flat_map(|row| row[..half as usize].to_vec()).collect(),
            _ => unreachable!("built as u8 above"),
        }),
    );
    let want = live(&gpu, &registry, "unoptimized", &short, &lut, &options).frame(&cam);
    let got = live(&gpu, &registry, "bricks", &short, &lut, &options).frame(&cam);
    assert_same("rv_half", &got, &want, SAME);
}

/// Sort-last rendering simulated in one process (docs/scaling.md): the bricks split into N
/// slabs (ranks), each rank renders only its own, and the N images composited front to back in
/// the slabs' visibility order from the eye equal the single render. Each rank's image is an
/// f16 target: 1.5/255 covers N roundings of premultiplied colours ≤ 1 (2⁻¹¹ relative each).
#[test]
fn sort_last_compositing_of_brick_slabs_equals_the_single_render() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::vessels::vessel_tree(64, 2);
    let lut = TransferFunction::preset(Preset::Sparse, (0.0, 255.0)).to_lut_for(&volume, 256);
    let base = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0);
    let layout = volgraph_accel::bricks::BrickLayout::new(volume.dims, 16, 1).expect("layout");
    for azimuth in [20.0, 110.0, 250.0] {
        let cam = camera(azimuth, 2.4);
        let single = live(&gpu, &registry, "bricks_octree", &volume, &lut, &base).frame(&cam);
        let viewport = (SIZE, SIZE);
        let half = volgraph_core::runtime::VolumeDesc::of(&volume).half_extent;
        let eye = CameraData::from_orbit(&cam, viewport).eye / (2.0 * half) + glam::DVec3::splat(0.5);
        // Along x (the longest grid axis; ties go to x): the eye's voxel coordinate.
        let eye_voxel = eye.x * volume.dims.x as f64 - 0.5;
        for ranks in [2u32, 4] {
            // Each rank's slab as a voxel range along x, and its image.
            let mut slabs: Vec<(f64, Image)> = (0..ranks)
                .map(|rank| {
                    let xs: Vec<u32> = (0..layout.brick_count() as u32)
                        .filter(|b| volgraph_accel::brick_leaves::owns(&layout, *b, (rank, ranks)))
                        .map(|b| layout.brick_coord(b as usize).x)
                        .collect();
                    let lo = *xs.iter().min().expect("every rank owns bricks") as f64 * 16.0;
                    let hi = (*xs.iter().max().expect("bricks") as f64 + 1.0) * 16.0;
                    let distance = if eye_voxel < lo { lo - eye_voxel } else { (eye_voxel - hi).max(0.0) };
                    let options = base.clone().with_param("march", "ranks", ranks as u64).with_param(
                        "march",
                        "rank",
                        rank as u64,
                    );
                    (distance, live(&gpu, &registry, "bricks_octree", &volume, &lut, &options).frame(&cam))
                })
                .collect();
            // Visibility order: nearest slab first (a ray meets the slabs on its side of the eye
            // in this order and no others).
            slabs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut composite = vec![[0.0f64; 4]; (SIZE * SIZE) as usize];
            for (_, image) in &slabs {
                for (i, acc) in composite.iter_mut().enumerate() {
                    let c = image.rgba(i as u32 % SIZE, i as u32 / SIZE);
                    let transmittance = 1.0 - acc[3];
                    for ch in 0..4 {
                        acc[ch] += transmittance * c[ch] as f64;
                    }
                }
            }
            let (max, _) = diff_reference(&single, &composite);
            if max > 1.5 / 255.0 {
                save_images(&format!("rv_sort_last_{ranks}_az{azimuth}"), &single, &composite);
            }
            assert!(coverage(&single) > 0.02, "the volume is in view");
            assert!(max <= 1.5 / 255.0, "{ranks} ranks at {azimuth}°: max {:.3}/255", max * 255.0);
        }
    }
}

/// Issue 19: a frame's brick uploads went into one staging buffer, so a dense volume larger
/// than the device's largest buffer (1024³ u8 on lavapipe's ~1 GiB) failed with "'brick
/// uploads' label is invalid". Here the device's buffer limit is forced down to 256 KiB, below
/// the 96³ volume (864 KiB) and below one frame's uploads: the uploads are split by the limit
/// and the image equals the single-texture raycast on an ordinary device (same samples, so the
/// bricked graphs' 1/255 applies).
#[test]
fn a_volume_larger_than_the_largest_buffer_uploads_in_chunks() {
    let small = Arc::new(
        Gpu::new_headless_with(&volgraph_core::runtime::GpuOptions {
            max_buffer_size: Some(256 << 10),
            ..Default::default()
        })
        .expect("a Vulkan adapter"),
    );
    assert_eq!(small.limits.max_buffer_size, 256 << 10);
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(96);
    assert!(volume.dims.as_u64vec3().element_product() > small.limits.max_buffer_size);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 16.0);
    let cam = camera(30.0, 2.2);
    let mut bricked = live(&small, &registry, "bricks_octree", &volume, &lut, &options);
    let got = bricked.frame(&cam);
    let uploaded = bricked.counter("uploaded_bytes");
    assert!(uploaded > small.limits.max_buffer_size as f64, "one frame uploads {uploaded} bytes");
    let mut base = live(&gpu, &registry, "unoptimized", &volume, &lut, &options);
    assert!(coverage(&got) > 0.1, "the volume is in view");
    assert_same("rv_buffer_limit", &got, &base.frame(&cam), SAME);
}

/// Issue 19: a 1-voxel-thick slab was padded to full bricks on its thin axis (16 MiB of a
/// 4096² slice became 1175 MiB of bricks). Slots are now as thin as the volume: a 128×128×1
/// slab in bricks of 32 cells stores 35×35×4 voxels per brick (one layer plus the filter's
/// clamped neighbours), and renders like the single-texture raycast.
#[test]
fn a_thin_slab_is_bricked_thin() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (w, h) = (128u32, 128u32);
    let data: Vec<u8> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 - 64.0, (i / w) as f64 - 64.0);
            (255.0 * (-(x * x + y * y) / 900.0).exp()).round() as u8
        })
        .collect();
    let volume = Volume::new("slab".to_string(), glam::UVec3::new(w, h, 1), glam::DVec3::ONE, VoxelData::U8(data));
    let lut = TransferFunction::preset(Preset::Default, (0.0, 255.0)).to_lut_for(&volume, 256);
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 32.0);
    // Looking down onto the slab: every ray crosses its one layer.
    let cam = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 80.0, distance: 2.0, ..OrbitCamera::default() };
    let mut bricked = live(&gpu, &registry, "bricks", &volume, &lut, &options);
    let got = bricked.frame(&cam);
    let slot = 35.0 * 35.0 * 4.0 * volume_texture_format(&gpu, &volume).bytes() as f64;
    let (slots, pool) = (bricked.counter("pool_slots"), bricked.counter("pool_bytes"));
    assert_eq!(pool, slots * slot, "{slots} slots of 35×35×4 voxels");
    let mut base = live(&gpu, &registry, "unoptimized", &volume, &lut, &options);
    assert!(coverage(&got) > 0.05, "the slab is in view");
    assert_same("rv_thin_slab", &got, &base.frame(&cam), SAME);
}
