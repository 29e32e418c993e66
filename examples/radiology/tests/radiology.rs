//! The worked external crate, end to end on the GPU: the graph that uses both new kinds compiles
//! with volgraph's registry plus this crate's, `mip` equals a CPU maximum-intensity projection
//! over volgraph's reference rays, and the WGSL-only `edge_enhance` equals unsharp masking
//! computed on the CPU from the MIP image the GPU produced.

use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{ray_segment, step_tex};
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Registry};

const SIZE: u32 = 64;

fn registry() -> Registry {
    let mut registry = volgraph_passes::builtin_registry();
    volgraph_example_radiology::register(&mut registry);
    registry
}

fn render(volume: &volgraph_accel::volume::Volume, camera: &OrbitCamera) -> (Image, Image) {
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)"));
    let shaders = volgraph_passes::builtin_shaders().with_embedded(volgraph_example_radiology::SHADERS);
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(shaders));
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/mip_enhanced.ron");
    let source = std::fs::read_to_string(&path).expect("graph");
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

/// The CPU MIP of pixel (x, y): the largest trilinear sample at volgraph's sample positions
/// (k + 0.5 steps of 0.5 voxel from the entry), or None where the ray misses the box.
fn cpu_mip(volume: &volgraph_accel::volume::Volume, camera: &OrbitCamera, x: u32, y: u32) -> Option<f64> {
    let frame = camera.frame(SIZE, SIZE);
    let seg = ray_segment(volume, camera, &frame, x, y)?;
    let step = step_tex(volume, seg.d_tex, 0.5);
    let count = (seg.len_tex / step - 0.5).ceil().max(0.0) as u32;
    Some((0..count).map(|k| volume.sample_trilinear(seg.u0 + (k as f64 + 0.5) * step * seg.d_tex)).fold(0.0, f64::max))
}

#[test]
fn mip_equals_a_cpu_maximum_intensity_projection() {
    let volume = volgraph_accel::generate::marschner_lobb(40);
    let camera = OrbitCamera { azimuth_deg: 35.0, elevation_deg: 20.0, distance: 2.6, ..OrbitCamera::default() };
    let (mip, _) = render(&volume, &camera);
    let (mut compared, mut edge, mut max) = (0, 0, 0.0f64);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let gpu = mip.rgba(x, y);
            match cpu_mip(&volume, &camera, x, y) {
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
    // 2/255: 8-bit trilinear weights on u8 data and an f16 target against f64 (the tolerance of
    // volgraph's own GPU-vs-reference tests).
    assert!(max <= 2.0 / 255.0, "largest MIP difference {:.3}/255", max * 255.0);
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
