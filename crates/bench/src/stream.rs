//! `volgraph bench stream`: volumes beyond memory (issue "Volumes beyond memory", "Measured"),
//! in one run:
//! - `volgraph convert NAME store.ome.zarr` (a generated vessel tree of 4096³ u8 by default, 64
//!   GiB of voxels): wall time, peak resident memory of the converter, bytes on disk — or an
//!   existing `--store`;
//! - that store streamed by `graphs/streaming/ray_guided.ron` at 800×600: time to the first image
//!   (from opening the store: metadata, the coarsest level, the pipeline's JIT), frame times while
//!   the camera turns (the moving level of detail), time to the full image at rest, peak resident
//!   memory of this process from opening the store on, bricks read against bricks in the volume;
//! - the same generator at 512³: the store streamed against the volume rendered in core by
//!   `modern/fastest` (time and image difference), and streamed with every sample at level 0
//!   (lod 0.5) against the same in-core render.
//!
//! The converted stores are written under `--work` and deleted afterwards unless `--keep`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::pyramid::PyramidSource;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Gpu, Image, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, compile};

use crate::report_files::write_markdown_and_json;

/// `bench stream` arguments.
#[derive(clap::Args, Debug)]
pub struct StreamArgs {
    /// The volume to convert (a generated name such as vessels4096, or a file).
    #[arg(long, default_value = "vessels4096")]
    pub volume: String,
    /// Stream this store instead of converting `--volume` (its conversion is then not timed).
    #[arg(long)]
    pub store: Option<PathBuf>,
    /// The volume of the in-core comparison (converted too, small enough to render in core).
    #[arg(long, default_value = "vessels512")]
    pub small: String,
    /// Where converted stores are written.
    #[arg(long, default_value = "target/bench-stream")]
    pub work: PathBuf,
    /// Keep the converted stores.
    #[arg(long)]
    pub keep: bool,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// Frames while the camera turns (1° each).
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(2..=10_000))]
    pub moving_frames: u32,
    /// Host memory for decoded chunks, MiB (`--memory-mb`).
    #[arg(long, default_value_t = 512)]
    pub memory_mb: u64,
    /// GPU memory for the brick pool, MiB (`--gpu-memory-mb`).
    #[arg(long, default_value_t = 1024)]
    pub gpu_memory_mb: u64,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the tables as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

const GRAPH: &str = "graphs/streaming/ray_guided.ron";

fn camera(azimuth: f64) -> OrbitCamera {
    OrbitCamera { azimuth_deg: azimuth, elevation_deg: 25.0, distance: 2.6, ..OrbitCamera::default() }
}

/// This process's peak resident memory (VmHWM), bytes.
fn peak_rss() -> Option<u64> {
    proc_peak(Path::new("/proc/self/status"))
}

fn proc_peak(status: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(status).ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kb| kb << 10)
}

/// Resets this process's peak resident memory to what it holds now (Linux `clear_refs` 5).
fn reset_peak_rss() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// `volgraph convert name out` in a child process: wall seconds and its peak resident memory
/// (its VmHWM, polled).
fn convert(name: &str, out: &Path) -> anyhow::Result<(f64, u64)> {
    let exe = std::env::current_exe().context("this program's path")?;
    let started = Instant::now();
    let mut child = std::process::Command::new(exe)
        .args(["convert", name])
        .arg(out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .context("starting volgraph convert")?;
    let status_file = PathBuf::from(format!("/proc/{}/status", child.id()));
    let mut peak = 0;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        peak = peak.max(proc_peak(&status_file).unwrap_or(0));
        std::thread::sleep(Duration::from_millis(50));
    };
    if !status.success() {
        let mut text = String::new();
        if let Some(mut e) = child.stderr.take() {
            use std::io::Read as _;
            let _ = e.read_to_string(&mut text);
        }
        return Err(anyhow!("volgraph convert {name}: {text}"));
    }
    Ok((started.elapsed().as_secs_f64(), peak))
}

/// The default transfer function fitted to `volume`, as a LUT.
fn fitted_lut(volume: &Volume) -> anyhow::Result<Vec<[f32; 4]>> {
    let (tf, _) = volgraph_app::inputs::transfer_function(None, None, volume, false)?;
    Ok(tf.to_lut_for(volume, volgraph_app::inputs::LUT_SIZE))
}

/// A runtime with `graph` applied over `volume` and `lut`, and optionally a pyramid bound in
/// the volume's place.
fn apply(
    gpu: &Arc<Gpu>,
    graph: &str,
    (volume, lut): (&Volume, &[[f32; 4]]),
    pyramid: Option<Arc<dyn PyramidSource>>,
    size: &str,
    set: &[(&str, f64)],
    gpu_memory_mb: u64,
) -> anyhow::Result<(Runtime, (u32, u32))> {
    let registry = volgraph_app::program::registry();
    let source = volgraph_app::inputs::read_graph(&PathBuf::from(graph))?;
    let mut options: CompileOptions = volgraph_app::cli::compile_options(size, &[], &[])?;
    for (name, value) in set {
        options = options.with_param("march", name, *value);
    }
    options.scene = scene_values_of(&match &pyramid {
        Some(p) => VolumeDesc::of_box(p.levels()[0].dims, p.spacing()),
        None => VolumeDesc::of(volume),
    });
    let plan = compile(graph, &source, &registry, &options).map_err(|d| anyhow!("{d}"))?;
    let mut runtime = Runtime::new(gpu.clone(), ShaderLibrary::new(volgraph_passes::builtin_shaders()));
    runtime.set_gpu_memory_budget(Some(gpu_memory_mb << 20));
    runtime.bind_scene(&plan.inputs, volume, lut).map_err(|e| anyhow!(e))?;
    if let Some(p) = pyramid {
        runtime.bind_pyramid("volume", p);
    }
    let viewport = plan.viewport;
    runtime.apply(plan, &registry).map_err(|e| anyhow!(e))?;
    Ok((runtime, viewport))
}

fn counter(runtime: &Runtime, name: &str) -> f64 {
    runtime.pass_counters().iter().find(|(_, n, _)| *n == name).map_or(0.0, |c| c.2)
}

/// A first frame at `cam`, then frames until complete (`volgraph render`'s refinement): the
/// frames and ms.
fn refine(runtime: &mut Runtime, viewport: (u32, u32), cam: &OrbitCamera) -> anyhow::Result<(u32, f64)> {
    let started = Instant::now();
    let camera = CameraData::from_orbit(cam, viewport);
    runtime.render(camera).map_err(|e| anyhow!(e))?;
    let mut frames = 1;
    let (complete, _) = volgraph_app::stream_progress::refine_runtime(runtime, camera, started, None, |_| frames += 1)?;
    if !complete {
        return Err(anyhow!("the stream did not complete"));
    }
    Ok((frames, started.elapsed().as_secs_f64() * 1e3))
}

fn max_diff(a: &Image, b: &Image) -> f64 {
    let (a, b) = (a.to_rgba_f64(), b.to_rgba_f64());
    a.iter().zip(&b).flat_map(|(p, q)| (0..4).map(move |k| (p[k] - q[k]).abs())).fold(0.0, f64::max)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Runs the benchmark, prints the tables and returns the JSON.
pub fn run(args: &StreamArgs) -> anyhow::Result<serde_json::Value> {
    std::fs::create_dir_all(&args.work).with_context(|| format!("--work {}", args.work.display()))?;
    let mut made = Vec::new();
    let (store, conversion) = match &args.store {
        Some(s) => (s.clone(), None),
        None => {
            let out = args.work.join(format!("{}.ome.zarr", args.volume));
            let _ = std::fs::remove_dir_all(&out);
            eprintln!("converting {} …", args.volume);
            let (seconds, peak) = convert(&args.volume, &out)?;
            made.push(out.clone());
            (out, Some((seconds, peak)))
        }
    };
    let on_disk = volgraph_app::convert_cmd::folder_bytes(&store);
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);

    // The big store, streamed.
    reset_peak_rss();
    let opened = Instant::now();
    let options = volgraph_accel::load::LoadOptions::default();
    let streamed = volgraph_app::zarr_input::stream(&store, &options, Some(args.memory_mb))?;
    let source: Arc<dyn PyramidSource> = streamed.source.clone();
    let lut = fitted_lut(&streamed.coarsest)?;
    let (mut runtime, viewport) =
        apply(&gpu, GRAPH, (&streamed.coarsest, &lut), Some(source.clone()), &args.size, &[], args.gpu_memory_mb)?;
    runtime.render(CameraData::from_orbit(&camera(30.0), viewport)).map_err(|e| anyhow!(e))?;
    let first_image_ms = opened.elapsed().as_secs_f64() * 1e3;
    let mut moving = Vec::new();
    for f in 1..=args.moving_frames {
        let started = Instant::now();
        runtime.render(CameraData::from_orbit(&camera(30.0 + f64::from(f)), viewport)).map_err(|e| anyhow!(e))?;
        moving.push(started.elapsed().as_secs_f64() * 1e3);
    }
    let rest = camera(30.0 + f64::from(args.moving_frames));
    let (rest_frames, full_ms) = refine(&mut runtime, viewport, &rest)?;
    let rest_frame_ms = {
        let started = Instant::now();
        runtime.render(CameraData::from_orbit(&rest, viewport)).map_err(|e| anyhow!(e))?;
        started.elapsed().as_secs_f64() * 1e3
    };
    let peak = peak_rss().unwrap_or(0);
    let (read, bricks, empty) =
        (counter(&runtime, "read_bricks"), counter(&runtime, "bricks"), counter(&runtime, "empty_bricks"));
    let level0 = source.levels()[0].dims;
    let adapter = gpu.adapter_name.clone();
    drop(runtime);

    // The small one: streamed against in core.
    let small_store = args.work.join(format!("{}.ome.zarr", args.small));
    let _ = std::fs::remove_dir_all(&small_store);
    convert(&args.small, &small_store)?;
    made.push(small_store.clone());
    let small = volgraph_accel::generate::by_name(&args.small).map_err(|e| anyhow!("{e}"))?;
    let cam = camera(30.0);
    // One transfer function for both (fitted to the whole volume, not the store's coarsest level).
    let small_lut = fitted_lut(&small)?;
    let (mut in_core, _) =
        apply(&gpu, "graphs/modern/fastest.ron", (&small, &small_lut), None, &args.size, &[], args.gpu_memory_mb)?;
    in_core.render(CameraData::from_orbit(&cam, viewport)).map_err(|e| anyhow!(e))?;
    let in_core_ms = {
        let times: Vec<f64> = (0..5)
            .map(|_| {
                let t = Instant::now();
                let _ = in_core.render(CameraData::from_orbit(&cam, viewport));
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        median(times)
    };
    let want = in_core.read_output("image").map_err(|e| anyhow!(e))?;
    drop(in_core);
    let mut small_rows = Vec::new();
    for (label, lod) in [("at rest (lod 1)", 1.0), ("every sample at level 0 (lod 0.5)", 0.5)] {
        let s = volgraph_app::zarr_input::stream(&small_store, &options, Some(args.memory_mb))?;
        let started = Instant::now();
        let (mut rt, _) = apply(
            &gpu,
            GRAPH,
            (&s.coarsest, &small_lut),
            Some(s.source.clone()),
            &args.size,
            &[("lod", lod)],
            args.gpu_memory_mb,
        )?;
        let (frames, _) = refine(&mut rt, viewport, &cam)?;
        let total_ms = started.elapsed().as_secs_f64() * 1e3;
        let times: Vec<f64> = (0..5)
            .map(|_| {
                let t = Instant::now();
                let _ = rt.render(CameraData::from_orbit(&cam, viewport));
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        let got = rt.read_output("image").map_err(|e| anyhow!(e))?;
        small_rows.push((label, frames, total_ms, median(times), max_diff(&got, &want)));
    }
    if !args.keep {
        for dir in &made {
            let _ = std::fs::remove_dir_all(dir);
        }
    }

    let moving_median = median(moving.clone());
    let moving_max = moving.iter().copied().fold(0.0, f64::max);
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut md = format!(
        "## Streaming {} ({}×{}×{} u8) at {}, {adapter}\n\n| figure | value | goal |\n|---|---:|---:|\n",
        store.display(),
        level0.x,
        level0.y,
        level0.z,
        args.size
    );
    if let Some((seconds, peak)) = conversion {
        md += &format!("| `volgraph convert {}`: wall | {seconds:.0} s | |\n", args.volume);
        md += &format!("| `volgraph convert`: peak resident | {:.0} MiB | |\n", mib(peak));
    }
    md += &format!("| store on disk (file bytes) | {:.1} MiB | |\n", mib(on_disk));
    md += &format!(
        "| time to the first image (open, coarsest level, JIT, frame) | {first_image_ms:.0} ms | ≤ 3000 ms |\n"
    );
    md += &format!(
        "| frame while the camera turns, median / max of {} | {moving_median:.0} / {moving_max:.0} ms | ≤ 150 ms |\n",
        args.moving_frames
    );
    md += &format!("| time to the full image at rest | {full_ms:.0} ms ({rest_frames} frames) | ≤ 30000 ms |\n");
    md += &format!("| frame at rest, fully loaded | {rest_frame_ms:.0} ms | |\n");
    md += &format!("| peak resident memory from opening the store | {:.0} MiB | ≤ 4096 MiB |\n", mib(peak));
    md += &format!("| bricks read / in the volume (all levels) | {read} / {bricks} ({empty} known empty) | |\n");
    md += &format!(
        "\n## {} streamed against in core (`modern/fastest`, {:.1} ms a frame)\n\n| stream | frames to full | ms to full \
         | ms a frame at rest | max difference |\n|---|---:|---:|---:|---:|\n",
        args.small, in_core_ms
    );
    for (label, frames, total, frame, diff) in &small_rows {
        md += &format!("| {label} | {frames} | {total:.0} | {frame:.1} | {:.2}/255 |\n", diff * 255.0);
    }
    println!("{md}");
    let json = serde_json::json!({
        "adapter": adapter,
        "store": store.display().to_string(),
        "size": args.size,
        "convert_s": conversion.map(|c| c.0),
        "convert_peak_bytes": conversion.map(|c| c.1),
        "store_bytes": on_disk,
        "first_image_ms": first_image_ms,
        "moving_frame_ms": moving,
        "full_image_ms": full_ms,
        "rest_frames": rest_frames,
        "rest_frame_ms": rest_frame_ms,
        "peak_rss_bytes": peak,
        "bricks_read": read,
        "bricks": bricks,
        "bricks_empty": empty,
        "small": {
            "volume": args.small,
            "in_core_frame_ms": in_core_ms,
            "streamed": small_rows.iter().map(|(label, frames, total, frame, diff)| serde_json::json!({
                "case": label, "frames_to_full": frames, "ms_to_full": total, "frame_ms": frame, "max_diff": diff,
            })).collect::<Vec<_>>(),
        },
    });
    write_markdown_and_json((args.markdown.as_deref(), &md), (args.json.as_deref(), &json))?;
    Ok(json)
}
