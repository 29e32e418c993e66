//! `volgraph bench api`: one frame through the library API (`volgraph_app::api::Renderer`, what
//! the Python package wraps) — render, wait, read the output back — the median of `frames`
//! after a warm-up, so the Python layer's own cost is `Renderer.render` in Python minus this
//! (crates/python/bench_overhead.py prints both).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::anyhow;
use volgraph_app::api::{Camera, Renderer};

use crate::graphs::measure::median;

/// `bench api` arguments.
#[derive(clap::Args, Debug)]
pub struct ApiArgs {
    /// The volume: a file, a dataset's or a generated volume's name.
    #[arg(long, default_value = "engine_vollib")]
    pub volume: PathBuf,
    /// The graph (a file or a built-in name).
    #[arg(long, default_value = "modern/fastest")]
    pub graph: PathBuf,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Timed frames (the median is reported).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
}

/// Runs the benchmark and prints the median ms per frame.
pub fn run(args: &ApiArgs) -> anyhow::Result<f64> {
    let size = volgraph_app::inputs::parse_size(&args.size)?;
    let shown = volgraph_app::scene::load_shown_volume(
        std::slice::from_ref(&args.volume),
        None,
        &volgraph_accel::load::LoadOptions::default(),
    )?;
    let mut r = Renderer::new(&args.graph, size).map_err(|e| anyhow!("{e}"))?;
    r.set_volume(shown.volume, shown.marschner_lobb_tf);
    let camera = Camera::Orbit(30.0, 20.0, 3.2);
    let mut times = Vec::new();
    for i in 0..=args.frames {
        let t0 = Instant::now();
        r.render(&camera, None).map_err(|e| anyhow!("{e}"))?;
        if i > 0 {
            times.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    let ms = median(&times);
    println!(
        "api: {} on {} at {}, render + wait + read back: {ms:.2} ms (median of {})",
        args.graph.display(),
        args.volume.display(),
        args.size,
        args.frames
    );
    Ok(ms)
}
