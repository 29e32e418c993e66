//! The worked external crate, end to end on the GPU: the graph that uses both new kinds compiles
//! with volgraph's registry plus this crate's, `mip` equals a CPU maximum-intensity projection
//! over volgraph's reference rays, and the WGSL-only `edge_enhance` equals unsharp masking
//! computed on the CPU from the MIP image the GPU produced.

use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Registry};

const SIZE: u32 = 64;

fn registry() -> Registry {
    let mut registry = volgraph_passes::builtin_registry();
    volgraph_example_radiology::register(&mut registry);
    registry
}

fn render(volume: &volgraph_accel::volume::Volume, camera: &OrbitCamera) -> (Image, Image) {
    render_with(volume, camera, |source| source)
}

/// Renders the example graph after `edit` changed its text.
fn render_with(
    volume: &volgraph_accel::volume::Volume,
    camera: &OrbitCamera,
    edit: impl Fn(String) -> String,
) -> (Image, Image) {
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)"));
    let shaders = volgraph_example_radiology::shader_sources();
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(shaders));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/mip_enhanced.ron");
    let source = edit(std::fs::read_to_string(&path).expect("graph"));
    let registry = registry();
    let plan = runtime
        .compile("mip_enhanced.ron", &source, &registry, &CompileOptions::new(SIZE, SIZE))
        .unwrap_or_else(|d| panic!("{d}"));
    runtime.bind_scene(&plan.inputs, volume, &[[0.0; 4]; 2]).expect("binds");
    let viewport = plan.viewport;
    runtime.apply(plan, &registry).unwrap_or_else(|e| panic!("{e}"));
    runtime.render(CameraData::from_orbit(camera, viewport)).unwrap_or_else(|e| panic!("{e}"));
    (runtime.read_output("mip").expect("mip"), runtime.read_output("image").expect("image"))
}

/// The CPU MIP of pixel (x, y) at volgraph's sample positions, step 0.5 voxel
/// ([`volgraph_accel::mip::mip_pixel`]), or None where the ray misses the box.
fn cpu_mip(
    volume: &volgraph_accel::volume::Volume,
    camera: &OrbitCamera,
    x: u32,
    y: u32,
    jittered: bool,
) -> Option<f64> {
    volgraph_accel::mip::mip_pixel(volume, camera, &camera.frame(SIZE, SIZE), (x, y, SIZE), 0.5, jittered)
}

/// Compares the GPU MIP with the CPU one; returns the largest difference over the pixels both
/// hit, after checking that the volume fills the view and few silhouette pixels disagree.
fn compare_with_cpu(mip: &Image, volume: &volgraph_accel::volume::Volume, camera: &OrbitCamera, jittered: bool) -> f64 {
    let (mut compared, mut edge, mut max) = (0, 0, 0.0f64);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let gpu = mip.rgba(x, y);
            match cpu_mip(volume, camera, x, y, jittered) {
                Some(m) if gpu[3] == 1.0 => {
                    compared += 1;
                    max = max.max((gpu[0] as f64 - m).abs());
                }
                None if gpu[3] == 0.0 => {}
                // A ray grazing the box's silhouette meets it in f32 and misses in f64, or back.
                _ => edge += 1,
            }
        }
    }
    assert!(compared > (SIZE * SIZE / 4) as usize, "the volume fills the view ({compared} pixels)");
    assert!(edge * 100 <= compared, "{edge} silhouette pixels disagree on hit/miss");
    max
}

#[test]
fn mip_equals_a_cpu_maximum_intensity_projection() {
    let volume = volgraph_accel::generate::marschner_lobb(40);
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 20.0, distance: 2.6, ..OrbitCamera::default() };
    let (mip, _) = render(&volume, &camera);
    let max = compare_with_cpu(&mip, &volume, &camera, false);
    // 2/255: 8-bit trilinear weights on u8 data and an f16 target against f64 (the tolerance of
    // volgraph's own GPU-vs-reference tests).
    assert!(max <= 2.0 / 255.0, "largest MIP difference {:.3}/255", max * 255.0);
}

/// `jitter` comes with volgraph's shared sampling block, and the pass honours it: the GPU MIP
/// equals the CPU one at the jittered sample positions, and not the unjittered one.
#[test]
fn mip_takes_the_shared_jitter() {
    let volume = volgraph_accel::generate::marschner_lobb(40);
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 20.0, distance: 2.6, ..OrbitCamera::default() };
    let jitter_on = |source: String| source.replacen(r#""width": 1.0}"#, r#""width": 1.0, "jitter": true}"#, 1);
    let (mip, _) = render_with(&volume, &camera, jitter_on);
    // 2/255 as above: the same samples, offset by the same per-pixel hash.
    let jittered = compare_with_cpu(&mip, &volume, &camera, true);
    assert!(jittered <= 2.0 / 255.0, "largest jittered MIP difference {:.3}/255", jittered * 255.0);
    let plain = compare_with_cpu(&mip, &volume, &camera, false);
    assert!(plain > jittered, "jitter moved the samples ({:.3} vs {:.3}/255)", plain * 255.0, jittered * 255.0);
}

#[test]
fn the_wgsl_only_edge_enhance_is_unsharp_masking() {
    let volume = volgraph_accel::generate::marschner_lobb(40);
    let camera = OrbitCamera { azimuth_deg: 10.0, elevation_deg: 30.0, distance: 2.4, ..OrbitCamera::default() };
    let (mip, enhanced) = render(&volume, &camera);
    let at = |x: i64, y: i64, c: usize| {
        let (x, y) = (x.clamp(0, SIZE as i64 - 1) as u32, y.clamp(0, SIZE as i64 - 1) as u32);
        mip.rgba(x, y)[c] as f64
    };
    let (strength, r) = (1.5, 1);
    let mut max = 0.0f64;
    for y in 0..SIZE as i64 {
        for x in 0..SIZE as i64 {
            for c in 0..3 {
                let blur = 0.25 * (at(x + r, y, c) + at(x - r, y, c) + at(x, y + r, c) + at(x, y - r, c));
                let want = (at(x, y, c) + strength * (at(x, y, c) - blur)).clamp(0.0, 1.0);
                max = max.max((enhanced.rgba(x as u32, y as u32)[c] as f64 - want).abs());
            }
        }
    }
    // The same arithmetic in f32 on the GPU, stored as f16: ≤ 2⁻¹¹ relative on values ≤ 1.
    assert!(max <= 1e-3, "largest difference {max}");
}
