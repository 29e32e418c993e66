//! `volgraph view`: a window showing a graph live, with an egui overlay (per-pass GPU time, the
//! plan, every parameter, scalars, feature toggles) and hot reload of the graph, its shaders and
//! its transfer function. Failures show located diagnostics and keep the last good graph.
//! Scriptable for tests: `--frames N`, `--screenshot PATH`, and `--script` (lines on stdin:
//! `quit`, `screenshot PATH`, `param PASS.NAME VALUE`); one line per event on stdout.

pub mod graph_picture;
pub mod orbit;
pub mod panel;
pub mod session;
pub mod watch;
pub mod window;

#[cfg(test)]
mod tests;

use std::io::Write as _;
use std::path::PathBuf;

use volgraph_accel::camera::OrbitCamera;

use crate::cli::{CliError, RawArgs};
use crate::inputs;

/// The arguments of `volgraph view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// The graph file (RON); default: the scene's graph.
    pub graph: Option<PathBuf>,
    /// A scene file (scenes/*.ron): volume, transfer function, camera, viewport, graph, effects
    /// (on at start; the panel toggles them), precision; flags given as well win over it.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Volume file (.raw, .nrrd, .nhdr, .mhd, .mha); default: a generated Marschner–Lobb 64³.
    #[arg(long)]
    pub volume: Option<PathBuf>,
    #[command(flatten)]
    pub raw: RawArgs,
    /// Transfer function (RON, or ParaView color-map .json); watched for edits.
    #[arg(long)]
    pub tf: Option<PathBuf>,
    /// The colour map to use from a ParaView .json holding several.
    #[arg(long = "tf-map")]
    pub tf_map: Option<String>,
    /// Window size, WIDTHxHEIGHT [default: the scene's viewport, else 800x600].
    #[arg(long)]
    pub size: Option<String>,
    /// Orbit camera AZIMUTH,ELEVATION,DISTANCE (degrees, degrees, world units) [default: the
    /// scene's first camera, else 30,20,3.2].
    #[arg(long)]
    pub camera: Option<String>,
    /// Scene features on at start, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub features: Vec<String>,
    /// A shader folder to read and watch (default: `shaders/` beside the graph's workspace, if any;
    /// else the shaders built into the binary).
    #[arg(long)]
    pub shaders: Option<PathBuf>,
    /// GPU memory, in MiB, passes that stream data may hold (a brick pool) [default: what the
    /// adapter allows].
    #[arg(long = "gpu-memory-mb", value_parser = clap::value_parser!(u64).range(1..=1 << 24))]
    pub gpu_memory_mb: Option<u64>,
    /// Exit after this many presented frames.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: Option<u64>,
    /// Write the last frame here on exit (PNG; the graph output as presented, without the overlay).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Turn the camera this many degrees per frame.
    #[arg(long)]
    pub turn: Option<f64>,
    /// Start without the overlay panel (F1 toggles it).
    #[arg(long)]
    pub no_panel: bool,
    /// Read script lines from stdin: `quit`, `screenshot PATH`, `param PASS.NAME VALUE`.
    #[arg(long)]
    pub script: bool,
}

/// What only the window needs.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The start camera.
    pub camera: OrbitCamera,
    /// Exit after this many frames.
    pub frames: Option<u64>,
    /// Screenshot path on exit.
    pub screenshot: Option<PathBuf>,
    /// Panel shown at start.
    pub panel: bool,
    /// Degrees per frame.
    pub turn_degrees: Option<f64>,
}

/// Writes one event line to stdout, flushed (tests read it as it happens).
pub fn emit(event: &session::Event) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{event}");
    let _ = out.flush();
}

/// Runs `volgraph view`.
pub fn run(args: ViewArgs) -> Result<(), CliError> {
    let scene = args.scene.as_deref().map(crate::scene::Scene::load).transpose().map_err(|e| anyhow::anyhow!(e))?;
    let graph = match (&args.graph, scene.as_ref().and_then(|s| s.graph.clone())) {
        (Some(g), _) => g.clone(),
        (None, Some(g)) => g,
        (None, None) => {
            return Err(CliError::Other(anyhow::anyhow!(
                "no graph: give a graph file (volgraph view GRAPH), or a --scene whose file names one"
            )));
        }
    };
    let size = args.size.clone().or_else(|| scene.as_ref().and_then(|s| s.viewport).map(|(w, h)| format!("{w}x{h}")));
    let viewport = inputs::parse_size(size.as_deref().unwrap_or("800x600"))?;
    let camera = match (&args.camera, scene.as_ref().and_then(|s| s.camera.as_ref())) {
        (Some(text), _) => inputs::parse_camera(text)?,
        (None, Some(spec)) => spec.at(0),
        (None, None) => inputs::parse_camera("30,20,3.2")?,
    };
    if let Some(path) = &args.screenshot {
        let kind = crate::image_out::ImageKind::from_path(path)?;
        if kind != crate::image_out::ImageKind::Png {
            return Err(CliError::Other(anyhow::anyhow!(
                "--screenshot {}: screenshots are PNG; end the name in .png",
                path.display()
            )));
        }
    }
    let session_args = session::SessionArgs {
        graph,
        scene,
        volume: args.volume,
        raw: inputs::raw_options(&args.raw)?,
        tf: args.tf,
        tf_map: args.tf_map,
        viewport,
        features: args.features,
        shaders: args.shaders,
        gpu_memory_mb: args.gpu_memory_mb,
    };
    let view = ViewOptions {
        camera,
        frames: args.frames,
        screenshot: args.screenshot,
        panel: !args.no_panel,
        turn_degrees: args.turn,
    };
    let script = args.script.then(|| {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::stdin().lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
            let _ = tx.send("quit".to_string());
        });
        rx
    });
    window::run(session_args, view, script).map_err(|e| CliError::Other(anyhow::anyhow!(e)))
}
