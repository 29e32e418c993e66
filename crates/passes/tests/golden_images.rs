//! Every shipped graph (`graphs/*/*.ron`, not the transfer functions in `graphs/tf/`) renders the
//! image it rendered when its golden was blessed: neghip (a real 64³ scan) at 128², the default
//! transfer function, two frames — the second from a camera turned 8° so that Klein et al.
//! 2005's reprojection graphs start their rays from the first frame's hits — and the second
//! frame's `image` output compared with `crates/passes/tests/golden_images/<folder>/<graph>.png`
//! (16-bit premultiplied RGBA).
//!
//! The goldens were made before the raycasters were folded onto one sampling core (issue "One
//! march"), so they hold every graph to the image it had as its own code path.
//!
//! Tolerance (per channel of premultiplied RGBA): mean abs ≤ 0.1/255 and at most 0.3 % of the
//! pixels over 2/255. Restating a sample position as `first + k·delta` instead of
//! `u0 + t·d` moves it by f32 rounding (~1e-7 of the box), which leaves DVR pixels within
//! ~0.1/255 but can move a first-hit isosurface across a sample at a grazing pixel (a whole
//! colour step there); the 16-bit PNG's own quantisation is 0.004/255. A changed sampling rule,
//! a lost effect or a swapped uniform moves thousands of pixels.
//! `VOLGRAPH_BLESS=1 cargo test -p volgraph-passes --test golden_images` rewrites them.

use std::path::{Path, PathBuf};

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_core::CompileOptions;
use volgraph_core::runtime::{CameraData, Image};
use volgraph_passes::builtin_registry;

mod support;

use support::{gpu, render_once};

const SIZE: u32 = 128;
const MAX_MEAN_ABS: f64 = 0.1 / 255.0;
const PIXEL_THRESHOLD: f64 = 2.0 / 255.0;
const MAX_FRACTION_OVER: f64 = 0.003;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden_images")
}

/// `graphs/<folder>/<name>.ron` for every folder but `tf`, sorted.
fn shipped_graphs() -> Vec<(String, PathBuf)> {
    let mut graphs = Vec::new();
    let root = repo().join("graphs");
    let mut folders: Vec<_> = std::fs::read_dir(&root).expect("graphs/").flatten().map(|e| e.path()).collect();
    folders.sort();
    for folder in folders.into_iter().filter(|f| f.is_dir() && !f.ends_with("tf")) {
        let mut files: Vec<_> = std::fs::read_dir(&folder).expect("graph folder").flatten().map(|e| e.path()).collect();
        files.sort();
        for file in files.into_iter().filter(|f| f.extension().is_some_and(|e| e == "ron")) {
            let name = format!(
                "{}/{}",
                folder.file_name().expect("a folder name").to_string_lossy(),
                file.file_stem().expect("a file name").to_string_lossy()
            );
            graphs.push((name, file));
        }
    }
    graphs
}

fn camera(azimuth_deg: f64) -> OrbitCamera {
    OrbitCamera { azimuth_deg, elevation_deg: 20.0, distance: 2.8, fov_y_deg: 30.0, ..OrbitCamera::default() }
}

fn to_rgba16(image: &Image) -> image::ImageBuffer<image::Rgba<u16>, Vec<u16>> {
    let pixels = image.to_rgba_f64();
    let mut out = image::ImageBuffer::new(image.width, image.height);
    for (i, p) in pixels.iter().enumerate() {
        let q = |v: f64| (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
        out.put_pixel(
            i as u32 % image.width,
            i as u32 / image.width,
            image::Rgba([q(p[0]), q(p[1]), q(p[2]), q(p[3])]),
        );
    }
    out
}

fn from_rgba16(golden: &image::ImageBuffer<image::Rgba<u16>, Vec<u16>>) -> Vec<[f64; 4]> {
    golden.pixels().map(|p| p.0.map(|c| c as f64 / 65535.0)).collect()
}

/// The graph's second frame: its `image` output, else its first (the slice panes' `axial`).
fn render(gpu: &std::sync::Arc<volgraph_core::runtime::Gpu>, name: &str, path: &Path) -> Result<Image, String> {
    let volume = volgraph_accel::data_dir::load_dataset("neghip").map_err(|e| e.to_string())?.volume;
    let tf = TransferFunction::default_for(&volume);
    let lut = tf.to_lut_for(&volume, 256);
    let source = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let registry = builtin_registry();
    let options = CompileOptions::new(SIZE, SIZE);
    let (mut runtime, plan) = render_once(gpu, &registry, name, &source, &options, &volume, &lut, &camera(30.0))?;
    runtime.render(CameraData::from_orbit(&camera(38.0), plan.viewport)).map_err(|e| e.to_string())?;
    let output = match plan.outputs.keys().next() {
        _ if plan.outputs.contains_key("image") => "image",
        Some(first) => first.as_str(),
        None => return Err("the graph has no output".to_string()),
    };
    runtime.read_output(output).map_err(|e| e.to_string())
}

#[test]
fn every_shipped_graph_renders_its_golden_image() {
    let gpu = gpu();
    let bless = std::env::var_os("VOLGRAPH_BLESS").is_some();
    let graphs = shipped_graphs();
    assert!(graphs.len() >= 20, "expected every paper's graphs, found {}", graphs.len());
    let mut failures = Vec::new();
    let mut report = Vec::new();
    for (name, path) in &graphs {
        let image = match render(&gpu, name, path) {
            Ok(image) => image,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let golden_path = golden_dir().join(format!("{name}.png"));
        if bless {
            std::fs::create_dir_all(golden_path.parent().unwrap()).expect("golden folder");
            to_rgba16(&image).save(&golden_path).expect("writes the golden");
            continue;
        }
        let golden = match image::open(&golden_path) {
            Ok(g) => g.to_rgba16(),
            Err(e) => {
                failures
                    .push(format!("{name}: no golden {} ({e}); bless with VOLGRAPH_BLESS=1", golden_path.display()));
                continue;
            }
        };
        if golden.dimensions() != (image.width, image.height) {
            failures.push(format!(
                "{name}: golden is {:?}, image {}x{}",
                golden.dimensions(),
                image.width,
                image.height
            ));
            continue;
        }
        // A golden PNG holds [0, 1]; additive channels (multi/channels) exceed 1 where they
        // overlap, as a display saturates them.
        let actual: Vec<[f64; 4]> = image.to_rgba_f64().iter().map(|p| p.map(|c| c.clamp(0.0, 1.0))).collect();
        let expected = from_rgba16(&golden);
        let diff = volgraph_accel::image_diff::image_diff(&actual, &expected).expect("same size");
        let over = volgraph_accel::image_diff::fraction_over(&actual, &expected, PIXEL_THRESHOLD).expect("same size");
        report.push(format!(
            "{name}: max {:.3}/255, mean {:.4}/255, {:.3} % over 2/255",
            diff.max_abs * 255.0,
            diff.mean_abs * 255.0,
            over * 100.0
        ));
        if !(diff.mean_abs <= MAX_MEAN_ABS) || !(over <= MAX_FRACTION_OVER) {
            let dir = repo().join("target/test-images/golden");
            let _ = std::fs::create_dir_all(&dir);
            let _ = to_rgba16(&image).save(dir.join(format!("{}.png", name.replace('/', "__"))));
            failures.push(format!(
                "{name}: mean {:.4}/255 (≤ {:.2}), {:.3} % of pixels over 2/255 (≤ {:.1} %); image in target/test-images/golden",
                diff.mean_abs * 255.0,
                MAX_MEAN_ABS * 255.0,
                over * 100.0,
                MAX_FRACTION_OVER * 100.0
            ));
        }
    }
    println!("{}", report.join("\n"));
    assert!(
        failures.is_empty(),
        "{} of {} graphs differ from their golden images:\n{}",
        failures.len(),
        graphs.len(),
        failures.join("\n")
    );
}

/// The goldens hold pictures, not blank frames: a golden of zeros would pass any graph that
/// renders nothing.
#[test]
fn golden_images_are_not_empty() {
    for (name, _) in shipped_graphs() {
        let path = golden_dir().join(format!("{name}.png"));
        let Ok(golden) = image::open(&path) else { continue };
        let lit = golden.to_rgba16().pixels().filter(|p| p.0[3] > 655).count();
        assert!(lit > 500, "{name}: only {lit} pixels of its golden have alpha over 1 %");
    }
}
