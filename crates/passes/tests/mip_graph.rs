//! `graphs/basic/mip.ron`: a stock graph whose pass kind is declared in the graph and written in
//! WGSL alone (`shaders/graph_kinds/mip_projection.wgsl`). Its image equals the f64 MIP at
//! volgraph's sample positions (`volgraph_accel::mip::mip_pixel`), and its parameters reach the
//! shader in the declared order.

mod support;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::mip::mip_pixel;
use volgraph_core::CompileOptions;
use volgraph_passes::builtin_registry;

const SIZE: u32 = 64;

/// Renders the MIP graph with `options`' parameter overrides; the largest difference from the
/// CPU MIP windowed by (level, width) over the pixels both hit, and how many pixels were compared.
fn largest_difference(options: CompileOptions, level: f64, width: f64, step: f64) -> (f64, usize) {
    let volume = volgraph_accel::generate::marschner_lobb(40);
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 20.0, distance: 2.6, ..OrbitCamera::default() };
    let (mut runtime, _) = support::render_once(
        &support::gpu(),
        &builtin_registry(),
        "basic/mip.ron",
        &support::graph_source("basic/mip.ron"),
        &options,
        &volume,
        &[[0.0; 4]; 2],
        &camera,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let image = runtime.read_output("image").expect("the MIP image");
    let frame = camera.frame(SIZE, SIZE);
    let (mut gpu_pixels, mut wanted, mut edge) = (Vec::new(), Vec::new(), 0usize);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let gpu = image.rgba(x, y);
            match mip_pixel(&volume, &camera, &frame, (x, y, SIZE), step, false) {
                Some(m) if gpu[3] == 1.0 => {
                    let want = ((m - (level - 0.5 * width)) / width).clamp(0.0, 1.0);
                    gpu_pixels.push(gpu.map(f64::from));
                    wanted.push([want, want, want, 1.0]);
                }
                None if gpu[3] == 0.0 => {}
                // A ray grazing the silhouette meets the box in f32 and misses in f64, or back.
                _ => edge += 1,
            }
        }
    }
    let compared = gpu_pixels.len();
    assert!(compared > (SIZE * SIZE / 4) as usize, "the volume fills the view ({compared} pixels)");
    assert!(edge * 100 <= compared, "{edge} silhouette pixels disagree on hit/miss");
    // The project's one metric over the pixels both hit: a NaN would be an infinite difference.
    let diff = volgraph_accel::image_diff::image_diff(&gpu_pixels, &wanted).expect("same size");
    (diff.max_abs, compared)
}

#[test]
fn the_wgsl_only_mip_equals_the_f64_mip() {
    let (max, _) = largest_difference(CompileOptions::new(SIZE, SIZE), 0.5, 1.0, 0.5);
    // 2/255: 8-bit trilinear weights on u8 data and an f16 target against f64 (the tolerance of
    // volgraph's other GPU-vs-reference tests).
    assert!(max <= 2.0 / 255.0, "largest MIP difference {:.3}/255", max * 255.0);
}

/// The three parameters are filled by position: a narrow window and a coarse step only match
/// the reference if each reaches its own member.
#[test]
fn the_declared_parameters_reach_the_shader() {
    let options = CompileOptions::new(SIZE, SIZE)
        .with_param("mip", "level", 0.3)
        .with_param("mip", "width", 0.4)
        .with_param("mip", "step_voxels", 2.0);
    let (max, _) = largest_difference(options, 0.3, 0.4, 2.0);
    // 2/255 before the window; the window's gain of 1/0.4 scales it to 5/255.
    assert!(max <= 5.0 / 255.0, "largest MIP difference {:.3}/255", max * 255.0);
}
