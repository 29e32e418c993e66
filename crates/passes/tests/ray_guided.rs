//! Ray-guided multiresolution streaming (`graphs/streaming/ray_guided.ron`, the
//! `raycast_stream` pass; Hadwiger et al. 2012, Crassin et al. 2009): a volume read as a pyramid
//! brick by brick. At rest, fully loaded, the image equals the single-texture raycast however
//! many levels the pyramid has; levels meet without seams; the first frame draws the coarsest
//! level without waiting, and later frames refine it; a pool too small for the view draws
//! coarser and says so. Failure images go to target/test-images.

use std::sync::Arc;

use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::{CropBox, Cuts};
use volgraph_accel::transfer_function::{ControlPoint, TransferFunction};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime};
use volgraph_core::{CompileOptions, Registry};
use volgraph_passes::builtin_registry;

mod support;

use support::{as_reference, coverage, diff_reference, save_images};

const SIZE: u32 = 96;
const GRAPH: &str = "streaming/ray_guided.ron";

fn tf_points(domain: (f64, f64), points: &[(f64, [f64; 3], f64)]) -> TransferFunction {
    let points = points.iter().map(|&(value, color, alpha)| ControlPoint { value, color, alpha }).collect();
    TransferFunction { domain, points }
}

fn camera(azimuth: f64) -> OrbitCamera {
    OrbitCamera { azimuth_deg: azimuth, elevation_deg: 25.0, distance: 2.4, ..OrbitCamera::default() }
}

/// A graph applied on its own runtime, with `cuts`.
fn runtime_for(
    gpu: &Arc<Gpu>,
    registry: &Registry,
    graph: &str,
    (volume, lut): (&Volume, &[[f32; 4]]),
    options: &CompileOptions,
    cuts: Cuts,
) -> (Runtime, (u32, u32)) {
    let mut runtime = support::runtime(gpu);
    runtime.set_cuts(cuts);
    let mut options = options.clone();
    options.features.extend(volgraph_core::cut_effects::features_of(&cuts));
    options.scene = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(volume));
    let plan = runtime
        .compile(graph, &support::graph_source(graph), registry, &options)
        .unwrap_or_else(|d| panic!("{graph}:\n{d}"));
    runtime.bind_scene(&plan.inputs, volume, lut).expect("binds");
    let viewport = plan.viewport;
    runtime.apply(plan, registry).unwrap_or_else(|e| panic!("{graph}: {e}"));
    (runtime, viewport)
}

fn counter(runtime: &Runtime, name: &str) -> f64 {
    let counters = runtime.pass_counters();
    counters.iter().find(|(_, n, _)| *n == name).unwrap_or_else(|| panic!("no counter {name}: {counters:?}")).2
}

/// Frames at `camera` until the rays lack nothing (the last frame read the feedback of the one
/// before, which asked for nothing, and nothing is being read); the image and the frames it took.
fn render_until_complete(runtime: &mut Runtime, viewport: (u32, u32), camera: &OrbitCamera) -> (Image, u32) {
    for frame in 1..=200 {
        runtime.render(CameraData::from_orbit(camera, viewport)).unwrap_or_else(|e| panic!("{e}"));
        let complete = counter(runtime, "feedback_read") == 1.0 && counter(runtime, "missing_bricks") == 0.0;
        if complete {
            return (runtime.read_output("image").expect("image"), frame);
        }
        runtime.wait_for_background(std::time::Duration::from_secs(10));
    }
    panic!("the stream never completed in 200 frames")
}

fn render_once(runtime: &mut Runtime, viewport: (u32, u32), camera: &OrbitCamera) -> Image {
    runtime.render(CameraData::from_orbit(camera, viewport)).unwrap_or_else(|e| panic!("{e}"));
    runtime.read_output("image").expect("image")
}

fn max_diff(name: &str, got: &Image, want: &Image) -> f64 {
    let want = as_reference(want);
    let (max, _) = diff_reference(got, &want);
    if max > 1.0 / 255.0 {
        save_images(name, got, &want);
    }
    max
}

/// An odd, anisotropic 16-bit volume: a ball of smooth values inside noise-free zeros.
fn odd_ball() -> Volume {
    let dims = UVec3::new(45, 37, 29);
    let mut data = Vec::with_capacity(dims.element_product() as usize);
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let p = (UVec3::new(x, y, z).as_dvec3() + 0.5) / dims.as_dvec3() - 0.5;
                data.push((60000.0 * (1.0 - (p.length() / 0.45)).clamp(0.0, 1.0)) as u16);
            }
        }
    }
    Volume::new("odd_ball", dims, DVec3::new(1.0, 1.3, 2.0), VoxelData::U16(data))
}

/// At rest and fully loaded every sample takes level 0, so the image is the single-texture
/// raycast's (same samples, same compositing) within 1/255 — the f16 colour target's rounding —
/// whether the pyramid has 2 or 5 levels (bricks of 16 down to 4 voxels: levels halve until one
/// brick holds the coarsest). The first frame, drawn from the coarsest level alone, differs.
#[test]
fn fully_loaded_at_rest_equals_the_single_texture_raycast() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let ml = volgraph_accel::generate::marschner_lobb(48);
    let ball = odd_ball();
    let ball_tf =
        tf_points((0.0, 65535.0), &[(0.0, [0.0; 3], 0.0), (20000.0, [1.0, 0.5, 0.2], 0.1), (65535.0, [1.0; 3], 0.6)]);
    let cases =
        [(TransferFunction::default_for(&ml).to_lut_for(&ml, 256), &ml), (ball_tf.to_lut_for(&ball, 256), &ball)];
    for (lut, volume) in cases {
        let base = CompileOptions::new(SIZE, SIZE);
        let (mut single, viewport) =
            runtime_for(&gpu, &registry, "ruijters_vilanova_2006/unoptimized.ron", (volume, &lut), &base, Cuts::NONE);
        for brick in [4.0, 8.0, 16.0] {
            // lod 0.5: a level-1 voxel would be wider than half a pixel everywhere, so every
            // sample takes level 0.
            let options =
                CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", brick).with_param("march", "lod", 0.5);
            let (mut stream, _) = runtime_for(&gpu, &registry, GRAPH, (volume, &lut), &options, Cuts::NONE);
            for az in [30.0, 200.0] {
                let want = render_once(&mut single, viewport, &camera(az));
                assert!(coverage(&want) > 0.05, "{}: the volume is in view", volume.name);
                let (got, frames) = render_until_complete(&mut stream, viewport, &camera(az));
                let name = format!("stream_{}_b{brick}_az{az}", volume.name);
                let max = max_diff(&name, &got, &want);
                eprintln!("{name}: {frames} frames to the full image, max {:.2}/255", max * 255.0);
                assert!(max <= 1.0 / 255.0, "{name}: max {:.2}/255 against the single-texture raycast", max * 255.0);
            }
        }
    }
}

/// The first frame waits for no brick: it draws the coarsest level (read first, pinned) and asks
/// for nothing yet; the next frames ask for what the rays lacked, coarse before fine, and refine.
/// Brick 4 on 48³ gives 5 levels.
#[test]
fn the_first_frame_draws_the_coarsest_level_and_later_frames_refine_it() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(48);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 4.0).with_param("march", "lod", 0.5);
    let (mut stream, viewport) = runtime_for(&gpu, &registry, GRAPH, (&volume, &lut), &options, Cuts::NONE);
    let first = render_once(&mut stream, viewport, &camera(30.0));
    assert_eq!(counter(&stream, "levels"), 5.0, "48 → 24 → 12 → 6 → 3 voxels per side");
    assert_eq!(counter(&stream, "read_bricks"), 1.0, "only the coarsest level's one brick");
    assert_eq!(counter(&stream, "feedback_read"), 0.0);
    assert!(coverage(&first) > 0.05, "the coarsest level is drawn at once");
    render_once(&mut stream, viewport, &camera(30.0));
    assert!(counter(&stream, "requested_bricks") > 0.0, "the second frame asks for what the first lacked");
    let (full, _) = render_until_complete(&mut stream, viewport, &camera(30.0));
    let differs = max_diff("stream_first_vs_full", &first, &full);
    assert!(differs > 8.0 / 255.0, "the coarse first frame is not the full image ({:.1}/255)", differs * 255.0);
    assert!(counter(&stream, "resident_bricks") > 1.0);
}

/// A field linear in x has the same trilinear reconstruction at every level (each coarse voxel
/// is the mean of the fine ones, which a linear field takes at the coarse centre), so an image
/// drawn from any mix of levels equals the level-0 image — except where clamp-to-edge differs
/// per level, within half a coarse voxel of the x faces, which the crop removes. The opacity is
/// the same everywhere (a constant alpha), and a coarse sample stands at the centre of the grid
/// samples it replaces: what remains is rounding, 1.5/255. A seam — an apron or
/// offset wrong by one voxel — moves a brick's values by the field's slope over a voxel (4/255
/// here) over the brick's whole footprint: hundreds of pixels.
#[test]
fn levels_meet_without_seams() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let n = 64u32;
    let data: Vec<f32> = (0..n * n * n).map(|i| (i % n) as f32 / (n - 1) as f32).collect();
    let volume = Volume::new("ramp_x", UVec3::splat(n), DVec3::ONE, VoxelData::F32(data));
    let tf = tf_points((0.0, 1.0), &[(0.0, [0.0, 0.0, 0.0], 0.03), (1.0, [1.0, 1.0, 1.0], 0.03)]);
    let lut = tf.to_lut_for(&volume, 256);
    let crop = CropBox::new(DVec3::new(0.15, 0.0, 0.0), DVec3::new(0.85, 1.0, 1.0)).expect("box");
    let cuts = Cuts::new(Some(crop), &[]).expect("cuts");
    let fine = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 8.0).with_param("march", "lod", 0.125);
    let (mut level0, viewport) = runtime_for(&gpu, &registry, GRAPH, (&volume, &lut), &fine, cuts);
    let cam = camera(35.0);
    let (want, _) = render_until_complete(&mut level0, viewport, &cam);
    assert!(coverage(&want) > 0.2);
    for lod in [2.0, 4.0, 16.0] {
        // lod 2 and 4 mix levels by distance; 16 draws the coarsest alone.
        let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 8.0).with_param("march", "lod", lod);
        let (mut mixed, _) = runtime_for(&gpu, &registry, GRAPH, (&volume, &lut), &options, cuts);
        let (got, _) = render_until_complete(&mut mixed, viewport, &cam);
        let resident = counter(&mixed, "resident_bricks");
        let name = format!("stream_seams_lod{lod}");
        let max = max_diff(&name, &got, &want);
        let reference = as_reference(&want);
        let over = (0..got.height)
            .flat_map(|y| (0..got.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let w = reference[(y * got.width + x) as usize];
                got.rgba(x, y).iter().zip(w).any(|(g, w)| (f64::from(*g) - w).abs() > 1.5 / 255.0)
            })
            .count();
        eprintln!(
            "{name}: levels drawn {:#b}, {resident} bricks resident, max {:.2}/255 against level 0, {over} pixels over 1.5/255",
            counter(&mixed, "drawn_levels") as u32,
            max * 255.0
        );
        assert!(max <= 1.5 / 255.0 && over == 0, "{name}: max {:.2}/255, {over} pixels over 1.5/255", max * 255.0);
        let drawn = counter(&mixed, "drawn_levels") as u32;
        assert!(drawn & !1 != 0, "{name}: levels drawn (bits) {drawn:#b}: coarser levels, not level 0 alone");
        assert!(lod > 4.0 || drawn.count_ones() >= 2, "{name}: levels drawn (bits) {drawn:#b}: a mix");
    }
}

/// A pool smaller than what the view needs at full resolution never evicts what the last frame
/// drew: the bricks that find no slot are counted, drawn from a coarser level, and the stream
/// still completes (it asks for them again only when the view changes).
#[test]
fn a_pool_too_small_draws_coarser_and_counts_the_refused_bricks() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(128);
    let lut = TransferFunction::default_for(&volume).to_lut_for(&volume, 256);
    // 1 MiB of 10³-voxel slots: 1048, fewer than the 4096 level-0 bricks in view.
    let options = CompileOptions::new(64, 64)
        .with_scalar("brick_cells", 8.0)
        .with_param("march", "lod", 0.5)
        .with_param("march", "pool_mb", 1.0);
    let (mut stream, viewport) = runtime_for(&gpu, &registry, GRAPH, (&volume, &lut), &options, Cuts::NONE);
    let (image, _) = render_until_complete(&mut stream, viewport, &camera(30.0));
    assert!(counter(&stream, "refused_bricks") > 0.0);
    assert!(counter(&stream, "resident_bricks") <= counter(&stream, "pool_slots"));
    assert!(coverage(&image) > 0.2, "what found no slot is drawn coarser, not left out");
}

/// The ray's grid counts level-0 steps however coarse the levels it draws from: a ray through
/// 2400 voxels at half a voxel a step takes 4800 grid steps, more than `max_steps`' default
/// 4096, and must still reach the volume's far end (the pass raises the bound to the longest
/// ray's steps). A 64×64×2400 column seen end-on from just outside its near face, whose only
/// content is a slab at the far end.
#[test]
fn a_ray_longer_than_max_steps_reaches_the_far_end() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let dims = UVec3::new(64, 64, 2400);
    let data: Vec<u8> = (0..dims.element_product()).map(|i| if i / (dims.x * dims.y) < 40 { 200 } else { 0 }).collect();
    let volume = Volume::new("column", dims, DVec3::ONE, VoxelData::U8(data));
    // Exactly transparent below 50 (the LUT's first texels too), so 2400 voxels of zeros add nothing.
    let tf = tf_points(
        (0.0, 255.0),
        &[(0.0, [0.0; 3], 0.0), (50.0, [0.0; 3], 0.0), (100.0, [1.0; 3], 0.5), (255.0, [1.0; 3], 0.5)],
    );
    let lut = tf.to_lut_for(&volume, 256);
    let options = CompileOptions::new(32, 32).with_param("march", "lod", 0.125);
    let (mut stream, viewport) = runtime_for(&gpu, &registry, GRAPH, (&volume, &lut), &options, Cuts::NONE);
    // Azimuth 0: the eye on +z, looking down the column toward z = 0, where the slab is.
    let end_on = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 1.05, ..OrbitCamera::default() };
    let (image, _) = render_until_complete(&mut stream, viewport, &end_on);
    let centre = image.rgba(16, 16);
    assert!(centre[3] > 0.4, "the far slab is seen through 2400 voxels: {centre:?}");
}

/// A transfer-function change re-classifies what is known: bricks and sub-blocks empty under the
/// old function are drawn under the new one and resident bricks stay — the image equals a fresh
/// stream's under the new function (within 1/255: bricks land in other slots). Bricks of 32, so
/// a sub-block is 4 voxels: resident sub-blocks left marked empty fail it (tried by hand).
#[test]
fn a_tf_change_reclassifies_bricks_and_sub_blocks() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let volume = volgraph_accel::generate::marschner_lobb(48);
    // A band of high values only, then a band that shows low values the first one left empty.
    let high = tf_points((0.0, 255.0), &[(0.0, [0.0; 3], 0.0), (180.0, [0.0; 3], 0.0), (230.0, [1.0, 0.6, 0.2], 0.6)])
        .to_lut_for(&volume, 256);
    let low = tf_points((0.0, 255.0), &[(0.0, [0.0; 3], 0.0), (40.0, [0.2, 0.6, 1.0], 0.3), (90.0, [0.0; 3], 0.0)])
        .to_lut_for(&volume, 256);
    let options = CompileOptions::new(SIZE, SIZE).with_scalar("brick_cells", 32.0).with_param("march", "lod", 0.5);
    let cam = camera(30.0);
    let (mut changed, viewport) = runtime_for(&gpu, &registry, GRAPH, (&volume, &high), &options, Cuts::NONE);
    let (first, _) = render_until_complete(&mut changed, viewport, &cam);
    let empty_before = counter(&changed, "empty_bricks");
    changed.bind_lut("tf", &low).expect("binds");
    let (got, _) = render_until_complete(&mut changed, viewport, &cam);
    let (mut fresh, _) = runtime_for(&gpu, &registry, GRAPH, (&volume, &low), &options, Cuts::NONE);
    let (want, _) = render_until_complete(&mut fresh, viewport, &cam);
    assert!(max_diff("stream_tf_before_after", &first, &want) > 8.0 / 255.0, "the two functions show different things");
    let max = max_diff("stream_tf_change", &got, &want);
    assert!(max <= 1.0 / 255.0, "after the change: max {:.2}/255 against a fresh stream", max * 255.0);
    assert!(empty_before > 0.0, "the first function left bricks empty: {empty_before}");
}
