//! Krüger & Westermann 2003 and the compute-shader thesis as graphs, checked on the GPU
//! (lavapipe in CI) against each other and against the f64 CPU reference.
//!
//! Tolerances, per channel of premultiplied linear RGBA:
//! - Lossless accelerations (segments vs the single pass, empty-space skipping, empty-block
//!   leaping, isosurface segments): max abs ≤ 1/255 against the unaccelerated GPU graph. Both
//!   take the same samples through the same hardware filter; only f32 rounding differs (the
//!   segment blend re-associates the compositing sum; the termination pass's f32 box exits).
//! - Against the f64 reference: max abs ≤ 2/255, mean ≤ 0.5/255, the bounds of
//!   `gpu_vs_reference.rs` for the single-pass raycaster, with the same reasons (f32 vs f64
//!   over ~250 samples; rasterized vs analytic entry/exit at grazing pixels).
//! - Early ray termination at alpha ≥ T: stopping drops at most what the rest of the ray would
//!   add, `(1 - A) ≤ (1 - T)` per channel (colours are premultiplied and ≤ 1), so the bound is
//!   `(1 - T) + 1/255`.
//! - SBVR: see `sbvr_approximates_the_reference`.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::minmax::MinMaxGrid;
use volgraph_accel::reference::{corrected_alpha, lut_sample, ray_segment, render_reference, step_tex};
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{Gpu, Image, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, Plan, Registry, compile};
use volgraph_passes::builtin_registry;
use volgraph_passes::empty_space::EmptySpace;
use volgraph_passes::grid_tap::GridTap;
use volgraph_passes::minmax_grid::MinMaxGridPass;
use volgraph_passes::raycast_params::reference_settings;
use volgraph_passes::raycast_segment::{InvocationCounter, RaycastSegment};

mod support;

use support::{as_reference, diff_reference, gpu, graph_source, render_once, save_images};

const SIZE: u32 = 96;
const STEP_VOXELS: f64 = 0.5;
/// One 8-bit display level: the bound for lossless accelerations.
const LOSSLESS: f64 = 1.0 / 255.0;

/// Options for `volume`: the viewport and the scene values the runtime gives graphs (the longest
/// ray in voxels, which the segment loop's count divides by step and M).
fn options(volume: &Volume) -> CompileOptions {
    let mut options = CompileOptions::new(SIZE, SIZE);
    options.scene = scene_values_of(&VolumeDesc::of(volume));
    options
}

/// K of Krüger & Westermann 2003 §3: steps of `step_voxels` along the longest ray.
fn longest_ray_steps(volume: &Volume, step_voxels: f64) -> f64 {
    VolumeDesc::of(volume).longest_ray_voxels() / step_voxels
}

struct Rendered {
    image: Image,
    /// The `hit` output, for graphs that have one.
    hit: Option<Image>,
    plan: Plan,
}

fn render_with(
    gpu: &std::sync::Arc<Gpu>,
    registry: &Registry,
    graph: &str,
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    options: &CompileOptions,
) -> Rendered {
    let plan =
        compile(graph, &graph_source(graph), registry, options).unwrap_or_else(|d| panic!("{graph} compiles:\n{d}"));
    let (mut runtime, _) = render_once(gpu, registry, graph, &graph_source(graph), options, volume, lut, camera)
        .unwrap_or_else(|e| panic!("{graph}: {e}"));
    let image = runtime.read_output("image").unwrap_or_else(|e| panic!("{graph}: {e}"));
    let hit =
        plan.outputs.contains_key("hit").then(|| runtime.read_output("hit").unwrap_or_else(|e| panic!("{graph}: {e}")));
    Rendered { image, hit, plan }
}

fn render(
    gpu: &std::sync::Arc<Gpu>,
    graph: &str,
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    options: &CompileOptions,
) -> Rendered {
    render_with(gpu, &builtin_registry(), graph, volume, lut, camera, options)
}

/// (max abs, mean abs) per channel between two GPU images; NaN counts as infinite.
fn diff_images(a: &Image, b: &Image) -> (f64, f64) {
    diff_reference(a, &as_reference(b))
}

/// Fraction of pixels with non-zero alpha (a comparison of empty images proves nothing).
fn coverage(image: &Image) -> f64 {
    let mut n = 0;
    for y in 0..image.height {
        for x in 0..image.width {
            if image.rgba(x, y)[3] > 0.0 {
                n += 1;
            }
        }
    }
    n as f64 / (image.width * image.height) as f64
}

/// Checks `rendered` against the reference for its "march" pass's settings (overridden by
/// `threshold` when given), with the single-pass raycaster's bounds plus `extra`.
fn assert_matches_reference(
    name: &str,
    rendered: &Rendered,
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    extra: f64,
) {
    let march = rendered.plan.steps.iter().find(|s| s.pass_id == "march").expect("a march step");
    let settings = reference_settings(&march.params);
    let reference = render_reference(volume, lut, camera, SIZE, SIZE, &settings);
    let (max_abs, mean_abs) = diff_reference(&rendered.image, &reference.color);
    save_images(&format!("kw_{name}"), &rendered.image, &reference.color);
    eprintln!("{name} vs reference: max {:.3}/255 mean {:.4}/255", max_abs * 255.0, mean_abs * 255.0);
    assert!(max_abs <= 2.0 / 255.0 + extra, "{name}: max abs {:.3}/255 vs the reference", max_abs * 255.0);
    assert!(mean_abs <= 0.5 / 255.0 + extra, "{name}: mean abs {:.4}/255 vs the reference", mean_abs * 255.0);
}

fn assert_close(name: &str, a: &Rendered, b: &Rendered, bound: f64) {
    let (max_abs, mean_abs) = diff_images(&a.image, &b.image);
    let cov = coverage(&b.image);
    eprintln!(
        "{name}: max {:.3}/255 mean {:.4}/255 (bound {:.2}/255), coverage {cov:.2}",
        max_abs * 255.0,
        mean_abs * 255.0,
        bound * 255.0
    );
    assert!(cov > 0.05, "{name}: the image is nearly empty ({cov:.2}); pick a visible camera/TF");
    assert!(max_abs <= bound, "{name}: max abs {:.3}/255 > {:.3}/255", max_abs * 255.0, bound * 255.0);
}

const CAMERA: OrbitCamera = OrbitCamera {
    azimuth_deg: 30.0,
    elevation_deg: 20.0,
    distance: 3.2,
    fov_y_deg: 30.0,
    near: 0.01,
    far: 100.0,
    target: [0.0; 3],
    up: volgraph_accel::camera::CameraUp::Y,
};

fn ml() -> Volume {
    volgraph_accel::generate::marschner_lobb(64)
}

fn lut(volume: &Volume, preset: Preset) -> Vec<[f32; 4]> {
    let (lo, hi) = volume.value_range;
    TransferFunction::preset(preset, (lo, hi)).to_lut_for(volume, 256)
}

/// A solid sphere, binary 0/255: everything outside it is empty space.
fn sphere() -> Volume {
    volgraph_accel::generate::sphere(64, 0.6)
}

/// The real 128³ hydrogen atom where the data folder has it (mostly empty space).
fn hydrogen() -> Option<Volume> {
    volgraph_accel::data_dir::require_dataset("hydrogen_atom")?;
    Some(volgraph_accel::data_dir::load_dataset("hydrogen_atom").expect("hydrogen_atom loads").volume)
}

/// Options that make termination lossless for `graph`: T = 1 on its raycaster and, where it
/// has one, its termination test.
fn lossless(options: CompileOptions, graph: &str) -> CompileOptions {
    let options = options.with_param("march", "threshold", 1.0);
    if graph_source(graph).contains("id: \"terminate\"") {
        options.with_param("terminate", "threshold", 1.0)
    } else {
        options
    }
}

#[test]
fn rc_segments_equal_the_single_pass_raycast_and_the_reference() {
    let gpu = gpu();
    let v = ml();
    let l = lut(&v, Preset::Default);
    let opts = options(&v);
    let single = render(&gpu, "basic/fragment_raycast.ron", &v, &l, &CAMERA, &opts);
    let rc = render(&gpu, "kruger_westermann_2003/rc.ron", &v, &l, &CAMERA, &opts);
    let segments = rc.plan.steps.iter().filter(|s| s.pass_id == "march").count();
    assert_eq!(segments as f64, (longest_ray_steps(&v, STEP_VOXELS) / 8.0).ceil(), "one segment per M = 8 steps of K");
    assert_close("rc vs single pass", &rc, &single, LOSSLESS);
    assert_matches_reference("rc", &rc, &v, &l, &CAMERA, 0.0);
}

#[test]
fn rc_a_with_lossless_threshold_equals_rc_and_stays_within_the_termination_bound() {
    let gpu = gpu();
    let v = ml();
    for preset in [Preset::Default, Preset::Opaque] {
        let l = lut(&v, preset);
        let opts = options(&v);
        let rc = render(&gpu, "kruger_westermann_2003/rc.ron", &v, &l, &CAMERA, &opts);
        // T = 1: only rays that left the volume (or are fully opaque) stop — lossless.
        let exact = render(
            &gpu,
            "kruger_westermann_2003/rc_a.ron",
            &v,
            &l,
            &CAMERA,
            &lossless(opts.clone(), "kruger_westermann_2003/rc_a.ron"),
        );
        assert_close(&format!("rc_a(T=1) vs rc, {}", preset.name()), &exact, &rc, LOSSLESS);
        let rc_a = render(&gpu, "kruger_westermann_2003/rc_a.ron", &v, &l, &CAMERA, &opts);
        let t = rc_a.plan.steps.iter().find(|s| s.pass_id == "terminate").expect("terminate").params.float("threshold");
        assert!(t < 1.0, "the graph's default T terminates early");
        assert_close(&format!("rc_a(T={t}) vs rc, {}", preset.name()), &rc_a, &rc, (1.0 - t) + LOSSLESS);
        if preset == Preset::Default {
            // The opaque TF's step from 0 to 1 makes 8-bit filtering differences visible in the
            // single pass as well (as for isosurfaces in gpu_vs_reference.rs); rc_a is held to
            // rc above.
            assert_matches_reference(&format!("rc_a {}", preset.name()), &exact, &v, &l, &CAMERA, 0.0);
        }
    }
}

#[test]
fn rc_b_empty_space_skipping_is_lossless() {
    let gpu = gpu();
    let mut cases = vec![("sphere", sphere(), Preset::Default), ("ML sparse", ml(), Preset::Sparse)];
    if let Some(h) = hydrogen() {
        cases.push(("hydrogen", h, Preset::Default));
    }
    // The paper's form (empty segments rejected by the depth test) and the leaping form (the
    // segment leaps over empty blocks itself) must both leave the image unchanged.
    for graph in ["kruger_westermann_2003/rc_b.ron", "kruger_westermann_2003/rc_b_leap.ron"] {
        for (name, v, preset) in &cases {
            let l = lut(v, *preset);
            let opts = options(v);
            let rc = render(&gpu, "kruger_westermann_2003/rc.ron", v, &l, &CAMERA, &opts);
            let rc_b = render(&gpu, graph, v, &l, &CAMERA, &lossless(opts.clone(), graph));
            assert_close(&format!("{graph}(T=1) vs rc, {name}"), &rc_b, &rc, LOSSLESS);
            if *preset == Preset::Default {
                // The sparse TF's steep ramp on 8-bit data exceeds the reference bound for the
                // single-pass raycaster too (8-bit filter weights, see gpu_vs_reference.rs); rc_b is
                // held to rc above, which is what skipping must preserve.
                assert_matches_reference(&format!("{graph} {name}"), &rc_b, v, &l, &CAMERA, 0.0);
            }
            let rc_b_t = render(&gpu, graph, v, &l, &CAMERA, &opts);
            assert_close(&format!("{graph}(T=0.95) vs rc, {name}"), &rc_b_t, &rc, 0.05 + LOSSLESS);
        }
    }
}

#[test]
fn single_pass_empty_block_leaping_equals_the_plain_raycast() {
    let gpu = gpu();
    let mut cases =
        vec![("sphere", sphere(), Preset::Default), ("ML", ml(), Preset::Default), ("ML sparse", ml(), Preset::Sparse)];
    if let Some(h) = hydrogen() {
        cases.push(("hydrogen", h, Preset::Default));
    }
    for (name, v, preset) in cases {
        let l = lut(&v, preset);
        let opts = options(&v);
        let plain = render(&gpu, "basic/fragment_raycast.ron", &v, &l, &CAMERA, &opts);
        let leaping = render(
            &gpu,
            "modern/single_pass_ess_ert.ron",
            &v,
            &l,
            &CAMERA,
            &opts.clone().with_param("march", "threshold", 1.0),
        );
        assert_close(&format!("leaping(T=1) vs raycast, {name}"), &leaping, &plain, LOSSLESS);
        let ert = render(&gpu, "modern/single_pass_ess_ert.ron", &v, &l, &CAMERA, &opts);
        let t = ert.plan.steps.iter().find(|s| s.pass_id == "march").expect("march").params.float("threshold");
        assert_close(&format!("leaping(T={t}) vs raycast, {name}"), &ert, &plain, (1.0 - t) + LOSSLESS);
    }
}

#[test]
fn gpu_minmax_grid_and_empty_flags_equal_the_cpu_ones() {
    let gpu = gpu();
    // 64³ (blocks divide it), 37³ (ragged last block), f32 data, and the real data if present.
    let mut cases = vec![
        ("ML 64", ml(), 8u32),
        ("ML 37", volgraph_accel::generate::marschner_lobb(37), 8),
        ("ML f32 40, blocks of 6", volgraph_accel::generate::marschner_lobb_f32(40), 6),
    ];
    if let Some(h) = hydrogen() {
        cases.push(("hydrogen", h, 8));
    }
    for (name, v, block) in cases {
        for preset in [Preset::Default, Preset::Sparse] {
            let l = lut(&v, preset);
            let grid_tap = GridTap::new();
            let flags_tap = GridTap::new();
            let mut registry = builtin_registry();
            registry.register(MinMaxGridPass::tapped(grid_tap.clone())).register(EmptySpace::tapped(flags_tap.clone()));
            let opts = options(&v).with_param("minmax", "block_size", block).with_param("march", "block_size", block);
            render_with(&gpu, &registry, "modern/single_pass_ess_ert.ron", &v, &l, &CAMERA, &opts);
            let cpu = MinMaxGrid::build(&v, block).expect("CPU grid");
            let (dims, gpu_grid) = grid_tap.read_f32(&gpu, 2).expect("GPU grid");
            assert_eq!(dims, cpu.dims().to_array(), "{name}: grid dims");
            // The CPU rounds each exact f64 normalized value outward to f32 (1 ulp), and the
            // GPU's unorm → float conversion is v·(1/255) in f32 on lavapipe, not correctly
            // rounded (1 more ulp). Either way the GPU grid bounds exactly the texel values its
            // own sampler interpolates, and the flags below must still agree exactly.
            let mut worst_ulps = 0;
            for (i, cpu_range) in cpu.ranges().iter().enumerate() {
                for c in 0..2 {
                    let g = gpu_grid[2 * i + c];
                    let ulps = (g.to_bits() as i64 - cpu_range[c].to_bits() as i64).abs();
                    worst_ulps = worst_ulps.max(ulps);
                }
            }
            assert!(worst_ulps <= 2, "{name}: GPU min/max differs from the CPU grid by {worst_ulps} ulps");
            let classifier = OpacityClassifier::new(&l).expect("LUT");
            let cpu_flags = classifier.empty_flags(&cpu);
            let (_, gpu_flags) = flags_tap.read_f32(&gpu, 1).expect("GPU flags");
            let mismatches = cpu_flags.iter().zip(&gpu_flags).filter(|(c, g)| (**c != 0) != (**g > 0.5)).count();
            let empty = cpu_flags.iter().filter(|c| **c != 0).count();
            eprintln!(
                "{name}/{}: {} blocks, {empty} empty on the CPU, {mismatches} flags differ",
                preset.name(),
                cpu_flags.len()
            );
            assert_eq!(mismatches, 0, "{name}/{}: GPU empty flags differ from the CPU classification", preset.name());
        }
    }
}

/// Segments of pixel `(x, y)` that the early depth test lets through with termination at `t`:
/// segment 0 always (the depth buffer starts "live"), segment i ≥ 1 while the alpha after i·M
/// samples is below `t` and the ray has a sample at i·M (`docs/rendering_model.md` samples).
#[allow(clippy::too_many_arguments, reason = "a test helper mirroring the shader's inputs one to one")]
fn live_segments(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    x: u32,
    y: u32,
    m: u32,
    segments: u32,
    t: f64,
) -> u32 {
    let frame = camera.frame(SIZE, SIZE);
    let Some(seg) = ray_segment(volume, camera, &frame, x, y) else { return 1 };
    let step = step_tex(volume, seg.d_tex, STEP_VOXELS);
    let samples = ((seg.len_tex / step) - 0.5).ceil().max(0.0) as u32;
    let mut alpha = 0.0;
    let mut live = 1;
    for i in 1..segments {
        for k in (i - 1) * m..(i * m).min(samples) {
            let s = volume.sample_trilinear(seg.u0 + (k as f64 + 0.5) * step * seg.d_tex);
            alpha += (1.0 - alpha) * corrected_alpha(lut_sample(lut, s)[3], STEP_VOXELS);
        }
        if alpha >= t || i * m >= samples {
            break;
        }
        live += 1;
    }
    live
}

#[test]
fn early_z_rejects_terminated_fragments_before_the_segment_shader_runs() {
    let gpu = gpu();
    if !gpu.early_depth_test {
        // Forcing early tests for a shader with side effects is Vulkan-only; the project's CI
        // runs lavapipe (Vulkan), where this always holds.
        panic!("{}: no SHADER_EARLY_DEPTH_TEST; run on Vulkan (lavapipe)", gpu.adapter_name);
    }
    let v = ml();
    let l = lut(&v, Preset::Opaque);
    let opts = options(&v);
    let counter = InvocationCounter::new();
    let mut registry = builtin_registry();
    registry.register(RaycastSegment::counting(counter.clone()));

    let rc = render_with(&gpu, &registry, "kruger_westermann_2003/rc.ron", &v, &l, &CAMERA, &opts);
    let segments = rc.plan.steps.iter().filter(|s| s.pass_id == "march").count() as u64;
    let without = counter.read(&gpu).expect("counter") as u64;
    // Segments draw the volume's screen footprint grown by a pixel (`draw_footprint`'s fan):
    // every pixel whose ray meets the box, and none further than two pixels from one.
    let frame = CAMERA.frame(SIZE, SIZE);
    let has_ray: Vec<bool> =
        (0..SIZE * SIZE).map(|i| ray_segment(&v, &CAMERA, &frame, i % SIZE, i / SIZE).is_some()).collect();
    let near_a_ray = |x: u32, y: u32| {
        let (x0, x1, y0, y1) = (x.saturating_sub(2), (x + 2).min(SIZE - 1), y.saturating_sub(2), (y + 2).min(SIZE - 1));
        (y0..=y1).any(|yy| (x0..=x1).any(|xx| has_ray[(yy * SIZE + xx) as usize]))
    };
    let rays = has_ray.iter().filter(|&&r| r).count() as u64;
    let near = (0..SIZE * SIZE).filter(|i| near_a_ray(i % SIZE, i / SIZE)).count() as u64;
    assert_eq!(without % segments, 0, "without the termination test every fragment drawn runs in every segment");
    let drawn = without / segments;
    assert!(
        (rays..=near).contains(&drawn) && near < (SIZE * SIZE) as u64,
        "{drawn} pixels drawn per segment: every one of the {rays} with a ray, none beyond the {near} near one"
    );

    let rc_a = render_with(&gpu, &registry, "kruger_westermann_2003/rc_a.ron", &v, &l, &CAMERA, &opts);
    let with = counter.read(&gpu).expect("counter") as u64;
    let t = rc_a.plan.steps.iter().find(|s| s.pass_id == "terminate").expect("terminate").params.float("threshold");
    let m = rc_a.plan.steps.iter().find(|s| s.pass_id == "terminate").expect("terminate").params.uint("segment_steps")
        as u32;
    // The drawn pixels without a ray run segment 0 only (the test then finds no sample left).
    let expected: u64 = (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
        .filter(|&(x, y)| has_ray[(y * SIZE + x) as usize])
        .map(|(x, y)| live_segments(&v, &l, &CAMERA, x, y, m, segments as u32, t) as u64)
        .sum::<u64>()
        + (drawn - rays);
    eprintln!(
        "segment fragments: {without} without termination, {with} with (expected {expected}), {segments} segments"
    );
    assert!(with * 5 < without, "termination should reject most fragments: {with} of {without} ran");
    // Within reason: pixels whose alpha lands within f32 rounding of T, or rays that graze an
    // edge (rasterized vs analytic entry), can run one segment more or less; 2% covers them.
    let slack = expected / 50;
    assert!(with.abs_diff(expected) <= slack, "{with} segment fragments ran, expected {expected} ± {slack}");
}

#[test]
fn iso_segments_equal_the_single_pass_isosurface() {
    let gpu = gpu();
    let mlf = volgraph_accel::generate::marschner_lobb_f32(64);
    for (name, v) in [("ML", ml()), ("ML f32", mlf)] {
        let l = lut(&v, Preset::Default);
        let opts = options(&v);
        let single = render(&gpu, "basic/isosurface.ron", &v, &l, &CAMERA, &opts);
        let segments = render(&gpu, "kruger_westermann_2003/iso.ron", &v, &l, &CAMERA, &opts);
        // Same samples, same refinement (sample k-1 is fetched again at a segment start), same
        // shading: equal up to rounding.
        assert_close(&format!("iso segments vs single pass, {name}"), &segments, &single, LOSSLESS);
        // The hit target blends like the colour, so the segments keep the same first hit; both
        // sides compute it with the same f32 expressions, so 1e-5 (≈ 1/1500 voxel at 64³) only
        // allows for the blend unit's rounding of a value it multiplies by exactly 1.
        let (a, b) = (segments.hit.as_ref().expect("iso.ron has a hit output"), single.hit.as_ref().expect("hit"));
        let (max, _) = diff_images(a, b);
        assert!(max <= 1e-5, "iso segments hit positions differ from the single pass by {max} (texture units)");
    }
}

#[test]
fn camera_inside_the_volume_with_multipass_segments() {
    let gpu = gpu();
    let v = sphere();
    let l = lut(&v, Preset::Default);
    // Inside the box, looking at the sphere from its edge: rays start at the near plane.
    let camera = OrbitCamera {
        azimuth_deg: 20.0,
        elevation_deg: 10.0,
        distance: 0.45,
        fov_y_deg: 60.0,
        near: 0.01,
        far: 100.0,
        target: [0.0; 3],
        up: volgraph_accel::camera::CameraUp::Y,
    };
    let opts = options(&v);
    for graph in ["kruger_westermann_2003/rc.ron", "kruger_westermann_2003/rc_b.ron"] {
        let r = render(&gpu, graph, &v, &l, &camera, &lossless(opts.clone(), graph));
        assert!(coverage(&r.image) > 0.05, "{graph}: nothing visible from inside");
        assert_matches_reference(&format!("inside {graph}"), &r, &v, &l, &camera, 0.0);
    }
}

#[test]
fn axis_aligned_view_with_multipass_segments() {
    let gpu = gpu();
    let v = ml();
    let l = lut(&v, Preset::Default);
    // Rays parallel to the z axis through the centre column: zero direction components.
    let camera = OrbitCamera {
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        distance: 3.2,
        fov_y_deg: 30.0,
        near: 0.01,
        far: 100.0,
        target: [0.0; 3],
        up: volgraph_accel::camera::CameraUp::Y,
    };
    let opts = options(&v);
    for graph in ["kruger_westermann_2003/rc.ron", "kruger_westermann_2003/rc_b.ron", "modern/single_pass_ess_ert.ron"]
    {
        let r = render(&gpu, graph, &v, &l, &camera, &lossless(opts.clone(), graph));
        assert_matches_reference(&format!("axis-aligned {graph}"), &r, &v, &l, &camera, 0.0);
    }
}

#[test]
fn sbvr_approximates_the_reference() {
    let gpu = gpu();
    let v = ml();
    let l = lut(&v, Preset::Default);
    let sbvr = render(&gpu, "kruger_westermann_2003/sbvr.ron", &v, &l, &CAMERA, &CompileOptions::new(SIZE, SIZE));
    let slices = sbvr.plan.steps.iter().find(|s| s.pass_id == "slices").expect("slices");
    let settings = volgraph_accel::reference::RaycastSettings {
        step_voxels: slices.params.float("slice_voxels"),
        threshold: 1.0,
        max_steps: 1 << 16,
        jitter: false,
        mode: volgraph_accel::reference::RenderMode::Dvr,
        ..Default::default()
    };
    let reference = render_reference(&v, &l, &CAMERA, SIZE, SIZE, &settings);
    let (max_abs, mean_abs) = diff_reference(&sbvr.image, &reference.color);
    save_images("kw_sbvr", &sbvr.image, &reference.color);
    let cov = coverage(&sbvr.image);
    eprintln!("sbvr vs reference: max {:.3}/255 mean {:.4}/255 coverage {cov:.2}", max_abs * 255.0, mean_abs * 255.0);
    assert!(cov > 0.05, "sbvr: nearly empty image");
    let over = |level: f64| {
        let mut n = 0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                let g = sbvr.image.rgba(x, y);
                let r = reference.color[(y * SIZE + x) as usize];
                if (0..4).any(|c| (g[c] as f64 - r[c]).abs() > level / 255.0) {
                    n += 1;
                }
            }
        }
        n as f64 / (SIZE * SIZE) as f64
    };
    let (over_4, over_16) = (over(4.0), over(16.0));
    eprintln!("sbvr: {:.2}% of pixels beyond 4/255, {:.2}% beyond 16/255", 100.0 * over_4, 100.0 * over_16);
    // SBVR samples each ray where it crosses the planes, not at the raycaster's (k + 0.5)·step:
    // the same Riemann sum of the same integral with every sample shifted by less than one
    // step, and a different count of samples where the ray enters and leaves the box. Inside
    // the box that moves a pixel by a few 1/255 at most (measured on ML at 96²: 1.1% of pixels
    // beyond 4/255). Rays that graze a face or edge of the box are the exception: their short
    // chord is sampled by a handful of planes at positions unrelated to the reference's (and
    // polygon rasterization vs the slab test decide differently whether they hit at all), so
    // single silhouette pixels differ by up to 93/255. Hence a statistical bound, like the
    // 8-bit isosurface test: mean ≤ 1/255 (measured 0.30/255) and ≤ 1% of pixels beyond 16/255
    // (measured 0.22%).
    assert!(mean_abs <= 1.0 / 255.0, "sbvr: mean abs {:.4}/255", mean_abs * 255.0);
    assert!(over_16 <= 0.01, "sbvr: {:.2}% of pixels beyond 16/255", 100.0 * over_16);
    let _ = max_abs;
}

#[test]
fn thesis_pixel_and_compute_shader_graphs_agree_and_match_the_reference() {
    let gpu = gpu();
    let v = ml();
    let l = lut(&v, Preset::Default);
    let opts = options(&v);
    let pixel = render(&gpu, "compute_raycast_2013/pixel_shader.ron", &v, &l, &CAMERA, &opts);
    let compute = render(&gpu, "compute_raycast_2013/compute_shader.ron", &v, &l, &CAMERA, &opts);
    // The same integral written to the same Rgba16Float format: equal up to rounding.
    assert_close("thesis compute vs pixel shader", &compute, &pixel, LOSSLESS);
    assert_matches_reference("thesis pixel shader", &pixel, &v, &l, &CAMERA, 0.0);
    assert_matches_reference("thesis compute shader", &compute, &v, &l, &CAMERA, 0.0);
}

#[test]
fn empty_space_skipping_rejects_segments_in_empty_blocks() {
    let gpu = gpu();
    assert!(gpu.early_depth_test, "{}: no SHADER_EARLY_DEPTH_TEST; run on Vulkan (lavapipe)", gpu.adapter_name);
    // A sphere of radius 0.6 in its box: most segments of most rays lie in empty blocks.
    let v = sphere();
    let l = lut(&v, Preset::Default);
    let counter = InvocationCounter::new();
    let mut registry = builtin_registry();
    registry.register(RaycastSegment::counting(counter.clone()));
    let mut counts = Vec::new();
    for graph in ["kruger_westermann_2003/rc_a.ron", "kruger_westermann_2003/rc_b.ron"] {
        render_with(&gpu, &registry, graph, &v, &l, &CAMERA, &lossless(options(&v), graph));
        counts.push(counter.read(&gpu).expect("counter") as u64);
    }
    eprintln!("segment fragments on the sphere: rc_a {}, rc_b {}", counts[0], counts[1]);
    // Measured 52634 vs 24277 at 96²: skipping rejects more than half the segments that
    // termination alone lets through (the lossless images are checked in
    // rc_b_empty_space_skipping_is_lossless).
    assert!(
        counts[1] * 2 < counts[0],
        "empty-space skipping should reject most segments: rc_a {}, rc_b {}",
        counts[0],
        counts[1]
    );
}

#[test]
fn segment_graphs_agree_on_the_sample_sequence() {
    // The termination test recomputes where the next segment's samples lie, so its sampling
    // parameters must equal the segment pass's, and the loop must have ceil(K / M) iterations.
    let v = ml();
    let k = longest_ray_steps(&v, STEP_VOXELS);
    for graph in ["rc", "rc_a", "rc_b", "iso"] {
        let name = format!("kruger_westermann_2003/{graph}.ron");
        let plan =
            compile(&name, &graph_source(&name), &builtin_registry(), &options(&v)).unwrap_or_else(|d| panic!("{d}"));
        let march: Vec<_> = plan.steps.iter().filter(|s| s.pass_id == "march").collect();
        let m = march[0].params.uint("segment_steps");
        assert_eq!(
            march.len() as f64,
            (k / m as f64).ceil(),
            "{name}: the repeat count's divide_by must be segment_steps"
        );
        if let Some(t) = plan.steps.iter().find(|s| s.pass_id == "terminate") {
            for p in ["step_voxels", "segment_steps", "max_steps", "jitter"] {
                assert_eq!(
                    t.params.iter().find(|(n, _)| *n == p),
                    march[0].params.iter().find(|(n, _)| *n == p),
                    "{name}: {p}"
                );
            }
        }
    }
}

#[test]
fn jittered_segments_with_skipping_equal_the_jittered_single_pass() {
    // Jitter shifts every sample of a ray; segments and the termination test must shift theirs
    // the same way, or skipping would drop or repeat samples at segment boundaries.
    let gpu = gpu();
    let v = sphere();
    let l = lut(&v, Preset::Default);
    let single =
        render(&gpu, "basic/fragment_raycast.ron", &v, &l, &CAMERA, &options(&v).with_param("march", "jitter", true));
    let graph = "kruger_westermann_2003/rc_b.ron";
    let opts = lossless(options(&v), graph).with_param("march", "jitter", true).with_param("terminate", "jitter", true);
    let rc_b = render(&gpu, graph, &v, &l, &CAMERA, &opts);
    assert_close("jittered rc_b(T=1) vs jittered single pass", &rc_b, &single, LOSSLESS);
}
