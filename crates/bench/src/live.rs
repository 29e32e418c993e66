//! `volgraph bench live`: what the live runtime costs and saves, measured on a scratch copy of a
//! graph and the shader folder.
//!
//! (a) Reload latency, file change → first frame of the new graph finished: a parameter-only edit
//!     (written in place), a graph edit that changes no shader (a pass added or removed; its
//!     pipeline comes from the cache), and a shader edit (the module recompiled). Each edit is
//!     written to disk and picked up by the viewer's own debounced watcher, so the figure is what
//!     a user sees, debounce included.
//! (b) Throughput: frames submitted with up to `MAX_FRAMES_IN_FLIGHT` queued vs each frame
//!     waited for (the old blocking executor's way), same graph, same frames.
//! (c) Soak: frames and reloads alternating a good and a broken graph, with resident memory,
//!     the runtime's own accounting and wgpu's allocator report at the start and the end.
//!
//! Prints a markdown table, writes JSON when asked. Never asserts a timing.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail};
use serde::Serialize;
use volgraph_accel::camera::OrbitCamera;
use volgraph_core::runtime::{CameraData, Gpu};

use crate::graphs::measure::median;
use volgraph_app::view::session::{Event, LiveSession, SessionArgs};
use volgraph_app::view::watch::{FileWatch, QUIET};

/// The options of `volgraph bench live`.
#[derive(clap::Args, Debug, Clone)]
pub struct LiveArgs {
    /// The graph to reload (copied to a scratch folder with the shaders).
    #[arg(long, default_value = "graphs/basic/fragment_raycast.ron")]
    pub graph: PathBuf,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256")]
    pub size: String,
    /// Edits timed per kind (the median is reported; at least 1, or the tables would be NaN).
    #[arg(long, default_value_t = 15, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=100_000))]
    pub edits: usize,
    /// Frames per throughput run (at least 2: the first includes pipeline JIT).
    #[arg(long, default_value_t = 120, value_parser = clap::value_parser!(u32).range(2..))]
    pub throughput_frames: u32,
    /// Soak frames (at least 1).
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..))]
    pub soak_frames: u32,
    /// Soak reloads (alternating a good and a broken graph; at least 1).
    #[arg(long, default_value_t = 1_000, value_parser = clap::value_parser!(u32).range(1..))]
    pub soak_reloads: u32,
    /// Soak viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "64x64")]
    pub soak_size: String,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Latency of one kind of edit.
#[derive(Clone, Debug, Serialize)]
pub struct Latency {
    /// What was edited.
    pub edit: String,
    /// Edits timed.
    pub samples: usize,
    /// Median ms, file written → first new frame done.
    pub median_ms: f64,
    /// Fastest.
    pub min_ms: f64,
    /// Slowest.
    pub max_ms: f64,
    /// What the session reported for the last one.
    pub last_event: String,
}

/// Memory at one point of the soak.
#[derive(Clone, Debug, Serialize)]
pub struct MemorySample {
    /// Frames rendered so far.
    pub frames: u32,
    /// Reloads so far.
    pub reloads: u32,
    /// Resident set size, MiB (`/proc/self/statm`).
    pub rss_mib: f64,
    /// The runtime's transient + pooled + history + input bytes, MiB.
    pub runtime_mib: f64,
    /// Pipelines cached.
    pub pipelines: usize,
    /// Textures created since start.
    pub textures_created: u64,
    /// wgpu's allocator: bytes allocated and reserved, MiB (`None` where the backend has no report).
    pub wgpu_allocated_mib: Option<f64>,
    /// wgpu's allocator: memory blocks reserved, MiB.
    pub wgpu_reserved_mib: Option<f64>,
}

/// Everything `volgraph bench live` measures.
#[derive(Clone, Debug, Serialize)]
pub struct LiveReport {
    /// The adapter.
    pub adapter: String,
    /// The graph.
    pub graph: String,
    /// Viewport of (a) and (b).
    pub viewport: (u32, u32),
    /// The watcher's quiet period included in every latency, ms.
    pub debounce_ms: f64,
    /// (a).
    pub latency: Vec<Latency>,
    /// (b): frames per second, in flight and blocking, and their ratio.
    pub fps_in_flight: f64,
    /// (b) blocking.
    pub fps_blocking: f64,
    /// (b) ratio.
    pub throughput_ratio: f64,
    /// (c) at the start and the end.
    pub soak: Vec<MemorySample>,
    /// (c) events seen: errors (the broken graph) and recoveries.
    pub soak_errors: u32,
    /// (c) recoveries.
    pub soak_recoveries: u32,
}

fn rss_mib() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: f64 = statm.split_whitespace().nth(1).and_then(|p| p.parse().ok()).unwrap_or(0.0);
    pages * 4096.0 / (1024.0 * 1024.0)
}

fn sample(session: &LiveSession, frames: u32, reloads: u32) -> MemorySample {
    let m = session.runtime.memory();
    let report = session.runtime.gpu().device.generate_allocator_report();
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    MemorySample {
        frames,
        reloads,
        rss_mib: rss_mib(),
        runtime_mib: mib(m.transient_bytes + m.pooled_free_bytes + m.history_bytes + m.input_bytes),
        pipelines: m.pipelines,
        textures_created: m.textures_created,
        wgpu_allocated_mib: report.as_ref().map(|r| mib(r.total_allocated_bytes)),
        wgpu_reserved_mib: report.as_ref().map(|r| mib(r.total_reserved_bytes)),
    }
}

fn copy_dir(from: &Path, to: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let entry = entry?;
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target)?;
        }
    }
    Ok(())
}

fn camera_data(session: &LiveSession) -> CameraData {
    CameraData::from_orbit(&OrbitCamera::default(), session.options().viewport)
}

/// Writes `text` to `file`, then waits for the watcher to deliver it, the session to reload and
/// the first frame of the result to finish: the latency and the events.
fn timed_edit(
    session: &mut LiveSession,
    watch: &mut FileWatch,
    file: &Path,
    text: &str,
) -> anyhow::Result<(f64, Vec<Event>)> {
    let start = Instant::now();
    std::fs::write(file, text).with_context(|| format!("writing {}", file.display()))?;
    let deadline = start + Duration::from_secs(20);
    loop {
        let changed = watch.poll();
        if !changed.is_empty() {
            let events = session.files_changed(&changed);
            session.runtime.submit(camera_data(session), None).map_err(|e| anyhow!(e))?;
            session.runtime.finish();
            let ms = start.elapsed().as_secs_f64() * 1e3;
            watch.set_files(&session.watched_files());
            return Ok((ms, events));
        }
        if Instant::now() > deadline {
            bail!("the watcher never reported the edit of {}", file.display());
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

fn latency_of(
    session: &mut LiveSession,
    watch: &mut FileWatch,
    name: &str,
    file: &Path,
    variants: [&str; 2],
    edits: usize,
) -> anyhow::Result<Latency> {
    // One untimed round so both variants' pipelines exist (the graph edit is about the cache).
    for v in variants {
        timed_edit(session, watch, file, v)?;
    }
    let mut ms = Vec::new();
    let mut last = String::new();
    for i in 0..edits {
        let (t, events) = timed_edit(session, watch, file, variants[i % 2])?;
        if let Some(e) = events.iter().find(|e| matches!(e, Event::Error { .. })) {
            bail!("{name}: the edit failed: {e}");
        }
        last = events.iter().map(ToString::to_string).collect::<Vec<_>>().join("; ");
        ms.push(t);
    }
    Ok(Latency {
        edit: name.to_string(),
        samples: ms.len(),
        median_ms: median(&ms),
        min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
        max_ms: ms.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        last_event: last,
    })
}

/// Runs the benchmark.
pub fn run(args: &LiveArgs) -> anyhow::Result<()> {
    let viewport = volgraph_app::inputs::parse_size(&args.size)?;
    let soak_viewport = volgraph_app::inputs::parse_size(&args.soak_size)?;
    // The graph first: a missing graph file is named as such, not as a missing shaders folder.
    let original = volgraph_accel::input_file::read_text(&args.graph, "graph file")?;
    let shaders_root = volgraph_app::shader_dir::find_beside(&args.graph).ok_or_else(|| {
        anyhow!(
            "{}: no shaders/ folder beside the graph file or in a folder above it, to copy; give a graph inside a \
             volgraph checkout (e.g. graphs/basic/fragment_raycast.ron)",
            args.graph.display()
        )
    })?;
    let dir = std::env::temp_dir().join(format!("volgraph-bench-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&shaders_root, &dir.join("shaders"))?;
    let graph = dir.join("graph.ron");
    std::fs::write(&graph, &original)?;
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let open = |viewport: (u32, u32)| {
        LiveSession::open(
            gpu.clone(),
            &SessionArgs {
                scene: None,
                graph: graph.clone(),
                volume: Vec::new(),
                raw: Default::default(),
                tf: None,
                tf_map: None,
                viewport,
                features: Vec::new(),
                shaders: Some(dir.join("shaders")),
                gpu_memory_mb: None,
                memory_mb: None,
                cuts: Default::default(),
                lights: Default::default(),
                environment: None,
                named: Vec::new(),
                named_tfs: Vec::new(),
            },
        )
        .map(|(s, _)| s)
        .map_err(|e| match e {
            volgraph_app::cli::CliError::Graph(d) => anyhow!("{d}"),
            volgraph_app::cli::CliError::Other(e) => e,
        })
    };

    // (a) Latency.
    let mut session = open(viewport)?;
    session.runtime.render(camera_data(&session)).map_err(|e| anyhow!(e))?;
    let mut watch = FileWatch::new()?;
    watch.set_files(&session.watched_files());
    let step_a = original.replacen("\"step_voxels\": 0.5", "\"step_voxels\": 0.6", 1);
    if step_a == original {
        bail!("{}: the parameter edit looks for \"step_voxels\": 0.5", args.graph.display());
    }
    let mut latency = vec![latency_of(
        &mut session,
        &mut watch,
        "parameter only (step_voxels)",
        &graph,
        [&step_a, &original],
        args.edits,
    )?];
    let extra =
        original.replacen("\n    outputs: {\n", "\n    outputs: {\n        \"display2\": \"extra.display\",\n", 1);
    let extra = extra.replacen(
        "    ],\n    outputs",
        "        Pass(id: \"extra\", kind: \"present\", params: {\"background\": 0.2}, inputs: {\"color\": \"march.color\"}),\n    ],\n    outputs",
        1,
    );
    if !extra.contains("extra.display") || !extra.contains("id: \"extra\"") {
        bail!("{}: the graph edit adds a present pass after the last pass", args.graph.display());
    }
    latency.push(latency_of(
        &mut session,
        &mut watch,
        "graph edit, no shader change (a present pass added/removed)",
        &graph,
        [&extra, &original],
        args.edits,
    )?);
    let shader = dir.join("shaders/raycast.wgsl");
    let shader_text = std::fs::read_to_string(&shader)?;
    let shader_b = format!("{shader_text}\n// edited\n");
    latency.push(latency_of(
        &mut session,
        &mut watch,
        "shader edit (raycast.wgsl recompiled)",
        &shader,
        [&shader_b, &shader_text],
        args.edits,
    )?);

    // (b) Throughput.
    let camera = camera_data(&session);
    for _ in 0..3 {
        session.runtime.render(camera).map_err(|e| anyhow!(e))?;
    }
    let start = Instant::now();
    for _ in 0..args.throughput_frames {
        session.runtime.submit(camera, None).map_err(|e| anyhow!(e))?;
    }
    session.runtime.finish();
    let fps_in_flight = args.throughput_frames as f64 / start.elapsed().as_secs_f64();
    let start = Instant::now();
    for _ in 0..args.throughput_frames {
        session.runtime.render(camera).map_err(|e| anyhow!(e))?;
    }
    let fps_blocking = args.throughput_frames as f64 / start.elapsed().as_secs_f64();
    drop(session);
    // The soak rewrites the graph thousands of times: a watcher nobody drains would queue every
    // event (that queue, not the runtime, is what grows).
    drop(watch);

    // (c) Soak.
    std::fs::write(&graph, &original)?;
    let mut session = open(soak_viewport)?;
    let broken = original.replacen("kind: \"raycast\"", "kind: \"raycats\"", 1);
    let mut soak = vec![sample(&session, 0, 0)];
    let (mut frames, mut reloads, mut errors, mut recoveries) = (0u32, 0u32, 0u32, 0u32);
    let frames_per_reload = (args.soak_frames / args.soak_reloads.max(1)).max(1);
    let camera = camera_data(&session);
    while frames < args.soak_frames || reloads < args.soak_reloads {
        if reloads < args.soak_reloads && frames % frames_per_reload == 0 {
            std::fs::write(&graph, if reloads % 2 == 0 { &broken } else { &original })?;
            for e in session.reload_graph() {
                match e {
                    Event::Error { .. } => errors += 1,
                    Event::Recovered { .. } => recoveries += 1,
                    _ => {}
                }
            }
            reloads += 1;
        }
        if frames < args.soak_frames {
            session.runtime.submit(camera, None).map_err(|e| anyhow!(e))?;
            frames += 1;
            if frames % 64 == 0 {
                session.runtime.poll();
            }
        }
        if frames == args.soak_frames / 10 && soak.len() == 1 {
            session.runtime.finish();
            soak.push(sample(&session, frames, reloads));
        }
    }
    session.runtime.finish();
    soak.push(sample(&session, frames, reloads));
    let _ = std::fs::remove_dir_all(&dir);

    let report = LiveReport {
        adapter: gpu.adapter_name.clone(),
        graph: args.graph.display().to_string(),
        viewport,
        debounce_ms: QUIET.as_secs_f64() * 1e3,
        latency,
        fps_in_flight,
        fps_blocking,
        throughput_ratio: fps_in_flight / fps_blocking,
        soak,
        soak_errors: errors,
        soak_recoveries: recoveries,
    };
    volgraph_app::stdout::write_stdout(&to_markdown(&report))?;
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
        volgraph_app::stdout::write_stdout(&format!("\nJSON written to {}\n", path.display()))?;
    }
    Ok(())
}

/// The report as markdown.
pub fn to_markdown(r: &LiveReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# volgraph bench live\n\n{} on {}, {}x{}\n", r.graph, r.adapter, r.viewport.0, r.viewport.1);
    let _ = writeln!(
        s,
        "## Reload latency: file written → first frame of the new graph done (debounce {:.0} ms included)\n",
        r.debounce_ms
    );
    let _ = writeln!(s, "| edit | samples | median ms | min ms | max ms |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for l in &r.latency {
        let _ = writeln!(s, "| {} | {} | {:.1} | {:.1} | {:.1} |", l.edit, l.samples, l.median_ms, l.min_ms, l.max_ms);
    }
    let _ = writeln!(s, "\n## Throughput, same graph and frames\n");
    let _ = writeln!(
        s,
        "| frames in flight (≤ {}) fps | blocking fps | ratio |",
        volgraph_core::runtime::MAX_FRAMES_IN_FLIGHT
    );
    let _ = writeln!(s, "|---:|---:|---:|");
    let _ = writeln!(s, "| {:.1} | {:.1} | {:.2} |", r.fps_in_flight, r.fps_blocking, r.throughput_ratio);
    let _ = writeln!(
        s,
        "\n## Soak: frames and reloads alternating a good and a broken graph ({} errors, {} recoveries)\n",
        r.soak_errors, r.soak_recoveries
    );
    let _ = writeln!(
        s,
        "| frames | reloads | RSS MiB | runtime MiB | pipelines | textures created | wgpu allocated MiB | wgpu reserved MiB |"
    );
    let _ = writeln!(s, "|---:|---:|---:|---:|---:|---:|---:|---:|");
    let opt = |v: Option<f64>| v.map_or("n/a".to_string(), |x| format!("{x:.1}"));
    for m in &r.soak {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.2} | {} | {} | {} | {} |",
            m.frames,
            m.reloads,
            m.rss_mib,
            m.runtime_mib,
            m.pipelines,
            m.textures_created,
            opt(m.wgpu_allocated_mib),
            opt(m.wgpu_reserved_mib)
        );
    }
    s
}
