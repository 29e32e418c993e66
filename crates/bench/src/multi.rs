//! `volgraph bench multi`: several volumes in one march (issue "several volumes", "Measured"),
//! side by side in one run on one runtime:
//! - `multi/ct_with_labels` (smooth and nearest labels) and `multi/ct_inside_labels` on the
//!   generated abdominal CT (`organs<N>`, HU) with a 117-label map, against `modern/fastest` on
//!   the CT alone (goal ≤ 1.5× its time), each against the f64 reference (every `stride`-th
//!   pixel of each row and column);
//! - a label's visibility toggled (its table entry hidden and shown again) → the first frame
//!   showing it finished on the GPU, at `--toggle-size` (goal ≤ 50 ms), at full resolution and
//!   as the viewer shows it (`multi_toggle`: coarse until input rests);
//! - label boundaries at 4× zoom, smooth against nearest, each against the converged boundary:
//!   the f64 reference of the same spheres voxelized 4× finer.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::fusion::{Combine, Fusion, TextureMap};
use volgraph_accel::labels::LabelTable;
use volgraph_accel::labels::sample::LabelFilter;
use volgraph_accel::reference::fused_pixel;
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::graph::ast::InputKind;
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{Params, compile};
use volgraph_passes::fusion::{FusionSettings, LabelFilterChoice};
use volgraph_passes::raycast_params::reference_settings;

use crate::graphs::measure::{median, time_frames};

/// `bench multi` arguments.
#[derive(clap::Args, Debug)]
pub struct MultiArgs {
    /// Edge of the generated CT (`organs<N>`: N × N × N/2 voxels of 1 × 1 × 2 mm).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=1024))]
    pub voxels: u32,
    /// Labels of the generated label map (TotalSegmentator writes 117).
    #[arg(long, default_value_t = 117, value_parser = clap::value_parser!(u32).range(1..=65_535))]
    pub labels: u32,
    /// Viewport of the timed cases, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Viewport of the label toggle, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600")]
    pub toggle_size: String,
    /// Timed frames per case and toggles (the median is reported).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// Compare every STRIDE-th pixel of each row and column with the f64 reference.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub stride: u32,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the tables as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

const CAMERA: OrbitCamera = OrbitCamera {
    azimuth_deg: 35.0,
    elevation_deg: 25.0,
    distance: 2.6,
    fov_y_deg: 30.0,
    near: 0.01,
    far: 100.0,
    target: [0.0; 3],
    up: volgraph_accel::camera::CameraUp::Y,
};

/// A label map of `labels` regions over the body of `ct` (HU > −500): each body voxel takes the
/// nearest of `labels` seeds spread over the body (a Voronoi partition: many boundaries, the
/// hard case for smooth sampling), 0 outside. Deterministic.
pub fn body_labels(ct: &Volume, labels: u32) -> Volume {
    let n = ct.dims;
    let inside = |i: usize| ct.raw_value(i) > -500.0;
    let body: Vec<usize> = (0..ct.voxel_count()).filter(|&i| inside(i)).collect();
    let position = |i: usize| {
        let (x, y, z) = (i as u32 % n.x, (i as u32 / n.x) % n.y, i as u32 / (n.x * n.y));
        DVec3::new(x as f64, y as f64, z as f64) * ct.spacing
    };
    // Seeds: body voxels at a golden-ratio stride through the list (spread, deterministic).
    let seeds: Vec<DVec3> = (0..labels as usize)
        .map(|k| position(body[((k as f64 * 0.618_033_988_75).fract() * body.len() as f64) as usize]))
        .collect();
    let data: Vec<u16> = (0..ct.voxel_count())
        .map(|i| {
            if !inside(i) {
                return 0;
            }
            let p = position(i);
            let nearest = (0..seeds.len())
                .min_by(|&a, &b| p.distance_squared(seeds[a]).total_cmp(&p.distance_squared(seeds[b])))
                .unwrap_or(0);
            nearest as u16 + 1
        })
        .collect();
    let mut map = Volume::new(format!("{labels} labels"), n, ct.spacing, VoxelData::U16(data));
    map.meta.frame = ct.meta.frame.clone();
    map.meta.origin = ct.meta.origin;
    map
}

/// One runtime, its GPU, and what a case binds.
struct Bench {
    runtime: Runtime,
    registry: volgraph_core::Registry,
    adapter: String,
}

/// What a case renders: a graph (built-in name), parameter overrides of its march, the size.
struct Case<'a> {
    name: &'a str,
    graph: &'a str,
    set: &'a [(&'a str, &'a str)],
}

/// The inputs: the CT and its LUT, the label map and its table.
struct Scene<'a> {
    ct: &'a Volume,
    lut: &'a [[f32; 4]],
    labels: &'a Volume,
    table: &'a [[f32; 4]],
}

impl Bench {
    /// Compiles `case` at `size`, binds `scene` by input kind and applies it; returns the march's
    /// parameters.
    fn apply(&mut self, case: &Case<'_>, scene: &Scene<'_>, size: &str) -> anyhow::Result<Params> {
        let source = volgraph_app::inputs::read_graph(&PathBuf::from(case.graph))?;
        let mut options = volgraph_app::cli::compile_options(size, &[], &[])?;
        for (name, value) in case.set {
            options = options.with_param("march", name, *value);
        }
        options.scene = scene_values_of(&VolumeDesc::of(scene.ct));
        let plan = compile(case.graph, &source, &self.registry, &options).map_err(|d| anyhow!("{d}"))?;
        for (name, kind) in &plan.inputs {
            match kind {
                InputKind::Volume if name == "volume" => self.runtime.bind_volume(name, scene.ct),
                InputKind::Volume => self.runtime.bind_volume(name, scene.labels),
                InputKind::TransferFunction => self.runtime.bind_lut(name, scene.lut),
                InputKind::LabelTable => self.runtime.bind_label_table(name, scene.table),
                InputKind::Scalar(_) | InputKind::Data(_) => Ok(false),
            }
            .map_err(|e| anyhow!(e))?;
        }
        let march = plan.steps.iter().find(|s| s.pass_id == "march").map(|s| s.params.clone());
        self.runtime.apply(plan, &self.registry).map_err(|e| anyhow!(e))?;
        march.ok_or_else(|| anyhow!("{}: no pass \"march\"", case.graph))
    }
}

/// (mean, max) abs difference per channel between `image` and the f64 reference at every
/// `stride`-th pixel of each row and column.
fn sparse_error(image: &Image, scene: &Scene<'_>, march: &Params, stride: u32) -> (f64, f64) {
    let settings = reference_settings(march);
    let fusion = FusionSettings::of(march);
    let filter = match fusion.label_filter {
        LabelFilterChoice::Smooth => LabelFilter::Smooth,
        LabelFilterChoice::Nearest => LabelFilter::Nearest,
    };
    let map = TextureMap::between(scene.ct, scene.labels).unwrap_or(TextureMap::IDENTITY);
    let model = fusion.combine().map(|combine| Fusion {
        combine,
        label_lut: scene.table,
        filter,
        second: Some((scene.labels, scene.table, map)),
        more: &[],
        overlay: None,
    });
    let frame = CAMERA.frame(image.width, image.height);
    let pixels: Vec<(u32, u32)> = (0..image.height)
        .step_by(stride as usize)
        .flat_map(|y| (0..image.width).step_by(stride as usize).map(move |x| (x, y)))
        .collect();
    use rayon::prelude::*;
    let diffs: Vec<f64> = pixels
        .par_iter()
        .map(|&(x, y)| {
            let (c, _, _) = fused_pixel(scene.ct, scene.lut, model.as_ref(), &CAMERA, &frame, (x, y), &settings);
            let g = image.rgba(x, y);
            (0..4).map(|k| (g[k] as f64 - c[k]).abs()).fold(0.0, f64::max)
        })
        .collect();
    let mean = diffs.iter().sum::<f64>() / diffs.len().max(1) as f64;
    (mean, diffs.iter().copied().fold(0.0, f64::max))
}

/// Runs the benchmark, prints the tables and returns the JSON.
pub fn run(args: &MultiArgs) -> anyhow::Result<serde_json::Value> {
    let ct = volgraph_accel::organs::organs_ct(args.voxels);
    let labels = body_labels(&ct, args.labels);
    let (tf, _) = volgraph_app::inputs::transfer_function(Some(&PathBuf::from("ct-soft-tissue")), None, &ct, false)
        .context("the ct-soft-tissue preset")?;
    let lut = tf.to_lut_for(&ct, volgraph_app::inputs::LUT_SIZE);
    let mut table = LabelTable::default_for(1..=args.labels);
    for label in table.labels.values_mut() {
        // Tint strength: the scan shows through the label's colour.
        label.opacity = 0.6;
    }
    let table_lut = table.lut(args.labels as usize + 1);
    let scene = Scene { ct: &ct, lut: &lut, labels: &labels, table: &table_lut };
    // The organs' own map (what an organ segmentation looks like: large regions, few
    // boundaries), tinted as strongly.
    let organs = volgraph_accel::organs::organs_labels(args.voxels);
    let mut organ_table = volgraph_accel::organs::label_table();
    for label in organ_table.labels.values_mut() {
        label.opacity = 0.6;
    }
    let organ_lut = organ_table.lut(organ_table.labels.keys().max().map_or(1, |m| *m as usize + 1));
    let organ_scene = Scene { ct: &ct, lut: &lut, labels: &organs, table: &organ_lut };
    let gpu = std::sync::Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let runtime = Runtime::new(gpu.clone(), ShaderLibrary::new(volgraph_passes::builtin_shaders()));
    let mut bench = Bench { runtime, registry: volgraph_app::program::registry(), adapter };
    let organ_cases = format!("{} organs' map", organ_table.labels.len());
    let cases = [
        (Case { name: "CT alone (modern/fastest)", graph: "modern/fastest", set: &[] }, &scene),
        (Case { name: "ct_with_labels, smooth", graph: "multi/ct_with_labels", set: &[] }, &scene),
        (
            Case {
                name: "ct_with_labels, nearest",
                graph: "multi/ct_with_labels",
                set: &[("label_filter", "nearest")],
            },
            &scene,
        ),
        (Case { name: "ct_inside_labels, smooth", graph: "multi/ct_inside_labels", set: &[] }, &scene),
        (
            Case { name: "ct_with_labels, smooth, the organs' map", graph: "multi/ct_with_labels", set: &[] },
            &organ_scene,
        ),
        (
            Case { name: "ct_inside_labels, smooth, the organs' map", graph: "multi/ct_inside_labels", set: &[] },
            &organ_scene,
        ),
    ];
    let mut rows = Vec::new();
    for (case, scene) in &cases {
        let march = bench.apply(case, scene, &args.size)?;
        let timing = time_frames(&mut bench.runtime, &CAMERA, 0.0, args.frames, || {}).map_err(|e| anyhow!(e))?;
        let image = bench.runtime.read_output("image").map_err(|e| anyhow!(e))?;
        let (mean, max) = sparse_error(&image, scene, &march, args.stride);
        rows.push((case.name, median(&timing.frame_ms), timing.wall_time_fallback, mean, max));
    }
    let toggle = time_toggle(&mut bench, &scene, &table, args)?;
    let viewport = volgraph_app::inputs::parse_size(&args.toggle_size)?;
    let in_viewer = crate::multi_toggle::time_in_viewer(&gpu, (&ct, &labels, &table), viewport, &CAMERA, args.frames)?;
    let quality = boundary_quality(&mut bench)?;
    let base = rows.first().map_or(1.0, |r| r.1);
    let clock = if rows.iter().any(|r| r.2) { "wall" } else { "GPU" };
    let mut text = format!(
        "# Several volumes in one march\n\nThe generated abdominal CT organs{} ({}×{}×{} voxels, HU, ct-soft-tissue) \
         and a {}-label map on its grid (u16: the body cut into that many Voronoi regions, every one bounded by \
         others — the hard case), or, in the last rows, the {organ_cases} (u8: the organs' own regions, large \
         and few), at {}, {} frames per case (median, {clock} time), side by side in one run on {}. A device with \
         subgroups ({}) takes the samples of a stretch inside one label without reading the map \
         (common/label_cubes.wgsl). Error: max abs channel difference to the f64 reference at every {}th pixel of \
         each row and column (mean and max over them, in 1/255).\n\n\
         | case | ms/frame | vs CT alone | mean err (1/255) | max err (1/255) |\n|---|---:|---:|---:|---:|\n",
        args.voxels,
        ct.dims.x,
        ct.dims.y,
        ct.dims.z,
        args.labels,
        args.size,
        args.frames,
        bench.adapter,
        if gpu.subgroups { "this one has" } else { "not this one" },
        args.stride
    );
    let mut json_rows = Vec::new();
    for (name, ms, _, mean, max) in &rows {
        text.push_str(&format!(
            "| {name} | {ms:.2} | {:.2}× | {:.3} | {:.2} |\n",
            ms / base,
            mean * 255.0,
            max * 255.0
        ));
        json_rows.push(serde_json::json!({
            "case": name, "ms_per_frame": ms, "ratio_to_ct_alone": ms / base,
            "mean_error": mean, "max_error": max,
        }));
    }
    text.push_str(&format!(
        "\nToggling a label's visibility (its table entry hidden or shown, the table uploaded) → the first frame \
         showing it finished on the GPU, ct_with_labels at {}: median {:.1} ms over {} toggles, of which the \
         toggle's own work (the table made and uploaded; no recompile, no reclassification) {:.2} ms and the \
         frame the rest (a steady frame: {:.1} ms; goal ≤ 50 ms).\n",
        args.toggle_size, toggle.0, args.frames, toggle.2, toggle.1
    ));
    text.push_str(&format!(
        "\nThe same toggle in the viewer's session (`LiveSession`, no window; the CT and label map opened as \
         MetaImage files, the table as an ITK-SNAP file), where a label shown or hidden counts as motion for the \
         level of detail as a dragged TF point does: the first frame showing it is coarse ({:.2} per axis, step \
         ×{}), the full image follows once input rests.\n\n| {} | ms |\n|---|---:|\n\
         | steady full frame | {:.1} |\n\
         | toggle at rest → first frame showing it (table upload, switch to the coarse image, frame; goal ≤ 50 ms) | {:.1} |\n\
         | toggle with the coarse image on screen → its frame | {:.1} |\n\
         | input at rest → full image finished | {:.1} |\n",
        in_viewer.scale,
        in_viewer.step,
        args.toggle_size,
        in_viewer.full_ms,
        in_viewer.from_rest_ms,
        in_viewer.while_coarse_ms,
        in_viewer.refined_ms
    ));
    text.push_str(&format!(
        "\nLabel boundaries at 4× zoom (multi/labels, three spheres voxelized at 48³, 256²): mean abs error \
         against the converged boundary (the f64 reference of the spheres voxelized at 192³), in 1/255 — smooth \
         {:.2}, nearest {:.2} ({:.1}× less with smooth).\n",
        quality.0 * 255.0,
        quality.1 * 255.0,
        quality.1 / quality.0.max(1e-12)
    ));
    println!("{text}");
    let value = serde_json::json!({
        "voxels": args.voxels, "labels": args.labels, "size": args.size, "frames": args.frames,
        "adapter": bench.adapter, "clock": clock, "subgroups": gpu.subgroups, "rows": json_rows,
        "toggle": {"size": args.toggle_size, "median_ms": toggle.0, "steady_ms": toggle.1, "upload_ms": toggle.2},
        "toggle_in_viewer": in_viewer,
        "boundary_quality": {"smooth_mean_error": quality.0, "nearest_mean_error": quality.1},
    });
    crate::report_files::write_markdown_and_json((args.markdown.as_deref(), &text), (args.json.as_deref(), &value))?;
    Ok(value)
}

/// (median ms from a label's visibility toggled to its frame finished, median steady frame ms,
/// median ms of the toggle's own work: the table made and uploaded).
fn time_toggle(
    bench: &mut Bench,
    scene: &Scene<'_>,
    table: &LabelTable,
    args: &MultiArgs,
) -> anyhow::Result<(f64, f64, f64)> {
    let case = Case { name: "toggle", graph: "multi/ct_with_labels", set: &[] };
    bench.apply(&case, scene, &args.toggle_size)?;
    let viewport = bench.runtime.plan().ok_or_else(|| anyhow!("no plan"))?.viewport;
    let steady = time_frames(&mut bench.runtime, &CAMERA, 0.0, args.frames, || {}).map_err(|e| anyhow!(e))?;
    let mut toggled = table.clone();
    let (mut times, mut uploads) = (Vec::new(), Vec::new());
    for k in 0..args.frames {
        // Label 1 hidden on odd toggles, shown on even ones.
        if let Some(l) = toggled.labels.get_mut(&1) {
            l.visible = k % 2 == 0;
        }
        let t0 = Instant::now();
        let lut = toggled.lut(scene.table.len());
        bench.runtime.bind_label_table("label_table", &lut).map_err(|e| anyhow!(e))?;
        uploads.push(t0.elapsed().as_secs_f64() * 1e3);
        bench.runtime.render(CameraData::from_orbit(&CAMERA, viewport)).map_err(|e| anyhow!(e))?;
        bench.runtime.finish();
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok((median(&times), median(&steady.wall_ms), median(&uploads)))
}

/// Three spheres of labels 1, 2, 3 (touching, so two boundaries lie between labels) at edge `n`.
fn spheres(n: u32) -> Volume {
    let centres = [
        (DVec3::new(0.38, 0.5, 0.5), 0.2, 1u8),
        (DVec3::new(0.62, 0.5, 0.5), 0.18, 2),
        (DVec3::new(0.5, 0.66, 0.45), 0.14, 3),
    ];
    let mut data = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / n as f64;
                data.push(centres.iter().find(|(c, r, _)| p.distance(*c) < *r).map_or(0, |s| s.2));
            }
        }
    }
    let mut v =
        Volume::new(format!("spheres{n}"), UVec3::splat(n), DVec3::splat(192.0 / n as f64), VoxelData::U8(data));
    v.value_range = (0.0, 255.0);
    v
}

/// (smooth, nearest): mean abs error of `multi/labels` at 4× zoom on spheres at 48³ against the
/// f64 reference of the spheres at 192³ (smooth), the converged boundary.
fn boundary_quality(bench: &mut Bench) -> anyhow::Result<(f64, f64)> {
    let (coarse, fine) = (spheres(48), spheres(192));
    let table = LabelTable::default_for([1, 2, 3]).lut(4);
    let zoomed = OrbitCamera { fov_y_deg: CAMERA.fov_y_deg / 4.0, distance: 2.2, ..CAMERA };
    let mut errors = Vec::new();
    let settings_for = |march: &Params| reference_settings(march);
    let mut converged = None;
    for filter in ["smooth", "nearest"] {
        let scene = Scene { ct: &coarse, lut: &[[0.0; 4]; 2], labels: &coarse, table: &table };
        let case = Case { name: filter, graph: "multi/labels", set: &[("label_filter", filter)] };
        let march = bench.apply(&case, &scene, "256x256")?;
        let viewport = bench.runtime.plan().ok_or_else(|| anyhow!("no plan"))?.viewport;
        bench.runtime.render(CameraData::from_orbit(&zoomed, viewport)).map_err(|e| anyhow!(e))?;
        let image = bench.runtime.read_output("image").map_err(|e| anyhow!(e))?;
        let reference = converged.get_or_insert_with(|| {
            let model = Fusion {
                combine: Combine::Labels,
                label_lut: &table,
                filter: LabelFilter::Smooth,
                second: None,
                more: &[],
                overlay: None,
            };
            volgraph_accel::reference::render_fused_reference(
                &fine,
                &[[0.0; 4]; 2],
                Some(&model),
                &zoomed,
                256,
                256,
                &settings_for(&march),
            )
            .color
        });
        let d = volgraph_accel::image_diff::image_diff(&image.to_rgba_f64(), reference).map_err(|e| anyhow!(e))?;
        errors.push(d.mean_abs);
    }
    Ok((errors[0], errors[1]))
}
