//! `volgraph bench fetch`: the fetch ceiling of this device — trilinear volume samples per
//! second of a pass that takes every sample a raycaster would (the analytic rays of
//! `raycast_compute` with `rays: "analytic"`, same step, same volume texture format) and does nothing else with them
//! (`graphs/bench/fetch_ceiling.ron`, pass `fetch_probe`). Samples are counted on the GPU; time
//! is the median frame over views turning about y. `volgraph bench graphs` measures the same
//! ceiling for each dataset and viewport it times and reports every graph's counted samples per
//! second as a fraction of it.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::anyhow;
use serde::Serialize;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{Gpu, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Diagnostics, Registry};

use crate::graphs::dataset;
use crate::graphs::gpu_count;
use crate::graphs::measure::{self, frame_camera, median};
use volgraph_app::inputs;

/// The probe graph, compiled in so the command works from any directory.
pub const FETCH_GRAPH: &str = include_str!("../../../graphs/bench/fetch_ceiling.ron");
/// Its file name in messages.
pub const FETCH_GRAPH_FILE: &str = "graphs/bench/fetch_ceiling.ron";

/// Flags of `volgraph bench fetch`.
#[derive(clap::Args, Debug, Clone)]
pub struct FetchArgs {
    /// Datasets, comma separated (as for `bench graphs`: names in $VOLGRAPH_DATA/volumes or
    /// generated volumes such as ml128).
    #[arg(long, value_delimiter = ',', default_value = "hydrogen_atom,engine_vollib")]
    pub datasets: Vec<String>,
    /// Viewports WIDTHxHEIGHT, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "512x512")]
    pub size: Vec<String>,
    /// Sample distance in voxels.
    #[arg(long, default_value_t = 0.5)]
    pub step: f64,
    /// Timed frames per case after one warm-up frame; they cover a full turn about y.
    #[arg(long, default_value_t = 12)]
    pub frames: u32,
    /// Orbit camera of the first frame, AZIMUTH,ELEVATION,DISTANCE (the peer comparison's).
    #[arg(long, default_value = "0,0,3.2")]
    pub camera: String,
    /// Write the report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also write the markdown table here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// The ceiling of one dataset and viewport.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Ceiling {
    /// Samples per pixel (counted on the GPU, middle view).
    pub samples_per_pixel: f64,
    /// Median ms per frame.
    pub median_ms: f64,
    /// Millions of trilinear samples per second.
    pub msamples_per_s: f64,
    /// Whether `median_ms` is wall time (no GPU timestamps covering compute work).
    pub wall_clock: bool,
}

/// One row of the report.
#[derive(Clone, Debug, Serialize)]
pub struct FetchRow {
    /// Dataset name.
    pub dataset: String,
    /// Volume dimensions.
    pub dims: [u32; 3],
    /// The volume texture's format on this device.
    pub texture_format: String,
    /// Viewport.
    pub viewport: [u32; 2],
    /// What was measured.
    pub ceiling: Ceiling,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct FetchReport {
    /// `"volgraph bench fetch"`.
    pub program: String,
    /// The adapter.
    pub adapter: String,
    /// Step in voxels.
    pub step_voxels: f64,
    /// Timed frames per case (a full turn).
    pub frames: u32,
    /// Start camera.
    pub camera: [f64; 3],
    /// Rows.
    pub rows: Vec<FetchRow>,
    /// Datasets that could not be measured, with the reason.
    pub skipped: Vec<String>,
}

/// Measures the fetch ceiling for `volume` (bound here as the `volume` input) at `viewport`:
/// frames from `camera` turning `degrees_per_frame` each, then one counted frame of the middle
/// view. Leaves the probe plan applied.
#[allow(clippy::too_many_arguments, reason = "one benchmark case, every part named")]
pub fn measure_ceiling(
    runtime: &mut Runtime,
    registry: &Registry,
    volume: &Volume,
    viewport: (u32, u32),
    camera: &OrbitCamera,
    degrees_per_frame: f64,
    frames: u32,
    step_voxels: f64,
) -> Result<Ceiling, String> {
    let inputs =
        std::collections::BTreeMap::from([("volume".to_string(), volgraph_core::graph::ast::InputKind::Volume)]);
    runtime.bind_scene(&inputs, volume, &[]).map_err(|e| e.to_string())?;
    let mut options = CompileOptions::new(viewport.0, viewport.1);
    options.param_overrides.insert("fetch.step_voxels".to_string(), ron::Value::from(step_voxels));
    let plan =
        runtime.compile(FETCH_GRAPH_FILE, FETCH_GRAPH, registry, &options).map_err(|d: Diagnostics| d.to_string())?;
    runtime.apply(plan, registry).map_err(|e| e.to_string())?;
    let timing = measure::time_frames(runtime, camera, degrees_per_frame, frames, || {}).map_err(|e| e.to_string())?;
    let middle = frame_camera(camera, degrees_per_frame, frames / 2);
    let counted = gpu_count::count(runtime, registry, FETCH_GRAPH_FILE, FETCH_GRAPH, &mut options, &middle, &middle)?
        .ok_or_else(|| "the fetch probe did not count its samples".to_string())?;
    let median_ms = median(&timing.frame_ms);
    let pixels = viewport.0 as f64 * viewport.1 as f64;
    Ok(Ceiling {
        samples_per_pixel: counted.samples_per_pixel,
        median_ms,
        msamples_per_s: counted.samples_per_pixel * pixels / (median_ms * 1e-3) / 1e6,
        wall_clock: timing.wall_time_fallback,
    })
}

/// Runs `volgraph bench fetch`.
pub fn run(args: &FetchArgs) -> anyhow::Result<FetchReport> {
    if args.frames == 0 {
        return Err(anyhow!("--frames 0: at least one timed frame is needed"));
    }
    if !(args.step.is_finite() && (0.01..=16.0).contains(&args.step)) {
        return Err(anyhow!("--step {}: expected a step in voxels within 0.01..=16", args.step));
    }
    let viewports: Vec<(u32, u32)> = args.size.iter().map(|s| inputs::parse_size(s)).collect::<anyhow::Result<_>>()?;
    let camera = inputs::parse_camera(&args.camera)?;
    let gpu = std::sync::Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let registry = volgraph_app::registry();
    let (sources, _) = volgraph_app::shader_dir::sources_for(std::path::Path::new(FETCH_GRAPH_FILE), None);
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
    let degrees = 360.0 / args.frames as f64;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for name in &args.datasets {
        let volume = match dataset::load(name) {
            Ok(v) => v,
            Err(e) => {
                volgraph_app::stdout::eprintln_escaped!("note: skipping dataset {name}: {e:#}");
                skipped.push(format!("{name}: {e:#}"));
                continue;
            }
        };
        for &viewport in &viewports {
            let ceiling =
                measure_ceiling(&mut runtime, &registry, &volume, viewport, &camera, degrees, args.frames, args.step)
                    .map_err(|e| anyhow!("dataset {name} at {}x{}: {e}", viewport.0, viewport.1))?;
            let format = runtime.volume().map_or_else(|| "?".to_string(), |(_, f)| format!("{f:?}"));
            rows.push(FetchRow {
                dataset: name.clone(),
                dims: volume.dims.to_array(),
                texture_format: format,
                viewport: [viewport.0, viewport.1],
                ceiling,
            });
        }
    }
    if rows.is_empty() {
        return Err(anyhow!("nothing was measured:\n  {}", skipped.join("\n  ")));
    }
    let report = FetchReport {
        program: "volgraph bench fetch".to_string(),
        adapter,
        step_voxels: args.step,
        frames: args.frames,
        camera: [camera.azimuth_deg, camera.elevation_deg, camera.distance],
        rows,
        skipped,
    };
    let markdown = to_markdown(&report);
    volgraph_app::stdout::write_stdout(&markdown)?;
    crate::report_files::write_file(args.json.as_deref(), &(serde_json::to_string_pretty(&report)? + "\n"), "--json")?;
    crate::report_files::write_file(args.markdown.as_deref(), &markdown, "--markdown")?;
    Ok(report)
}

/// The markdown table.
pub fn to_markdown(r: &FetchReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## volgraph bench fetch — the fetch ceiling\n");
    let clock = if r.rows.iter().any(|row| row.ceiling.wall_clock) { "wall time" } else { "GPU time" };
    let _ = writeln!(
        s,
        "Adapter: {}. Every sample of a {}-voxel-step raycast through the box (analytic rays, no leaping, no \
         termination), no classification or compositing (`{FETCH_GRAPH_FILE}`); samples counted on the GPU in the \
         middle view; ms/frame: median of {} frames over a full turn about y from camera {:?}, {clock}.\n",
        r.adapter, r.step_voxels, r.frames, r.camera
    );
    let _ = writeln!(s, "| dataset | volume texture | viewport | samples/px | ms/frame | Msamples/s |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for row in &r.rows {
        let _ = writeln!(
            s,
            "| {} {}×{}×{} | {} | {}×{} | {:.1} | {:.2} | {:.1} |",
            row.dataset,
            row.dims[0],
            row.dims[1],
            row.dims[2],
            row.texture_format,
            row.viewport[0],
            row.viewport[1],
            row.ceiling.samples_per_pixel,
            row.ceiling.median_ms,
            row.ceiling.msamples_per_s
        );
    }
    for k in &r.skipped {
        let _ = writeln!(s, "\nSkipped: {k}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe counts exactly the samples of the analytic ray (k + 0.5 steps inside the box):
    /// for a camera looking straight down -z at a 32³ cube filling a small viewport's centre,
    /// the centre pixel's ray crosses 32 voxels, so 64 samples at step 0.5 — and the total over
    /// the image matches the CPU reference's count of the same rays within rounding at the box
    /// edges.
    #[test]
    fn the_probe_counts_the_reference_samples() {
        let Ok(gpu) = Gpu::new_headless() else {
            panic!("no GPU adapter (install mesa-vulkan-drivers for lavapipe)");
        };
        let gpu = std::sync::Arc::new(gpu);
        let registry = volgraph_app::registry();
        let mut runtime = Runtime::new(gpu, ShaderLibrary::new(volgraph_passes::builtin_shaders()));
        let volume = volgraph_accel::generate::marschner_lobb(32);
        let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 3.2, ..OrbitCamera::default() };
        let viewport = (48, 48);
        let ceiling =
            measure_ceiling(&mut runtime, &registry, &volume, viewport, &camera, 0.0, 2, 0.5).expect("the probe runs");
        let settings = volgraph_accel::reference::RaycastSettings { step_voxels: 0.5, ..Default::default() };
        let lut = vec![[0.0f32; 4]; 256];
        let reference = volgraph_accel::reference::render_reference(&volume, &lut, &camera, 48, 48, &settings);
        let cpu_spp = reference.samples as f64 / (48.0 * 48.0);
        // A ray grazing an edge may gain or lose one sample to f32 vs f64 rounding.
        assert!(
            (ceiling.samples_per_pixel - cpu_spp).abs() < 0.02 * cpu_spp,
            "GPU {} vs CPU {cpu_spp} samples/px",
            ceiling.samples_per_pixel
        );
        assert!(ceiling.msamples_per_s > 0.0 && ceiling.median_ms > 0.0);
    }
}
