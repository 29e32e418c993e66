//! `volgraph bench slices`: the clinical viewer's slice panes (issue 45), measured through the
//! viewer's own session (`LiveSession` and its `SlicePanes`, no window):
//! - a pane update when the crosshair moves — compile the slice graph with the new position,
//!   write it in place, render the three panes and wait (goal ≤ 30 ms at 512² panes on lavapipe),
//!   for a click (two planes move) and a wheel notch (one plane moves);
//! - the 3D view's frame with the panes open against without, as the window lays them out: the
//!   image alone, or its four-up (the 3D view in a quarter, three panes beside it), the panes
//!   resting (drawn, not rendered) or following a crosshair dragged every frame.
//!
//! All cases run side by side in one process on one device; medians after a warm-up (JIT).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use glam::DVec2;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reslice::SliceAxis;
use volgraph_app::view::session::LiveSession;
use volgraph_app::view::slice_panes::FourUp;
use volgraph_core::runtime::Gpu;

use crate::graphs::measure::median;

/// `bench slices` arguments.
#[derive(clap::Args, Debug)]
pub struct SlicesArgs {
    /// The volume: a file, a dataset's or a generated volume's name (default: the engine).
    #[arg(long, default_value = "engine_vollib")]
    pub volume: PathBuf,
    /// The 3D view's graph (a file or a built-in name).
    #[arg(long, default_value = "modern/fastest")]
    pub graph: PathBuf,
    /// The image region beside the panel, WIDTHxHEIGHT: the four-up gives each pane a quarter.
    #[arg(long, default_value = "1024x1024")]
    pub size: String,
    /// Timed updates and frames per case (the median is reported).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the tables as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// A crosshair move of case `i`: a click on the coronal pane at a point that walks across it
/// (two planes move), or a wheel notch on the axial pane (one plane moves).
fn move_crosshair(session: &mut LiveSession, pane: (u32, u32), i: u32, click: bool) -> anyhow::Result<()> {
    let panes = session.slices_mut().context("the panes are open")?;
    if click {
        let t = 0.2 + 0.6 * f64::from(i % 16) / 15.0;
        let fit = panes.fit(SliceAxis::Coronal, pane);
        panes.click(SliceAxis::Coronal, pane, fit.point(DVec2::new(t, 1.0 - t)));
    } else {
        panes.scroll(SliceAxis::Axial, if i % 32 < 16 { 1 } else { -1 });
    }
    Ok(())
}

/// Median ms of `n` pane updates after crosshair moves (each rendered and waited for).
fn time_updates(session: &mut LiveSession, pane: (u32, u32), n: u32, click: bool) -> anyhow::Result<f64> {
    let mut times = Vec::new();
    for i in 0..n + 1 {
        move_crosshair(session, pane, i, click)?;
        let t0 = Instant::now();
        session.slices_mut().context("open")?.update(pane).map_err(|e| anyhow!(e))?;
        if i > 0 {
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    Ok(median(&times))
}

/// Median wall ms of `n` frames of the 3D view (submitted and waited for), each after `between`.
fn time_frames(
    session: &mut LiveSession,
    camera: &OrbitCamera,
    n: u32,
    mut between: impl FnMut(&mut LiveSession, u32) -> anyhow::Result<()>,
) -> anyhow::Result<f64> {
    let mut times = Vec::new();
    for i in 0..n + 1 {
        let t0 = Instant::now();
        between(session, i)?;
        session.frame(camera, None).map_err(|e| anyhow!(e))?;
        session.runtime.finish();
        if i > 0 {
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    Ok(median(&times))
}

/// Runs the benchmark, prints the tables and returns the JSON.
pub fn run(args: &SlicesArgs) -> anyhow::Result<serde_json::Value> {
    let image = volgraph_app::inputs::parse_size(&args.size)?;
    let layout = FourUp::of(image);
    let pane = layout.pane();
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.2, ..OrbitCamera::default() };
    let mut session = crate::workbench::open(&gpu, args.graph.clone(), &args.volume, image)?;
    let volume = session.volume();
    let volume_text = format!("{} ({}×{}×{})", volume.name, volume.dims.x, volume.dims.y, volume.dims.z);

    // The 3D view alone, the whole image.
    let alone = time_frames(&mut session, &camera, args.frames, |_, _| Ok(()))?;
    // The four-up: the 3D view in a quarter.
    session.resize(pane.0, pane.1);
    let quarter = time_frames(&mut session, &camera, args.frames, |_, _| Ok(()))?;
    if let Some(e) = session.set_slice_panes(true).first() {
        return Err(anyhow!("{e}"));
    }
    session.slices_mut().context("open")?.update(pane).map_err(|e| anyhow!(e))?;
    let resting = time_frames(&mut session, &camera, args.frames, |s, _| {
        s.slices_mut().context("open")?.update(pane).map(drop).map_err(|e| anyhow!(e))
    })?;
    let dragged = time_frames(&mut session, &camera, args.frames, |s, i| {
        move_crosshair(s, pane, i, true)?;
        s.slices_mut().context("open")?.update(pane).map(drop).map_err(|e| anyhow!(e))
    })?;
    let click_ms = time_updates(&mut session, pane, args.frames, true)?;
    let wheel_ms = time_updates(&mut session, pane, args.frames, false)?;
    drop(session);

    let goal = if click_ms <= 30.0 && wheel_ms <= 30.0 { "met" } else { "not met" };
    let text = format!(
        "# Slice panes (issue 45)\n\nMeasured through the viewer's session (no window) on {adapter}: {volume_text} \
         with {} in a {}×{} image, medians of {} in one run.\n\n\
         ## Pane update when the crosshair moves (goal ≤ 30 ms at 512²: {goal})\n\n\
         The slice graph (`clinical/slices`) compiled with the new positions, written in place, the three {}×{} panes \
         rendered and waited for.\n\n\
         | move | ms |\n|---|---:|\n| click on the coronal pane (two planes move) | {click_ms:.2} |\n\
         | wheel notch on the axial pane (one plane moves) | {wheel_ms:.2} |\n\n\
         ## The 3D view's frame with the panes open vs without\n\n\
         As the window lays them out: the image alone, or the four-up (3D view top left, a quarter of the image).\n\n\
         | layout | ms/frame | vs the image alone |\n|---|---:|---:|\n\
         | 3D view alone, {}×{} | {alone:.1} | 1.00 |\n\
         | four-up: 3D view {}×{}, panes closed | {quarter:.1} | {:.2} |\n\
         | four-up: 3D view + three panes at rest (nothing to render) | {resting:.1} | {:.2} |\n\
         | four-up: 3D view + three panes following a crosshair dragged every frame | {dragged:.1} | {:.2} |\n",
        args.graph.display(),
        image.0,
        image.1,
        args.frames,
        pane.0,
        pane.1,
        image.0,
        image.1,
        pane.0,
        pane.1,
        quarter / alone,
        resting / alone,
        dragged / alone,
    );
    println!("{text}");
    let value = serde_json::json!({
        "adapter": adapter,
        "volume": volume_text,
        "graph": args.graph.display().to_string(),
        "image": [image.0, image.1],
        "pane": [pane.0, pane.1],
        "frames": args.frames,
        "update_ms": {"click": click_ms, "wheel": wheel_ms, "goal_ms": 30.0},
        "frame_ms": {"alone": alone, "four_up_closed": quarter, "four_up_resting": resting, "four_up_dragged": dragged},
    });
    crate::report_files::write_markdown_and_json((args.markdown.as_deref(), &text), (args.json.as_deref(), &value))?;
    Ok(value)
}
