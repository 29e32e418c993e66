//! Helpers shared by the GPU integration tests of crates/passes: the adapter, graph files, image
//! comparison against the f64 reference, and failure images.

#![allow(dead_code, reason = "each test binary uses the subset it needs")]

use std::path::PathBuf;
use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Plan, Registry};

/// One DVR graph of each raycaster family that takes every scene effect: fragment, compute, the
/// single pass with leaping, the fastest path, Krüger–Westermann's multipass segments with
/// termination and skipping (rc_b) and with the leap inside the segments (rc_b_leap), and Klein
/// et al.'s leaping march alone and with empty cubes (its first frame: every ray from the box),
/// and Ruijters & Vilanova's brick pool with per-brick octrees.
/// `effects.rs` renders each against the reference, `effects_not_compiled.rs` checks each
/// compiles an effect only when asked.
pub const EFFECT_GRAPHS: [&str; 9] = [
    "basic/fragment_raycast.ron",
    "basic/compute_raycast.ron",
    "modern/single_pass_ess_ert.ron",
    "modern/fastest.ron",
    "kruger_westermann_2003/rc_b.ron",
    "kruger_westermann_2003/rc_b_leap.ron",
    "klein_2005/leap_dvr.ron",
    "klein_2005/leap_dvr_cubes.ron",
    "ruijters_vilanova_2006/bricks_octree.ron",
];

/// A GPU path tracer's mean image `got` over `spp` samples against the independent f64
/// tracer's per-pixel estimates `cpu`, asserted to agree: per pixel and channel
/// z = (GPU − CPU) / √(2 s² / n), s² the CPU's sample variance (the GPU's is the same
/// distribution's, or less with its better estimators) and at least one unit event in n samples
/// (a pixel the CPU's paths never interacted in may still see one GPU path do so). Two agreeing
/// estimators put |z| > 3 on 0.3 % of values (the means of hundreds of paths are near normal): at
/// most 2 % is allowed; a wrong light, phase function, majorant, map or medium moves whole
/// regions by tens of standard errors. No systematic offset: the mean of the z's has standard
/// deviation 1/√count (a pixel's channels are correlated, so 6 of those are allowed).
pub fn assert_agrees_with_the_f64_tracer(
    what: &str,
    got: &[[f64; 4]],
    cpu: &[volgraph_accel::path_trace::PixelEstimate],
    spp: u32,
) {
    let n = f64::from(spp);
    let (mut over, mut counted, mut sum_z) = (0usize, 0usize, 0.0);
    for (g, c) in got.iter().zip(cpu) {
        for k in 0..4 {
            let z = (g[k] - c.mean[k]) / (2.0 * c.variance[k] / n).sqrt().max(1.0 / n);
            sum_z += z;
            counted += 1;
            over += usize::from(z.abs() > 3.0);
        }
    }
    let (fraction, mean_z) = (over as f64 / counted as f64, sum_z / counted as f64);
    eprintln!("{what}: {counted} values, {:.2} % beyond 3 standard errors, mean z {mean_z:+.3}", fraction * 100.0);
    assert!(fraction < 0.02, "{what}: {:.2} % of values beyond 3 standard errors", fraction * 100.0);
    assert!(mean_z.abs() < 6.0 / (counted as f64).sqrt(), "{what}: mean z {mean_z}: one is biased");
}

/// The headless GPU. Under CI a missing adapter is a failure, never a skip.
pub fn gpu() -> Arc<Gpu> {
    Arc::new(Gpu::new_headless().expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"))
}

/// A runtime on `gpu` with the built-in shaders.
pub fn runtime(gpu: &Arc<Gpu>) -> Runtime {
    Runtime::new(gpu.clone(), ShaderLibrary::new(volgraph_passes::builtin_shaders()))
}

/// Renders graph `source` (named `file`) once on a fresh runtime: binds `volume` and `lut`,
/// compiles with the volume's scene values, applies, renders one frame from `camera`. The
/// runtime comes back for reading outputs.
#[allow(clippy::too_many_arguments, reason = "the graph, the scene and the camera, each needed once")]
pub fn render_once(
    gpu: &Arc<Gpu>,
    registry: &Registry,
    file: &str,
    source: &str,
    options: &CompileOptions,
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
) -> Result<(Runtime, Plan), String> {
    let mut runtime = runtime(gpu);
    let mut options = options.clone();
    options.scene = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(volume));
    let plan = volgraph_core::compile(file, source, registry, &options).map_err(|d| d.to_string())?;
    runtime.bind_scene(&plan.inputs, volume, lut).map_err(|e| e.to_string())?;
    runtime.apply(plan.clone(), registry).map_err(|e| e.to_string())?;
    runtime.render(CameraData::from_orbit(camera, plan.viewport)).map_err(|e| e.to_string())?;
    Ok((runtime, plan))
}

/// Asserts a shaded GPU image is its f64 reference within the bounds of shaded images (f32 on
/// the GPU, f64 on the CPU; the gradient's central differences and the specular power amplify
/// rounding where the normal is ill-conditioned): at most 0.5 % of pixels over 2/255, mean
/// under 0.5/255 per channel. Prints the figures after `what` (and `extra`).
pub fn assert_shaded_like_reference(what: &str, got: &[[f64; 4]], reference: &[[f64; 4]], extra: &str) {
    let diff = volgraph_accel::image_diff::image_diff(got, reference).expect("same size");
    let over = volgraph_accel::image_diff::fraction_over(got, reference, 2.0 / 255.0).expect("same size");
    eprintln!(
        "{what}: max {:.2}/255 mean {:.3}/255, {:.2}% over 2/255{extra}",
        diff.max_abs * 255.0,
        diff.mean_abs * 255.0,
        over * 100.0
    );
    assert!(over <= 0.005, "{what}: {:.2}% of pixels over 2/255", over * 100.0);
    assert!(diff.mean_abs <= 0.5 / 255.0, "{what}: mean {:.3}/255", diff.mean_abs * 255.0);
}

/// `graph` (under `graphs/`) rendered at `size`² on a fresh runtime with the scene's `light`,
/// `cuts` and `features`, and the reference settings of its "march" pass with the same light
/// and cuts. Krüger–Westermann's termination test stops between segments, the reference per
/// sample: those graphs are compared lossless (T = 1), as tests/kruger_westermann.rs compares
/// them.
pub fn render_in_scene(
    gpu: &Arc<Gpu>,
    (graph, size): (&str, u32),
    (volume, lut): (&Volume, &[[f32; 4]]),
    camera: &OrbitCamera,
    (lights, cuts): (impl Into<volgraph_accel::light::Lights>, volgraph_accel::cuts::Cuts),
    features: &[&str],
) -> (Image, volgraph_accel::reference::RaycastSettings) {
    let registry = volgraph_passes::builtin_registry();
    let source = graph_source(graph);
    let mut all = volgraph_core::cut_effects::features_of(&cuts);
    all.extend(features.iter().map(|f| f.to_string()));
    let mut options = CompileOptions::new(size, size).with_features(all);
    options.scene = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(volume));
    let mut plan =
        volgraph_core::compile(graph, &source, &registry, &options).unwrap_or_else(|d| panic!("{graph}: {d}"));
    if plan.steps.iter().any(|s| s.pass_id == "terminate") {
        options = options.with_param("terminate", "threshold", 1.0).with_param("march", "threshold", 1.0);
        plan = volgraph_core::compile(graph, &source, &registry, &options).unwrap_or_else(|d| panic!("{graph}: {d}"));
    }
    let march = plan.steps.iter().find(|s| s.pass_id == "march").expect("a march step");
    let lights = lights.into();
    let settings = volgraph_accel::reference::RaycastSettings {
        lights,
        cuts,
        ..volgraph_passes::raycast_params::reference_settings(&march.params)
    };
    let mut runtime = runtime(gpu);
    runtime.set_lights(lights);
    runtime.set_cuts(cuts);
    runtime.bind_scene(&plan.inputs, volume, lut).expect("binds");
    runtime.apply(plan.clone(), &registry).unwrap_or_else(|e| panic!("{graph}: {e}"));
    runtime.render(CameraData::from_orbit(camera, plan.viewport)).unwrap_or_else(|e| panic!("{graph}: {e}"));
    (runtime.read_output("image").expect("image"), settings)
}

/// `graphs/<name>` in the workspace.
pub fn graph_path(name: &str) -> PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs").join(name)
}

/// The text of `graphs/<name>`.
pub fn graph_source(name: &str) -> String {
    let path = graph_path(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A GPU image as f64 RGBA rows (to compare two GPU images with [`diff_reference`]).
pub fn as_reference(image: &Image) -> Vec<[f64; 4]> {
    image.to_rgba_f64()
}

/// (max abs, mean abs) per channel between a GPU image and reference colours, by the project's
/// one metric ([`volgraph_accel::image_diff`]): a NaN channel makes max abs infinite.
pub fn diff_reference(gpu: &Image, reference: &[[f64; 4]]) -> (f64, f64) {
    let d = volgraph_accel::image_diff::image_diff(&gpu.to_rgba_f64(), reference).unwrap_or_else(|e| panic!("{e}"));
    (d.max_abs, d.mean_abs)
}

/// Writes GPU, reference and 10×-amplified difference images to
/// `target/test-images/<name>_{gpu,reference,diff_x10}.png` so a failing comparison can be
/// looked at.
pub fn save_images(name: &str, gpu: &Image, reference: &[[f64; 4]]) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/test-images");
    let _ = std::fs::create_dir_all(&dir);
    let name: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    let (w, h) = (gpu.width, gpu.height);
    let to8 = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let mut g = image::RgbaImage::new(w, h);
    let mut r = image::RgbaImage::new(w, h);
    let mut d = image::RgbaImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let a = gpu.rgba(x, y);
            let b = reference[(y * w + x) as usize];
            g.put_pixel(x, y, image::Rgba([to8(a[0] as f64), to8(a[1] as f64), to8(a[2] as f64), 255]));
            r.put_pixel(x, y, image::Rgba([to8(b[0]), to8(b[1]), to8(b[2]), 255]));
            let diff = |c: usize| to8(10.0 * (a[c] as f64 - b[c]).abs());
            d.put_pixel(x, y, image::Rgba([diff(0), diff(1), diff(3), 255]));
        }
    }
    let _ = g.save(dir.join(format!("{name}_gpu.png")));
    let _ = r.save(dir.join(format!("{name}_reference.png")));
    let _ = d.save(dir.join(format!("{name}_diff_x10.png")));
}

/// A graph (`graphs/<name>`) applied on its own runtime with `volume` and `lut` bound, ready to
/// render frames and read what its passes report (the Klein and Ruijters tests).
pub struct Live {
    /// The runtime holding the applied plan.
    pub runtime: Runtime,
    /// The plan's viewport.
    pub viewport: (u32, u32),
}

impl Live {
    /// Compiles, binds and applies `graph` on a fresh runtime.
    pub fn new(
        gpu: &Arc<Gpu>,
        registry: &Registry,
        graph: &str,
        volume: &Volume,
        lut: &[[f32; 4]],
        options: &CompileOptions,
    ) -> Self {
        Self::with_source(gpu, registry, (graph, &graph_source(graph)), volume, lut, options, |_| {})
    }

    /// [`Self::new`] of the graph text `source` (named `graph`); `bind` binds what the scene's
    /// volume and TF do not (a second volume, a label table) before the plan is applied.
    pub fn with_source(
        gpu: &Arc<Gpu>,
        registry: &Registry,
        (graph, source): (&str, &str),
        volume: &Volume,
        lut: &[[f32; 4]],
        options: &CompileOptions,
        bind: impl FnOnce(&mut Runtime),
    ) -> Self {
        let mut runtime = runtime(gpu);
        let plan = runtime.compile(graph, source, registry, options).unwrap_or_else(|d| panic!("{graph}:\n{d}"));
        runtime.bind_scene(&plan.inputs, volume, lut).expect("binds");
        bind(&mut runtime);
        let viewport = plan.viewport;
        runtime.apply(plan, registry).unwrap_or_else(|e| panic!("{graph}: {e}"));
        Self { runtime, viewport }
    }

    /// Renders one frame from `camera` and reads the `image` output.
    pub fn frame(&mut self, camera: &OrbitCamera) -> Image {
        self.runtime.render(CameraData::from_orbit(camera, self.viewport)).unwrap_or_else(|e| panic!("{e}"));
        self.runtime.read_output("image").expect("image")
    }

    /// A target of the last frame by resource name (`holes.start`, `entry.entry`).
    pub fn resource(&mut self, name: &str) -> Image {
        let rid = self.runtime.plan().expect("plan").resources.iter().position(|r| r.name == name).expect(name);
        self.runtime.read_resource(rid).expect("reads")
    }

    /// A buffer of the last frame by resource name (`bounds.tiles`, `march.samples`), as words.
    pub fn buffer_words(&mut self, name: &str) -> Vec<u32> {
        let rid = self.runtime.plan().expect("plan").resources.iter().position(|r| r.name == name).expect(name);
        let bytes = self.runtime.read_buffer_resource(rid).expect("reads");
        bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect()
    }

    /// A figure a pass reported about the last frame (`PassNode::counters`), by name.
    pub fn counter(&self, name: &str) -> f64 {
        let counters = self.runtime.pass_counters();
        counters.iter().find(|(_, n, _)| *n == name).unwrap_or_else(|| panic!("no counter {name}: {counters:?}")).2
    }
}

/// The fraction of `image`'s pixels with any opacity: a test's check that the volume is in view.
pub fn coverage(image: &Image) -> f64 {
    let covered = (0..image.height).flat_map(|y| (0..image.width).map(move |x| (x, y)));
    covered.filter(|&(x, y)| image.rgba(x, y)[3] > 0.0).count() as f64 / (image.width * image.height) as f64
}
