//! `volgraph bench workbench`: the viewer-as-a-workbench figures of issue 24, measured through
//! the viewer's own session (`volgraph_app::view::session::LiveSession`, no window):
//! - from a TF edit (a control point moved, as a drag in the editor does) to the first frame
//!   that shows it finished on the GPU, on a 256³ volume at 800×600 (goal ≤ 50 ms): the LUT
//!   upload, the passes that read the TF rerunning (classification, distance map), the frame;
//!   beside the steady frame of the same view, so the edit's own cost shows;
//! - the frame time while the camera moves (a new camera every frame, as a drag gives) for every
//!   shipped graph (goal ≤ 100 ms at 800×600 on lavapipe).
//!
//! All cases run side by side in one process on one device; medians of `frames` frames after
//! a warm-up frame (pipeline JIT).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use volgraph_accel::camera::OrbitCamera;
use volgraph_app::view::session::{LiveSession, SessionArgs};
use volgraph_core::runtime::Gpu;

use crate::graphs::measure::median;

/// `bench workbench` arguments.
#[derive(clap::Args, Debug)]
pub struct WorkbenchArgs {
    /// The volume file (a 256³ dataset by default).
    #[arg(long)]
    pub volume: Option<PathBuf>,
    /// The graph the TF edits are timed with (a file or a built-in name).
    #[arg(long, default_value = "modern/fastest")]
    pub graph: PathBuf,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// Timed edits and frames per case (the median is reported).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// Skip the per-graph drag frame times (only the TF edit).
    #[arg(long)]
    pub no_drag: bool,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the tables as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// The viewer's session (no window) of `graph` on `volume` at `viewport`, as `volgraph view`
/// opens it with nothing else given (the benchmarks of the viewer share it).
pub(crate) fn open(
    gpu: &Arc<Gpu>,
    graph: PathBuf,
    volume: &std::path::Path,
    viewport: (u32, u32),
) -> anyhow::Result<LiveSession> {
    let args = session_args(graph, volume, viewport);
    LiveSession::open(gpu.clone(), &args).map(|(s, _)| s).map_err(|e| anyhow!("{}", volgraph_app::cli::error_text(&e)))
}

/// What `volgraph view GRAPH --volume VOLUME --size W×H` starts its session with (nothing else
/// given: the default TF, no scene, no features).
pub(crate) fn session_args(graph: PathBuf, volume: &std::path::Path, viewport: (u32, u32)) -> SessionArgs {
    SessionArgs {
        environment: None,
        graph,
        volume: vec![volume.to_path_buf()],
        raw: Default::default(),
        tf: None,
        tf_map: None,
        viewport,
        features: Vec::new(),
        shaders: None,
        gpu_memory_mb: None,
        memory_mb: None,
        scene: None,
        cuts: Default::default(),
        lights: Default::default(),
        named: Vec::new(),
        named_tfs: Vec::new(),
    }
}

/// Submits a frame of `camera` and waits for it: wall ms.
fn timed_frame(session: &mut LiveSession, camera: &OrbitCamera) -> anyhow::Result<f64> {
    let t0 = Instant::now();
    session.frame(camera, None).map_err(|e| anyhow!(e))?;
    session.runtime.finish();
    Ok(t0.elapsed().as_secs_f64() * 1e3)
}

/// Times `frames` TF edits, each moving the middle point's opacity as a drag in the editor
/// does, through the session: (median ms for the check + upload, median ms from the edit to
/// its frame finished).
fn time_tf_edits(session: &mut LiveSession, camera: &OrbitCamera, frames: u32) -> anyhow::Result<(f64, f64)> {
    let mut edits = Vec::new();
    let mut uploads = Vec::new();
    for i in 0..frames {
        let mut tf = session.transfer_function().clone();
        let k = tf.points.len() / 2;
        tf.points[k].alpha = (0.2 + 0.05 * (i % 8) as f64).min(1.0);
        let t0 = Instant::now();
        let events = session.edit_transfer_function(tf);
        if let Some(e) = events.iter().find(|e| matches!(e, volgraph_app::view::session::Event::Error { .. })) {
            return Err(anyhow!("TF edit: {e}"));
        }
        uploads.push(t0.elapsed().as_secs_f64() * 1e3);
        session.frame(camera, None).map_err(|e| anyhow!(e))?;
        session.runtime.finish();
        edits.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok((median(&uploads), median(&edits)))
}

/// Per pass: (id, wall ms in a steady frame, wall ms in the frame after a TF edit), each step
/// submitted on its own (the medians of 3).
fn pass_times_of_an_edit(session: &mut LiveSession, camera: &OrbitCamera) -> anyhow::Result<Vec<(String, f64, f64)>> {
    session.runtime.set_step_profiling(true);
    let profiled = |session: &mut LiveSession, edit: bool| -> anyhow::Result<Vec<Vec<(String, f64)>>> {
        (0..3)
            .map(|i| {
                if edit {
                    let mut tf = session.transfer_function().clone();
                    let k = tf.points.len() / 2;
                    tf.points[k].alpha = 0.3 + 0.05 * i as f64;
                    session.edit_transfer_function(tf);
                }
                session.frame(camera, None).map_err(|e| anyhow!(e))?;
                let stats = session.runtime.finish();
                Ok(stats.last().map(|s| s.per_pass_ms()).unwrap_or_default())
            })
            .collect()
    };
    timed_frame(session, camera)?;
    let steady = profiled(session, false)?;
    let edited = profiled(session, true)?;
    session.runtime.set_step_profiling(false);
    let median_of = |runs: &[Vec<(String, f64)>], pass: &str| {
        median(&runs.iter().filter_map(|r| r.iter().find(|(p, _)| p == pass).map(|(_, ms)| *ms)).collect::<Vec<_>>())
    };
    Ok(steady[0].iter().map(|(pass, _)| (pass.clone(), median_of(&steady, pass), median_of(&edited, pass))).collect())
}

/// Runs the benchmark, prints the tables and returns the JSON.
pub fn run(args: &WorkbenchArgs) -> anyhow::Result<serde_json::Value> {
    let viewport = volgraph_app::inputs::parse_size(&args.size)?;
    let volume = match &args.volume {
        Some(v) => v.clone(),
        None => {
            volgraph_accel::data_dir::dataset_path("engine_vollib").context("the engine dataset (set VOLGRAPH_DATA)")?
        }
    };
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.2, ..OrbitCamera::default() };

    // (a) TF edit → frame.
    let mut session = open(&gpu, args.graph.clone(), &volume, viewport)?;
    timed_frame(&mut session, &camera)?;
    let steady: Vec<f64> =
        (0..args.frames).map(|_| timed_frame(&mut session, &camera)).collect::<anyhow::Result<_>>()?;
    let steady_ms = median(&steady);
    let (upload_ms, edit_ms) = time_tf_edits(&mut session, &camera, args.frames)?;
    // The same view with the last edited TF: what the new TF costs by itself.
    let edited: Vec<f64> =
        (0..args.frames).map(|_| timed_frame(&mut session, &camera)).collect::<anyhow::Result<_>>()?;
    let edited_ms = median(&edited);
    // Dragging a point in the editor counts as motion for the level of detail (view/lod.rs),
    // so the frames that follow the drag are the coarse ones, as in the viewer.
    let mut lod = volgraph_app::view::lod::Lod::default();
    lod.observe(0, steady_ms);
    lod.moved();
    let coarse = lod.viewport(viewport);
    session.resize(coarse.0, coarse.1);
    let step = if session.set_step_factor(lod.step_factor()) { lod.step_factor() } else { 1.0 };
    timed_frame(&mut session, &camera)?;
    let (_, drag_edit_ms) = time_tf_edits(&mut session, &camera, args.frames)?;
    let lod_text = format!("{:.2} per axis, step ×{step}", coarse.0 as f64 / viewport.0 as f64);
    session.set_step_factor(1.0);
    session.resize(viewport.0, viewport.1);
    let passes = pass_times_of_an_edit(&mut session, &camera)?;
    drop(session);
    let mut md = format!(
        "# The viewer as a workbench (issue 24)\n\nMeasured through the viewer's session (no window) on {adapter}, \
         {} with {} at {}, medians of {} in one run.\n\n## From a TF edit to the first frame showing it (goal ≤ 50 ms)\n\n\
         Each edit moves the middle point's opacity, as a drag in the editor does; only what depends on the TF reruns \
         (the LUT upload, the empty-block classification and the distance map, then the frame).\n\n\
         | | ms |\n|---|---:|\n| steady frame (same view, no edit) | {steady_ms:.1} |\n| TF edit: check + LUT upload | {upload_ms:.2} |\n\
         | TF edit → full frame finished | {edit_ms:.1} |\n| steady frame with the edited TF | {edited_ms:.1} |\n\
         | TF point dragged → frame finished, at the viewer's level of detail ({lod_text}) | {drag_edit_ms:.1} |\n\n",
        volume.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default(),
        args.graph.display(),
        args.size,
        args.frames
    );
    md.push_str(
        "Where the time goes: one frame with every step submitted on its own and waited for \
         (`Runtime::set_step_profiling`; lavapipe's timestamps do not cover compute work), at full size:\n\n\
         | pass | steady frame ms | frame after a TF edit ms |\n|---|---:|---:|\n",
    );
    for (pass, steady, edited) in &passes {
        md.push_str(&format!("| {pass} | {steady:.1} | {edited:.1} |\n"));
    }
    md.push('\n');
    let mut drag_rows = Vec::new();
    if !args.no_drag {
        md.push_str(
            "## Frame time while the camera moves (goal ≤ 100 ms)\n\nFull: every frame at full resolution. With LOD: \
             the viewer's level of detail (`view/lod.rs`, target 15 fps) picks the scale from the full frame time and \
             doubles every raycaster's step (a slicer's slice distance, a multipass graph's segment length; ×4 or ×8 where \
             the coarsest scale still misses the target); \
             refined: from input at rest to the full image finished (the viewport restored, one frame).\n\n\
             | graph | full ms/frame | LOD | ms/frame while moving | within 100 ms | refined ms |\n\
             |---|---:|---:|---:|:---:|---:|\n",
        );
        for (name, _) in volgraph_app::builtin_graphs::EMBEDDED_GRAPHS {
            let mut session = match open(&gpu, PathBuf::from(name), &volume, viewport) {
                Ok(s) => s,
                Err(e) => {
                    md.push_str(&format!(
                        "| {name} | (does not open: {}) | |\n",
                        e.to_string().lines().next().unwrap_or("")
                    ));
                    continue;
                }
            };
            timed_frame(&mut session, &camera)?;
            let drag = |session: &mut LiveSession| -> anyhow::Result<f64> {
                let ms: Vec<f64> = (0..args.frames.min(4))
                    .map(|i| {
                        let moved = OrbitCamera { azimuth_deg: camera.azimuth_deg + 3.0 * (i + 1) as f64, ..camera };
                        timed_frame(session, &moved)
                    })
                    .collect::<anyhow::Result<_>>()?;
                Ok(median(&ms))
            };
            let full = drag(&mut session)?;
            let mut lod = volgraph_app::view::lod::Lod::default();
            lod.observe(0, full);
            lod.moved();
            let coarse_vp = lod.viewport(viewport);
            session.resize(coarse_vp.0, coarse_vp.1);
            let apply_step = |session: &mut LiveSession, lod: &mut volgraph_app::view::lod::Lod| {
                while lod.step_factor() > 1.0 && !session.set_step_factor(lod.step_factor()) {
                    lod.refuse_step();
                }
            };
            apply_step(&mut session, &mut lod);
            timed_frame(&mut session, &camera)?;
            // As the viewer does: coarse frames that still miss the target widen the step.
            for _ in 0..3 {
                let ms = timed_frame(&mut session, &camera)?;
                lod.moved();
                // Frames here are waited for one by one: each was rendered as set.
                lod.observe(0, ms);
                apply_step(&mut session, &mut lod);
            }
            let step = lod.step_factor();
            let moving = drag(&mut session)?;
            let t0 = Instant::now();
            session.set_step_factor(1.0);
            session.resize(viewport.0, viewport.1);
            timed_frame(&mut session, &camera)?;
            let refined = t0.elapsed().as_secs_f64() * 1e3;
            let scale = coarse_vp.0 as f64 / viewport.0 as f64;
            md.push_str(&format!(
                "| {name} | {full:.1} | {scale:.2}, step ×{step} | {moving:.1} | {} | {refined:.1} |\n",
                if moving <= 100.0 { "yes" } else { "no" }
            ));
            drag_rows.push(serde_json::json!({
                "graph": name, "full_ms_per_frame": full, "lod_scale": scale, "lod_step_factor": step, "moving_ms_per_frame": moving, "refined_ms": refined,
            }));
        }
    }
    println!("{md}");
    let value = serde_json::json!({
        "adapter": adapter, "size": args.size, "volume": volume.display().to_string(),
        "steady_frame_ms": steady_ms, "tf_upload_ms": upload_ms, "tf_edit_to_frame_ms": edit_ms,
        "steady_frame_edited_tf_ms": edited_ms, "tf_drag_to_lod_frame_ms": drag_edit_ms, "tf_drag_lod": lod_text,
        "pass_ms": passes.iter().map(|(p, s, e)| serde_json::json!({"pass": p, "steady_ms": s, "after_tf_edit_ms": e})).collect::<Vec<_>>(), "drag": drag_rows,
    });
    crate::report_files::write_markdown_and_json((args.markdown.as_deref(), &md), (args.json.as_deref(), &value))?;
    Ok(value)
}
