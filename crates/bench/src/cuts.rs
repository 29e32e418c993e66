//! `volgraph bench cuts`: what a crop box or clip plane does to the frame time (issue 24 §3: "a
//! crop makes rendering faster, not slower"). One graph on one dataset, the whole volume beside
//! crops and clips of it, timed side by side in one run on one runtime; each case renders a
//! warm-up frame (its pipelines compile with the cut's code), then `frames` frames turning 1°
//! each, and the median GPU ms is compared with the uncut volume's.

use std::path::PathBuf;

use anyhow::{Context as _, anyhow};
use glam::DVec3;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};
use volgraph_core::runtime::{Gpu, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{compile, cut_effects};

use crate::graphs::measure::{median, time_frames};

/// `bench cuts` arguments.
#[derive(clap::Args, Debug)]
pub struct CutsArgs {
    /// Dataset of `$VOLGRAPH_DATA/volumes` by name.
    #[arg(long, default_value = "engine")]
    pub dataset: String,
    /// The graph: a file or a built-in name.
    #[arg(long, default_value = "modern/fastest")]
    pub graph: PathBuf,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// Timed frames per case (the median is reported).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the table as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// The cases: the whole volume, crops to an eighth (a corner and the centre), to a half, and
/// a clip plane that keeps half.
fn cases() -> anyhow::Result<Vec<(&'static str, Cuts)>> {
    let crop = |lo: f64, hi: f64| CropBox::new(DVec3::splat(lo), DVec3::splat(hi));
    let half_x = CropBox::new(DVec3::ZERO, DVec3::new(0.5, 1.0, 1.0))?;
    let oblique = ClipPlane::new(DVec3::new(1.0, 1.0, 1.0), 1.5)?;
    Ok(vec![
        ("whole volume", Cuts::NONE),
        ("crop to 1/8 (corner)", Cuts::new(Some(crop(0.0, 0.5)?), &[])?),
        ("crop to 1/8 (centre)", Cuts::new(Some(crop(0.25, 0.75)?), &[])?),
        ("crop to 1/2 (x < 0.5)", Cuts::new(Some(half_x), &[])?),
        ("clip plane (x+y+z >= 1.5)", Cuts::new(None, &[oblique])?),
    ])
}

/// Runs the benchmark, prints the table and returns the JSON rows.
pub fn run(args: &CutsArgs) -> anyhow::Result<serde_json::Value> {
    let loaded = volgraph_accel::data_dir::load_dataset(&args.dataset)
        .with_context(|| format!("dataset \"{}\" (set VOLGRAPH_DATA)", args.dataset))?;
    let volume = loaded.volume;
    let (tf, _) = volgraph_app::inputs::transfer_function(None, None, &volume, false)?;
    let lut = tf.to_lut_for(&volume, volgraph_app::inputs::LUT_SIZE);
    let source = volgraph_app::inputs::read_graph(&args.graph)?;
    let registry = volgraph_app::program::registry();
    let gpu = std::sync::Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(volgraph_passes::builtin_shaders()));
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.2, ..OrbitCamera::default() };
    let mut rows = Vec::new();
    for (name, cuts) in cases()? {
        let mut options = volgraph_app::cli::compile_options(&args.size, &[], &[])?;
        options.features.extend(cut_effects::features_of(&cuts));
        options.scene = scene_values_of(&VolumeDesc::of(&volume));
        options.scene.extend(volgraph_app::inputs::data_scene_values(&volume));
        let plan =
            compile(&args.graph.display().to_string(), &source, &registry, &options).map_err(|d| anyhow!("{d}"))?;
        runtime.set_cuts(cuts);
        runtime.bind_scene(&plan.inputs, &volume, &lut).map_err(|e| anyhow!(e))?;
        runtime.apply(plan, &registry).map_err(|e| anyhow!(e))?;
        let timing = time_frames(&mut runtime, &camera, 1.0, args.frames, || {}).map_err(|e| anyhow!(e))?;
        let kept = cuts.crop().map_or(1.0, |c| c.volume_fraction());
        rows.push((name, kept, cuts.planes().count(), median(&timing.frame_ms), timing.wall_time_fallback));
    }
    let whole = rows.first().map_or(1.0, |r| r.3);
    let clock = if rows.iter().any(|r| r.4) { "wall" } else { "GPU" };
    let mut table = format!(
        "# Crop and clip: ms/frame vs the whole volume\n\n{} on {} ({}×{}×{} voxels), {} at {}, {} timed \
         frames per case (median, {clock} time), measured side by side in one run on {adapter}.\n\n\
         | case | crop keeps | clip planes | ms/frame | vs whole |\n|---|---:|---:|---:|---:|\n",
        args.graph.display(),
        args.dataset,
        volume.dims.x,
        volume.dims.y,
        volume.dims.z,
        "the fitted TF",
        args.size,
        args.frames
    );
    let mut json = Vec::new();
    for (name, kept, planes, ms, _) in &rows {
        table.push_str(&format!("| {name} | {kept:.3} | {planes} | {ms:.2} | {:.2}× |\n", ms / whole));
        json.push(serde_json::json!({
            "case": name, "crop_keeps": kept, "clip_planes": planes, "ms_per_frame": ms, "ratio_to_whole": ms / whole,
        }));
    }
    println!("{table}");
    let value = serde_json::json!({
        "graph": args.graph.display().to_string(), "dataset": args.dataset, "size": args.size,
        "frames": args.frames, "adapter": adapter, "clock": clock, "rows": json,
    });
    crate::report_files::write_markdown_and_json((args.markdown.as_deref(), &table), (args.json.as_deref(), &value))?;
    Ok(value)
}
