//! Klein et al. 2005 as graphs (`graphs/klein_2005/`): empty-space leaping by reprojected hit
//! points must not change the image. The first frame equals the plain raycast exactly (nothing
//! to reproject: every ray starts at the box); while the camera turns 1°, 2° and 5° per frame
//! for 30 frames, every frame equals the plain raycast within 1/255 on at least 99.9 % of its
//! pixels (a start estimate can only be wrong where a surface appears that the last frame did
//! not see); hole filling leaves no pixel of the volume's footprint without a start; a new
//! transfer function, an isovalue edit or a camera jump starts again from the box. The graphs'
//! bypass leaves splat and hole fill out where reprojection cannot pay (a surface right at the
//! box) and brings them back where it can, the image staying the plain raycast's; the measure it
//! decides by is checked against the CPU. The tests of reprojection itself set the bypass's
//! threshold so low that it never leaves the passes out. Failure images go to
//! target/test-images.

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{Phong, RaycastSettings, RenderMode, render_supersampled};
use volgraph_accel::transfer_function::{ControlPoint, Preset, TransferFunction};
use volgraph_accel::volume::Volume;
use volgraph_core::CompileOptions;
use volgraph_core::runtime::Image;
use volgraph_passes::builtin_registry;

mod support;

use support::{Live, as_reference, graph_source, save_images};

const SIZE: u32 = 128;

/// `input.reproject_below` low enough that the bypass never leaves reprojection out (a view
/// where some ray crosses empty space measures more), for the tests of reprojection itself.
const ALWAYS_REPROJECT: f64 = 1e-6;

/// The options of a reprojection test: `SIZE`² with the bypass kept from leaving it out.
fn reprojecting() -> CompileOptions {
    CompileOptions::new(SIZE, SIZE).with_scalar("reproject_below", ALWAYS_REPROJECT)
}

/// The fraction of pixels with a channel more than 1/255 apart, and the largest difference, by
/// the project's one metric (`volgraph_accel::image_diff`: a NaN is off and infinitely far).
fn compare(a: &Image, b: &Image) -> (f64, f64) {
    let (a, b) = (as_reference(a), as_reference(b));
    let off = volgraph_accel::image_diff::fraction_over(&a, &b, 1.0 / 255.0).expect("same size");
    (off, volgraph_accel::image_diff::image_diff(&a, &b).expect("same size").max_abs)
}

fn coverage(image: &Image) -> f64 {
    let covered = (0..image.height).flat_map(|y| (0..image.width).map(move |x| (x, y)));
    covered.filter(|&(x, y)| image.rgba(x, y)[3] > 0.0).count() as f64 / (image.width * image.height) as f64
}

/// Datasets with a TF (DVR) and an isovalue (iso) that show something: generated
/// Marschner–Lobb, and the real hydrogen_atom and neghip where the data folder has them.
fn datasets() -> Vec<(Volume, TransferFunction, f64)> {
    let mut out = smooth_datasets();
    out.push(tooth());
    out
}

/// The hard case of issue 47: a CT of a tooth (`volgraph_accel::tooth`, 128 × 128 × 81, noisy
/// air, thin enamel over dentin, root canals) under the TF `volgraph render` fits to it, at the
/// isovalue of its outer surface (0.45). Per-pixel splats left some rays starting past a
/// surface that turned into view (up to 30/255 on a few pixels at 5° per frame).
fn tooth() -> (Volume, TransferFunction, f64) {
    let t = volgraph_accel::tooth::tooth(128);
    let tf = TransferFunction::default_for(&t);
    (t, tf, 0.45)
}

/// `datasets()` but the tooth.
fn smooth_datasets() -> Vec<(Volume, TransferFunction, f64)> {
    let ml = volgraph_accel::generate::marschner_lobb(48);
    let mut out = vec![(ml.clone(), TransferFunction::preset(Preset::Opaque, ml.value_range), 0.3)];
    for (name, iso) in [("hydrogen_atom", 0.12), ("neghip", 0.25)] {
        if volgraph_accel::data_dir::require_dataset(name).is_some() {
            let v = volgraph_accel::data_dir::load_dataset(name).expect("loads").volume;
            let tf = TransferFunction::default_for(&v);
            out.push((v, tf, iso));
        }
    }
    out
}

fn camera(azimuth: f64) -> OrbitCamera {
    OrbitCamera { azimuth_deg: azimuth, elevation_deg: 20.0, distance: 2.6, ..OrbitCamera::default() }
}

/// Turns the camera 1°, 2° and 5° per frame for 30 frames and compares every frame of
/// `klein_2005/{leap}.ron` with the plain raycast: at most `allowed` of the pixels may differ by
/// more than 1/255.
fn rotation_matches_the_baseline(mode: &str, leap: &str, allowed: f64) {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let leap_name = leap;
    for (volume, tf, iso) in datasets() {
        let options = reprojecting().with_scalar("iso_value", iso);
        let lut = tf.to_lut_for(&volume, 256);
        for degrees in [1.0, 2.0, 5.0] {
            let mut base =
                Live::new(&gpu, &registry, &format!("klein_2005/baseline_{mode}.ron"), &volume, &lut, &options);
            let mut leap = Live::new(&gpu, &registry, &format!("klein_2005/{leap}.ron"), &volume, &lut, &options);
            let mut worst = (0.0, 0.0, 0);
            for f in 0..30 {
                let cam = camera(10.0 + degrees * f as f64);
                let (b, l) = (base.frame(&cam), leap.frame(&cam));
                if f == 0 {
                    assert!(coverage(&b) > 0.05, "{}: the volume is in view", volume.name);
                    assert_eq!(
                        l.data, b.data,
                        "{leap_name} {}: the first frame is the plain raycast, exactly",
                        volume.name
                    );
                }
                let (off, max) = compare(&l, &b);
                if off > worst.0 {
                    worst = (off, max, f);
                }
                if off > allowed {
                    save_images(
                        &format!("klein_{leap_name}_{}_{degrees}deg_frame{f}", volume.name),
                        &l,
                        &as_reference(&b),
                    );
                }
                assert!(
                    off <= allowed,
                    "{leap_name} {} at {degrees}°/frame, frame {f}: {:.3}% of pixels differ by more than 1/255 (max {:.1}/255)",
                    volume.name,
                    off * 100.0,
                    max * 255.0
                );
            }
            eprintln!(
                "{leap_name} {} {degrees}°/frame: worst frame {} with {:.3}% over 1/255 (max {:.2}/255)",
                volume.name,
                worst.2,
                worst.0 * 100.0,
                worst.1 * 255.0
            );
        }
    }
}

/// Per-tile depth bounds (`reprojection_tiles`, the graphs `leap_iso` and `leap_dvr`) are the
/// nearest reprojected depth around each tile, never farther than a per-pixel splat of the
/// margin's size: no ray starts past what it would have met, so every frame is the plain
/// raycast's (the same samples on the same step grid) to within 1/255 on every pixel, the
/// tooth included.
#[test]
fn tile_bounds_leave_every_frame_the_plain_raycast_while_rotating_the_tooth_included() {
    rotation_matches_the_baseline("iso", "leap_iso", 0.0);
    rotation_matches_the_baseline("dvr", "leap_dvr", 0.0);
    // With the empty cubes behind the first visible sample leapt as well (§6's suggestion).
    rotation_matches_the_baseline("dvr", "leap_dvr_cubes", 0.0);
}

/// The scene effects change what is sampled, not where: with shading, pre-integration,
/// tricubic reconstruction and jitter (DVR) and tricubic and jitter (isosurface) on both sides,
/// every frame of the tooth and Marschner–Lobb turning 2° and 5° a frame is still the plain
/// raycast's.
#[test]
fn tile_bounds_stay_exact_with_the_scene_effects() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (ml, ml_tf, ml_iso) = smooth_datasets().remove(0);
    for (volume, tf, iso) in [tooth(), (ml, ml_tf, ml_iso)] {
        let lut = tf.to_lut_for(&volume, 256);
        for (mode, features) in
            [("dvr", &["shading", "preintegration", "tricubic", "jitter"][..]), ("iso", &["tricubic", "jitter"][..])]
        {
            let options = reprojecting().with_scalar("iso_value", iso).with_features(features.iter().copied());
            for degrees in [2.0, 5.0] {
                let base = format!("klein_2005/baseline_{mode}.ron");
                let mut base = Live::new(&gpu, &registry, &base, &volume, &lut, &options);
                let mut leap =
                    Live::new(&gpu, &registry, &format!("klein_2005/leap_{mode}.ron"), &volume, &lut, &options);
                for f in 0..12 {
                    let cam = camera(10.0 + degrees * f as f64);
                    let (b, l) = (base.frame(&cam), leap.frame(&cam));
                    let (off, max) = compare(&l, &b);
                    if off > 0.0 {
                        save_images(
                            &format!("klein_effects_{mode}_{}_{degrees}deg_frame{f}", volume.name),
                            &l,
                            &as_reference(&b),
                        );
                    }
                    assert!(
                        off == 0.0,
                        "{mode} {} with {features:?} at {degrees}°/frame, frame {f}: {:.3}% over 1/255 (max {:.1}/255)",
                        volume.name,
                        off * 100.0,
                        max * 255.0
                    );
                }
            }
        }
    }
}

/// Fusion in Klein's family: the scan shown only inside its labels (the first visible sample
/// lies deeper than the scan's, where a label begins) and tinted by them, through per-tile
/// bounds reprojected from the fused image's hits — every frame of a turn equals the plain
/// fused raycast on every pixel, as one volume's does.
#[test]
fn tile_bounds_stay_exact_with_a_label_map() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (ct, labels) = (volgraph_accel::organs::organs_ct(48), volgraph_accel::organs::organs_labels(48));
    let lut = TransferFunction::default_for(&ct).to_lut_for(&ct, 256);
    let table = volgraph_accel::organs::label_table().lut(7);
    let with_labels = |graph: &str, fusion: &str| {
        graph_source(graph)
            .replace(
                r#""tf": TransferFunction,"#,
                r#""tf": TransferFunction, "labels": Volume, "label_table": LabelTable,"#,
            )
            .replacen(
                r#""step_voxels": "input.step_voxels","#,
                &format!(r#""step_voxels": "input.step_voxels", "fusion": "{fusion}","#),
                1,
            )
            .replace(
                r#""tf": "input.tf","#,
                r#""tf": "input.tf", "second": "input.labels", "label_table": "input.label_table","#,
            )
    };
    let bind = |runtime: &mut volgraph_core::runtime::Runtime| {
        runtime.bind_volume("labels", &labels).expect("binds");
        runtime.bind_label_table("label_table", &table).expect("binds");
    };
    for fusion in ["inside", "tint"] {
        let options = reprojecting().with_features(["shading"]);
        let (base_name, leap_name) = ("klein_2005/baseline_dvr.ron", "klein_2005/leap_dvr.ron");
        let (base_text, leap_text) = (with_labels(base_name, fusion), with_labels(leap_name, fusion));
        assert!(leap_text.contains(r#""second": "input.labels""#) && base_text.contains(r#""fusion": "#));
        let mut base = Live::with_source(&gpu, &registry, (base_name, &base_text), &ct, &lut, &options, bind);
        let mut leap = Live::with_source(&gpu, &registry, (leap_name, &leap_text), &ct, &lut, &options, bind);
        for f in 0..12 {
            let cam = camera(10.0 + 3.0 * f as f64);
            let (b, l) = (base.frame(&cam), leap.frame(&cam));
            if f == 0 {
                // A check of the scene, not of the march: the organs cover ~13 % of the image.
                assert!(coverage(&b) > 0.02, "{fusion}: the labelled scan is in view");
            }
            let (off, max) = compare(&l, &b);
            if off > 0.0 {
                save_images(&format!("klein_fusion_{fusion}_frame{f}"), &l, &as_reference(&b));
            }
            assert!(off == 0.0, "{fusion}, frame {f}: {:.3}% over 1/255 (max {:.1}/255)", off * 100.0, max * 255.0);
        }
    }
}

/// The paper's per-pixel splats (`leap_*_splats`): a start estimate can be wrong where a
/// surface appears that the last frame did not see, on at most 0.1 % of the pixels.
#[test]
fn per_pixel_splats_equal_the_plain_raycast_on_all_but_a_tenth_of_a_percent_while_rotating() {
    rotation_matches_the_baseline("iso", "leap_iso_splats", 0.001);
    rotation_matches_the_baseline("dvr", "leap_dvr_splats", 0.001);
}

/// The pixels whose ray crosses the volume box by more than a sliver (CPU, f64): the footprint
/// every start must cover. Grazing rays (< 1e-3 of the box) are left out: f32 and f64 may
/// disagree on whether they meet the box at all.
fn footprint(volume: &Volume, camera: &OrbitCamera) -> Vec<bool> {
    let frame = camera.frame(SIZE, SIZE);
    let covered =
        |x, y| volgraph_accel::reference::ray_segment(volume, camera, &frame, x, y).is_some_and(|s| s.len_tex > 1e-3);
    (0..SIZE).flat_map(|y| (0..SIZE).map(move |x| (x, y))).map(|(x, y)| covered(x, y)).collect()
}

#[test]
fn hole_filling_leaves_no_pixel_of_the_footprint_without_a_start() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, _) = datasets().remove(0);
    let lut = tf.to_lut_for(&volume, 256);
    // Single-pixel splats leave the most holes (the paper's Fig. 4, left); with and without the
    // extended-splat step, every pixel of the footprint must end up with a start.
    for extend in [0u64, 1] {
        let options = reprojecting().with_param("splat", "splat_size", 1u64).with_param("holes", "extend", extend);
        let mut leap = Live::new(&gpu, &registry, "klein_2005/leap_iso_splats.ron", &volume, &lut, &options);
        let mut holes_before_filling = 0;
        for f in 0..6 {
            let cam = camera(20.0 + 3.0 * f as f64);
            leap.frame(&cam);
            let (splats, start) = (leap.resource("splat.start"), leap.resource("holes.start"));
            let inside = footprint(&volume, &cam);
            let mut missing = 0;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    if inside[(y * SIZE + x) as usize] {
                        missing += (start.rgba(x, y)[3] == 0.0) as usize;
                        holes_before_filling += (f > 0 && splats.rgba(x, y)[3] == 0.0) as usize;
                    }
                }
            }
            assert_eq!(missing, 0, "extend {extend}, frame {f}: every pixel the box covers has a start");
        }
        assert!(holes_before_filling > 0, "1-pixel splats leave holes for hole_fill to fill");
    }
}

/// §4.4's silhouette rule, as the hole fill applies it from the footprint's row spans
/// (`volgraph_core::runtime::footprint`): a pixel within `silhouette_band` pixels of a pixel
/// whose ray misses the box starts at the box's front face — its entry, not the splat that
/// landed on it — and a pixel deeper inside keeps its splat. The footprint comes from the CPU
/// reference's rays (f64). The square of corners ±band pixels is inside when the one a pixel
/// larger is (its rays all meet the box by more than a sliver), and not inside when the one a
/// pixel smaller is not (by convexity); pixels in between, whose square's corner lies within a
/// pixel of the silhouette, are left out, as the shader's rounding and the span's 1/64-pixel
/// margin may go either way there.
#[test]
fn pixels_near_the_silhouette_start_at_the_box_and_deeper_ones_keep_their_splat() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, iso) = datasets().remove(0);
    let lut = tf.to_lut_for(&volume, 256);
    let band = 2i64;
    let options = reprojecting().with_scalar("iso_value", iso).with_param("holes", "silhouette_band", band as u64);
    let mut leap = Live::new(&gpu, &registry, "klein_2005/leap_iso_splats.ron", &volume, &lut, &options);
    let (mut overridden, mut kept) = (0, 0);
    for f in 0..4 {
        let cam = camera(20.0 + 2.0 * f as f64);
        leap.frame(&cam);
        if f == 0 {
            continue;
        }
        let frame = cam.frame(SIZE, SIZE);
        let segment = |x: i64, y: i64| {
            let (x, y) = (x.clamp(0, SIZE as i64 - 1) as u32, y.clamp(0, SIZE as i64 - 1) as u32);
            volgraph_accel::reference::ray_segment(&volume, &cam, &frame, x, y)
        };
        // Whether the rays of the (clamped) corners ±r around (x, y) all meet the box by more
        // than a sliver, and whether one misses it.
        let corners = |x: i64, y: i64, r: i64| {
            let rays = [(-r, -r), (r, -r), (-r, r), (r, r)].map(|(dx, dy)| segment(x + dx, y + dy));
            (rays.iter().all(|s| s.is_some_and(|s| s.len_tex > 1e-3)), rays.iter().any(Option::is_none))
        };
        let square_inside = |x: i64, y: i64| {
            if corners(x, y, band + 1).0 {
                Some(true)
            } else if corners(x, y, band - 1).1 {
                Some(false)
            } else {
                None
            }
        };
        let (splats, start) = (leap.resource("splat.start"), leap.resource("holes.start"));
        for y in 0..SIZE {
            for x in 0..SIZE {
                let Some(entry) = segment(x as i64, y as i64) else { continue };
                let (splat, got) = (splats.rgba(x, y), start.rgba(x, y));
                if splat[3] == 0.0 {
                    continue;
                }
                let is_entry = (0..3).all(|c| (got[c] as f64 - entry.u0[c]).abs() < 1e-4) && got[3] == 1.0;
                match square_inside(x as i64, y as i64) {
                    Some(false) => {
                        assert!(
                            is_entry,
                            "frame {f}, pixel ({x}, {y}) near the silhouette: start {got:?}, entry {:?}",
                            entry.u0
                        );
                        overridden += (splat != got) as usize;
                    }
                    Some(true) => {
                        assert_eq!(splat, got, "frame {f}, pixel ({x}, {y}) inside: the splat is its start");
                        kept += 1;
                    }
                    None => {}
                }
            }
        }
    }
    assert!(overridden > 0 && kept > 1000, "{overridden} splats near the silhouette replaced, {kept} kept");
}

#[test]
fn scattered_splats_are_the_rasterized_quads() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    for (volume, tf, iso) in smooth_datasets() {
        let lut = tf.to_lut_for(&volume, 256);
        for (size, block) in [(4u64, 2u64), (1, 1), (3, 1)] {
            let options = |method: &str| {
                reprojecting()
                    .with_scalar("iso_value", iso)
                    .with_param("splat", "method", method)
                    .with_param("splat", "splat_size", size)
                    .with_param("splat", "block", block)
            };
            let mut quads =
                Live::new(&gpu, &registry, "klein_2005/leap_iso_splats.ron", &volume, &lut, &options("quads"));
            let mut scatter =
                Live::new(&gpu, &registry, "klein_2005/leap_iso_splats.ron", &volume, &lut, &options("scatter"));
            for f in 0..4 {
                let cam = camera(10.0 + 3.0 * f as f64);
                quads.frame(&cam);
                scatter.frame(&cam);
                let (q, s) = (quads.resource("splat.start"), scatter.resource("splat.start"));
                let pixels = (q.width * q.height) as usize;
                let landed = (0..pixels).filter(|&i| q.data[4 * i + 3] > 0.0).count();
                // The same splats with the same depth test: the same start wherever a splat
                // landed, but for pixels whose centre lies on a quad's edge to within the
                // rasterizer's sub-pixel snapping (1/256 pixel: it may cover them or not where the
                // scatter's exact `ceil` does the other), whose start may then come from another
                // splat: at most 0.5 % of the pixels on the first splatted frame (28–70 of 16384
                // measured). Each graph keeps its own hits, so such a pixel may find its hit a
                // sample apart (a start past the surface reports the sample before it) and splat
                // it elsewhere the next frame: the differences carry over, changing by −2 to +32 pixels
                // (≤ 0.2 %) a frame in the runs measured, so 0.2 % more is allowed per frame.
                let differ = (0..pixels).filter(|&i| q.data[4 * i..4 * i + 4] != s.data[4 * i..4 * i + 4]).count();
                let allowed = 0.005 + 0.002 * (f as f64 - 1.0).max(0.0);
                assert!(
                    differ as f64 <= allowed * pixels as f64,
                    "{} k={size} b={block} frame {f}: {differ} of {pixels} starts differ ({landed} splatted)",
                    volume.name
                );
                assert!(f == 0 || landed > pixels / 20, "{} frame {f}: splats landed", volume.name);
            }
        }
    }
}

/// The keys of `reprojection_tiles`' buffer (shaders/common/reprojected_tiles.wgsl): none yet,
/// and "from the box".
const NO_BOUND_YET: u32 = 0;
const FROM_THE_BOX: u32 = u32::MAX;

/// The tile keys of the last frame (past the header: tile edge, tiles per row).
fn tile_keys(leap: &mut Live) -> Vec<u32> {
    let words = leap.buffer_words("bounds.tiles");
    let (edge, per_row) = (words[0], words[1]);
    if edge == 0 {
        return Vec::new();
    }
    let rows = SIZE.div_ceil(edge);
    words[2..2 + (per_row * rows) as usize].to_vec()
}

/// Whether every ray of the last frame started at the box: no reprojected hit bounded a tile.
fn started_at_the_box(leap: &mut Live) -> bool {
    tile_keys(leap).iter().all(|&k| k == NO_BOUND_YET || k == FROM_THE_BOX)
}

#[test]
fn a_new_transfer_function_an_isovalue_edit_and_a_camera_jump_start_from_the_box() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, _) = datasets().remove(0);
    let lut = tf.to_lut_for(&volume, 256);
    let options = reprojecting();
    let mut leap = Live::new(&gpu, &registry, "klein_2005/leap_iso.ron", &volume, &lut, &options);
    leap.frame(&camera(10.0));
    assert!(started_at_the_box(&mut leap), "the first frame starts at the box");
    leap.frame(&camera(11.0));
    assert!(!started_at_the_box(&mut leap), "the next frame leaps");

    // A new transfer function: the next frame starts at the box and shows the new TF.
    let other = TransferFunction::preset(Preset::Sparse, volume.value_range).to_lut_for(&volume, 256);
    let inputs = leap.runtime.plan().expect("plan").inputs.clone();
    leap.runtime.bind_scene(&inputs, &volume, &other).expect("binds");
    let after_tf = leap.frame(&camera(12.0));
    assert!(started_at_the_box(&mut leap), "a new TF leaves no stale start");
    let mut base = Live::new(&gpu, &registry, "klein_2005/baseline_iso.ron", &volume, &other, &options);
    assert_eq!(after_tf.data, base.frame(&camera(12.0)).data, "the frame after a TF change is the plain raycast");

    // An isovalue edit (a parameter of "march"): from the box again.
    leap.frame(&camera(13.0));
    assert!(!started_at_the_box(&mut leap));
    let edited = options.clone().with_scalar("iso_value", 0.45);
    let source = graph_source("klein_2005/leap_iso.ron");
    let plan = leap.runtime.compile("leap_iso.ron", &source, &registry, &edited).expect("compiles");
    leap.runtime.apply(plan, &registry).expect("applies");
    leap.frame(&camera(14.0));
    assert!(started_at_the_box(&mut leap), "an isovalue edit starts from the box");

    // A camera jump beyond the graph's 15° bound: from the box again; a small turn is not.
    leap.frame(&camera(15.0));
    leap.frame(&camera(25.0));
    assert!(!started_at_the_box(&mut leap), "a 10° turn keeps the estimates");
    leap.frame(&camera(50.0));
    assert!(started_at_the_box(&mut leap), "a 25° jump starts from the box");
}

/// The bypass of `live`'s graph after its last frame.
fn reprojection(live: &Live) -> volgraph_core::runtime::BypassStatus {
    let status = live.runtime.bypass_status();
    assert_eq!(status.len(), 1, "the Klein graphs have one bypass: {status:?}");
    status[0].clone()
}

#[test]
fn a_surface_at_the_box_bypasses_reprojection_and_a_deep_one_brings_it_back() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, iso) = datasets().remove(0);
    let lut = tf.to_lut_for(&volume, 256);
    for mode in ["iso", "dvr"] {
        // Isovalue 0 (every sample is at or above it) and an opaque TF over all values: every
        // ray stops at its first sample, nothing can be leapt over. Threshold 4 samples per pixel.
        let at_the_box =
            CompileOptions::new(SIZE, SIZE).with_scalar("iso_value", 0.0).with_scalar("reproject_below", 4.0);
        let (lo, hi) = volume.value_range;
        let opaque = TransferFunction {
            domain: (lo, hi),
            points: vec![
                ControlPoint { value: lo, color: [1.0, 1.0, 1.0], alpha: 1.0 },
                ControlPoint { value: hi, color: [1.0, 0.5, 0.2], alpha: 1.0 },
            ],
        }
        .to_lut_for(&volume, 256);
        let lut_at_box = if mode == "dvr" { &opaque } else { &lut };
        let graph = format!("klein_2005/leap_{mode}.ron");
        let mut leap = Live::new(&gpu, &registry, &graph, &volume, lut_at_box, &at_the_box);
        let mut base =
            Live::new(&gpu, &registry, &format!("klein_2005/baseline_{mode}.ron"), &volume, lut_at_box, &at_the_box);
        for f in 0..5 {
            let cam = camera(10.0 + f as f64);
            let (l, b) = (leap.frame(&cam), base.frame(&cam));
            let status = reprojection(&leap);
            // Frame 0 has no measure yet and runs everything; each later frame reads the last.
            assert_eq!(status.bypassed, f > 0, "{mode} frame {f}: {status:?}");
            if f > 0 {
                assert_eq!(status.measure, Some(0.0), "{mode} frame {f}: no ray can leap over a sample");
                let words = leap.buffer_words("bounds.tiles");
                assert!(words.iter().all(|&w| w == 0), "{mode} frame {f}: the left-out bounds read as zeros");
            }
            // Left out or not, the rays start at the box: the plain raycast's image, exactly.
            assert_eq!(l.data, b.data, "{mode} frame {f}: the bypassed graph draws the plain raycast");
        }
        let status = reprojection(&leap);
        assert_eq!((status.frames_bypassed, status.frames_run), (4, 1), "{mode}: {status:?}");

        // The isosurface inside the volume (for DVR a TF transparent over the lower 60 % of the
        // values): rays cross empty space first, the measure rises above the threshold and the
        // splats come back.
        let deep = at_the_box.clone().with_scalar("iso_value", iso);
        let plan = leap.runtime.compile(&graph, &graph_source(&graph), &registry, &deep).expect("compiles");
        if mode == "dvr" {
            let inputs = plan.inputs.clone();
            let hollow = tf.hidden_below(lo + 0.6 * (hi - lo)).to_lut_for(&volume, 256);
            leap.runtime.bind_scene(&inputs, &volume, &hollow).expect("binds");
        }
        leap.runtime.apply(plan, &registry).expect("applies");
        for f in 5..9 {
            leap.frame(&camera(10.0 + f as f64));
        }
        let status = reprojection(&leap);
        assert!(!status.bypassed, "{mode}: {status:?}");
        assert!(status.measure.is_some_and(|m| m > 4.0), "{mode}: rays cross empty space first: {status:?}");
        assert!(!started_at_the_box(&mut leap), "{mode}: the bounds are back");
    }
}

/// The view depth a tile key stands for (`depth_key` inverted).
fn key_depth(key: u32) -> f32 {
    f32::from_bits(!key)
}

/// Every tile's bound is at most the view depth of every hit of last frame that lands within
/// `margin` pixels of it (checked on the CPU in f64 from last frame's hits and this frame's
/// camera): rays start in front of everything last frame saw there. Tiles near the silhouette
/// start at the box; inside the footprint, tiles are bounded.
#[test]
fn a_tile_bound_lies_in_front_of_every_hit_reprojected_near_the_tile() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, iso) = tooth();
    let lut = tf.to_lut_for(&volume, 256);
    // The graphs' `margin`.
    let margin = 4.0;
    for mode in ["iso", "dvr"] {
        let options = reprojecting().with_scalar("iso_value", iso);
        let mut leap = Live::new(&gpu, &registry, &format!("klein_2005/leap_{mode}.ron"), &volume, &lut, &options);
        leap.frame(&camera(10.0));
        let hits = leap.resource("march.leap_hit");
        let cam = camera(13.0);
        leap.frame(&cam);
        let words = leap.buffer_words("bounds.tiles");
        let (edge, per_row) = (words[0], words[1]);
        assert_eq!((edge, per_row), (4, SIZE / 4), "{mode}: the header");
        let keys = &words[2..];
        let data = volgraph_core::runtime::CameraData::from_orbit(&cam, (SIZE, SIZE));
        let half = volume.half_extent_world();
        let (mut checked, mut bounded, mut from_box) = (0usize, 0usize, 0usize);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let h = hits.rgba(x, y);
                if h[3] == 0.0 {
                    continue;
                }
                let u = glam::DVec3::new(h[0] as f64, h[1] as f64, h[2] as f64);
                let world = (u - glam::DVec3::splat(0.5)) * 2.0 * half;
                let clip = data.clip_from_world * world.extend(1.0);
                if clip.w <= 0.0 {
                    continue;
                }
                let p = glam::DVec2::new(
                    (clip.x / clip.w + 1.0) * 0.5 * SIZE as f64,
                    (1.0 - clip.y / clip.w) * 0.5 * SIZE as f64,
                );
                let depth = (world - data.eye).dot(data.forward);
                // The pixels whose centre lies within the margin, less a hundredth of a pixel
                // (f32 and f64 may round a centre on the edge either way).
                let lo =
                    (p - glam::DVec2::splat(margin - 0.01) - glam::DVec2::splat(0.5)).ceil().max(glam::DVec2::ZERO);
                let hi = (p + glam::DVec2::splat(margin - 0.01) - glam::DVec2::splat(0.5))
                    .floor()
                    .min(glam::DVec2::splat(SIZE as f64 - 1.0));
                if lo.x > hi.x || lo.y > hi.y {
                    continue;
                }
                for ty in (lo.y as u32 / edge)..=(hi.y as u32 / edge) {
                    for tx in (lo.x as u32 / edge)..=(hi.x as u32 / edge) {
                        let key = keys[(ty * per_row + tx) as usize];
                        checked += 1;
                        if key == FROM_THE_BOX {
                            continue;
                        }
                        assert_ne!(key, NO_BOUND_YET, "{mode}: tile ({tx}, {ty}) has a hit nearby but no bound");
                        // f32 depths of a few world units: a few ulps.
                        let bound = key_depth(key) as f64;
                        assert!(
                            bound <= depth + 1e-5 * depth.abs().max(1.0),
                            "{mode}: tile ({tx}, {ty}) bound {bound} behind a hit at depth {depth}"
                        );
                    }
                }
            }
        }
        for &k in &keys[..(per_row * per_row) as usize] {
            bounded += (k != NO_BOUND_YET && k != FROM_THE_BOX) as usize;
            from_box += (k == FROM_THE_BOX) as usize;
        }
        eprintln!("{mode}: {checked} hit-tile pairs checked, {bounded} tiles bounded, {from_box} from the box");
        assert!(checked > 1000 && bounded > 100 && from_box > 10, "{mode}: {checked} {bounded} {from_box}");
    }
}

/// The samples the march takes in the last frame, per pixel (`count_samples`).
fn samples_per_pixel(live: &mut Live) -> f64 {
    let words = live.buffer_words("march.samples");
    words.iter().map(|&w| w as f64).sum::<f64>() / f64::from(SIZE * SIZE)
}

/// What the bounds are for: on the tooth, turning 1° per frame, the march started from the tile
/// bounds takes under half the plain raycast's samples (measured at 128²: 40 % for the
/// isosurface, 44 % for DVR; at 512² on tooth256, where a tile and its margin are smaller
/// against the volume, 12 % and 14 %: 10.5 of 84.7 and 12.4 of 86.5 in bench/klein2005.md).
#[test]
fn tile_bounds_leap_most_of_the_empty_space_in_front_of_the_tooth() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, iso) = tooth();
    let lut = tf.to_lut_for(&volume, 256);
    for mode in ["iso", "dvr"] {
        let options = reprojecting().with_scalar("iso_value", iso).with_param("march", "count_samples", true);
        let mut base = Live::new(&gpu, &registry, &format!("klein_2005/baseline_{mode}.ron"), &volume, &lut, &options);
        let mut leap = Live::new(&gpu, &registry, &format!("klein_2005/leap_{mode}.ron"), &volume, &lut, &options);
        for f in 0..4 {
            let cam = camera(10.0 + f as f64);
            base.frame(&cam);
            leap.frame(&cam);
        }
        let (b, l) = (samples_per_pixel(&mut base), samples_per_pixel(&mut leap));
        eprintln!("{mode}: {b:.2} samples per pixel plain, {l:.2} from the tile bounds");
        assert!(b > 5.0 && l < 0.5 * b, "{mode}: {l} of {b} samples per pixel");
    }
}

#[test]
fn the_leapable_measure_counts_what_a_perfect_estimate_would_skip() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, _, _) = datasets().remove(0);
    // A transfer function transparent everywhere: no sample is visible, so a perfect estimate
    // (the exit point) would skip every sample of the ray but the `step_back` = 2 before it.
    // The march counts one pixel of each 4×4 block, ×16.
    let (lo, hi) = volume.value_range;
    let clear = |value| ControlPoint { value, color: [1.0, 1.0, 1.0], alpha: 0.0 };
    let lut = TransferFunction { domain: (lo, hi), points: vec![clear(lo), clear(hi)] }.to_lut_for(&volume, 256);
    let mut leap = Live::new(&gpu, &registry, "klein_2005/leap_dvr.ron", &volume, &lut, &reprojecting());
    let cam = camera(20.0);
    leap.frame(&cam);
    leap.frame(&cam);
    let measured = reprojection(&leap).measure.expect("measured after two frames");
    let frame = cam.frame(SIZE, SIZE);
    let (mut expected, mut rays) = (0.0, 0.0);
    for y in (0..SIZE).step_by(4) {
        for x in (0..SIZE).step_by(4) {
            let Some(seg) = volgraph_accel::reference::ray_segment(&volume, &cam, &frame, x, y) else { continue };
            let step = volgraph_accel::reference::step_tex(&volume, seg.d_tex, 0.5);
            // `samples_along`: the samples (k + 0.5)·step inside the ray.
            let count = (seg.len_tex / step - 0.5).ceil().max(0.0);
            expected += 16.0 * (count - count.min(2.0));
            rays += 1.0;
        }
    }
    let pixels = f64::from(SIZE * SIZE);
    expected /= pixels;
    // f32 and f64 may put a ray's last sample on either side of its exit: one sample per
    // counted ray, ×16.
    let tolerance = 16.0 * rays / pixels;
    eprintln!("leapable: GPU {measured:.2} per pixel, CPU {expected:.2} (± {tolerance:.2}), {rays} lattice rays");
    assert!(rays > 50.0, "the volume is in view");
    assert!((measured - expected).abs() <= tolerance, "GPU {measured} vs CPU {expected} ± {tolerance}");
}

/// Pixels whose colour differs from a 4-neighbour (clamped at the border) by more than
/// `contrast` in some channel: the antialias pass's own test, on the same f32 values.
fn flagged_pixels(color: &Image, contrast: f32) -> Vec<bool> {
    let (w, h) = (color.width as i64, color.height as i64);
    let at = |x: i64, y: i64| color.rgba(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let c = at(x, y);
            let differs = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| (0..4).any(|i| (at(x + dx, y + dy)[i] - c[i]).abs() > contrast));
            out.push(differs);
        }
    }
    out
}

#[test]
fn selective_super_sampling_equals_full_super_sampling_on_the_flagged_pixels() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    for (volume, tf, iso) in datasets() {
        let lut = tf.to_lut_for(&volume, 256);
        for pattern in ["2x", "4x", "rgss"] {
            let options = |selection: &str| {
                CompileOptions::new(SIZE, SIZE)
                    .with_scalar("iso_value", iso)
                    .with_param("aa", "pattern", pattern)
                    .with_param("aa", "selection", selection)
            };
            let mut selective =
                Live::new(&gpu, &registry, "klein_2005/leap_iso_aa.ron", &volume, &lut, &options("selective"));
            let mut full = Live::new(&gpu, &registry, "klein_2005/leap_iso_aa.ron", &volume, &lut, &options("full"));
            // Three frames: the last starts its sub-pixel rays from reprojected leap hits.
            for f in 0..3 {
                let cam = camera(30.0 + 2.0 * f as f64);
                let (s, u) = (selective.frame(&cam), full.frame(&cam));
                let raw = selective.runtime.read_output("raw").expect("raw");
                let flags = flagged_pixels(&raw, 0.05);
                let flagged = flags.iter().filter(|&&f| f).count();
                assert!(flagged > 0, "{} {pattern}: some pixels are flagged", volume.name);
                let mut refined = 0;
                for y in 0..SIZE {
                    for x in 0..SIZE {
                        let expected = if flags[(y * SIZE + x) as usize] { u.rgba(x, y) } else { raw.rgba(x, y) };
                        assert_eq!(
                            s.rgba(x, y),
                            expected,
                            "{} {pattern} frame {f} pixel ({x}, {y}): selective = full where flagged, the raycast elsewhere",
                            volume.name
                        );
                        refined += (s.rgba(x, y) != raw.rgba(x, y)) as usize;
                    }
                }
                assert!(refined > 0, "{} {pattern}: super-sampling changes the flagged pixels", volume.name);
            }
        }
    }
}

/// Root-mean-square difference over all channels, in units of 1/255 (the project's one metric,
/// `volgraph_accel::image_diff`; a NaN makes it infinite).
fn rms_255(image: &Image, reference: &[[f64; 4]]) -> f64 {
    let d = volgraph_accel::image_diff::image_diff(&image.to_rgba_f64(), reference).expect("same size");
    if d.non_finite > 0 { f64::INFINITY } else { d.rms * 255.0 }
}

#[test]
fn super_sampling_moves_the_image_towards_the_16x_reference() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let (volume, tf, iso) = datasets().remove(0);
    let lut = tf.to_lut_for(&volume, 256);
    let cam = camera(35.0);
    // The reference: the f64 model at 4×4 sub-pixel positions per pixel, box-filtered.
    let settings = RaycastSettings {
        mode: RenderMode::Isosurface { iso, shading: Phong::default() },
        ..RaycastSettings::default()
    };
    let reference = render_supersampled(&volume, &lut, &cam, SIZE, SIZE, 4, &settings);
    for (pattern, selection) in [("4x", "full"), ("rgss", "selective"), ("rgss", "full")] {
        let options = CompileOptions::new(SIZE, SIZE)
            .with_scalar("iso_value", iso)
            .with_param("aa", "pattern", pattern)
            .with_param("aa", "selection", selection);
        let mut aa = Live::new(&gpu, &registry, "klein_2005/leap_iso_aa.ron", &volume, &lut, &options);
        let image = aa.frame(&cam);
        let raw = aa.runtime.read_output("raw").expect("raw");
        let (none, with) = (rms_255(&raw, &reference), rms_255(&image, &reference));
        eprintln!("{pattern} {selection}: rms {with:.2}/255 against the 16× reference, without AA {none:.2}/255");
        // The 1-sample image aliases along every silhouette; 4 sub-pixel rays must take away a
        // good part of that error (the rest: the reference's 16 rays per pixel vs 4).
        assert!(with < 0.8 * none, "{pattern} {selection}: {with:.2} vs {none:.2} without antialiasing");
    }
}
