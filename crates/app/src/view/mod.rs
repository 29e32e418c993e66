//! `volgraph view`: a window showing a graph live, with an egui overlay (per-pass GPU time, the
//! plan, every parameter, scalars, feature toggles) and hot reload of the graph, its shaders and
//! its transfer function. Failures show located diagnostics and keep the last good graph.
//! Scriptable for tests: `--frames N`, `--screenshot PATH`, and `--script` (lines on stdin:
//! `quit`, `screenshot PATH`, `param PASS.NAME VALUE`, `write`); one line per event on stdout.

pub mod accuracy;
pub mod graph_picture;
pub mod label_list;
pub mod light_control;
pub mod lod;
pub mod orbit;
pub mod orientation;
pub mod panel;
pub mod save_section;
pub mod script;
pub mod session;
pub mod slice_panes;
pub mod slice_section;
pub mod tf_editor;
pub mod watch;
pub mod window;
pub mod workbench;

#[cfg(test)]
mod tests;

use std::io::Write as _;
use std::path::PathBuf;

use volgraph_accel::camera::OrbitCamera;

use crate::cli::CliError;
use crate::inputs;

/// The arguments of `volgraph view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// What to show: graph, scene, volume, TF, camera, viewport.
    #[command(flatten)]
    pub inputs: crate::scene_args::SceneArgs,
    /// Exit after this many presented frames.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub frames: Option<u64>,
    /// Write the last frame here on exit (PNG; the graph output as presented, without the overlay).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Turn the camera this many degrees per frame (finite, -360..=360).
    #[arg(long, value_parser = parse_turn)]
    pub turn: Option<f64>,
    /// Start without the overlay panel (F1 toggles it).
    #[arg(long)]
    pub no_panel: bool,
    /// Open the axial, coronal and sagittal slice panes beside the 3D view (M toggles them).
    #[arg(long)]
    pub slices: bool,
    /// Read script lines from stdin: `quit`, `screenshot PATH`, `param PASS.NAME VALUE`, `write` (the
    /// panel's "write to graph file").
    #[arg(long)]
    pub script: bool,
}

/// `--turn DEGREES`: finite and at most a whole turn per frame (NaN would turn the camera
/// into NaN and draw nothing).
fn parse_turn(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= 360.0 => Ok(v),
        _ => Err(format!("\"{text}\": expected finite degrees per frame within -360..=360, e.g. 1.5")),
    }
}

/// Refuses a screenshot path that is no file to write: a FIFO (writing one blocks until a
/// reader comes, and the window with it), a directory, a device. The message names the path.
pub fn screenshot_target(path: &std::path::Path) -> Result<(), String> {
    match volgraph_accel::input_file::special_kind(path) {
        Ok(Some(kind)) => {
            Err(format!("{}: is {kind}, not a file to write a PNG screenshot to; give a file's path", path.display()))
        }
        _ => Ok(()),
    }
}

/// What only the window needs.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The start camera.
    pub camera: OrbitCamera,
    /// Nothing chose the camera: a volume in the patient frame opens in the anterior view.
    pub camera_is_default: bool,
    /// `--view NAME`: refused once the volume shows it lies outside the patient frame.
    pub patient_view: Option<String>,
    /// Exit after this many frames.
    pub frames: Option<u64>,
    /// Screenshot path on exit.
    pub screenshot: Option<PathBuf>,
    /// Panel shown at start.
    pub panel: bool,
    /// Degrees per frame.
    pub turn_degrees: Option<f64>,
    /// The slice panes open at start.
    pub slices: bool,
}

/// Writes one event line to stdout, flushed (tests read it as it happens).
pub fn emit(event: &session::Event) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{}", volgraph_core::terminal::escape_controls(&event.to_string()));
    let _ = out.flush();
}

/// A scene's named inputs, as `render --scene` takes them: where the command line names no
/// volume, the scene's `volume:` is the input `volume` (an empty path: loaded from the scene) and
/// its `volumes:` the others; its `tfs:` under the command line's of the same name.
fn with_scene_names(
    scene: Option<&crate::scene::Scene>,
    cli_volumes: &[PathBuf],
    mut named: Vec<(String, PathBuf)>,
    mut named_tfs: Vec<(String, PathBuf)>,
) -> (Vec<(String, PathBuf)>, Vec<(String, PathBuf)>) {
    let Some(scene) = scene else { return (named, named_tfs) };
    if cli_volumes.is_empty() && !scene.volumes.is_empty() {
        named = std::iter::once((volgraph_core::runtime::inputs::PRIMARY_VOLUME.to_string(), PathBuf::new()))
            .chain(scene.volumes.iter().cloned())
            .collect();
    }
    for (name, path) in &scene.tfs {
        if !named_tfs.iter().any(|(n, _)| n == name) {
            named_tfs.push((name.clone(), path.clone()));
        }
    }
    (named, named_tfs)
}

/// Runs `volgraph view`.
pub fn run(args: ViewArgs) -> Result<(), CliError> {
    let resolved = args.inputs.resolve("volgraph view GRAPH", "800x600")?;
    let viewport = inputs::parse_size(&resolved.size)?;
    let camera = resolved.camera.at(0);
    if let Some(path) = &args.screenshot {
        screenshot_target(path).map_err(|e| CliError::Other(anyhow::anyhow!("--screenshot {e}")))?;
        let kind = crate::image_out::ImageKind::from_path("--screenshot", path)?;
        if kind != crate::image_out::ImageKind::Png {
            return Err(CliError::Other(anyhow::anyhow!(
                "--screenshot {}: screenshots are PNG; end the name in .png",
                path.display()
            )));
        }
    }
    // Inputs by name, as `render` binds them: the frame volume (`volume`, else the first named)
    // is the one shown, probed and saved.
    let (tf, named_tfs) = crate::named_inputs::split_tfs(&args.inputs.tf)?;
    let named = crate::named_inputs::named_volumes(&args.inputs.volume)?;
    let (named, named_tfs) = with_scene_names(resolved.scene.as_ref(), &args.inputs.volume, named, named_tfs);
    let mut raw = inputs::raw_options(&args.inputs.raw)?;
    let volume = match named.get(crate::named_inputs::NamedBindings::primary_index(&named)) {
        // The scene's `volume:` (with_scene_names): loaded from the scene.
        Some((_, path)) if path.as_os_str().is_empty() => Vec::new(),
        Some((_, path)) => {
            let (file, options) = crate::named_inputs::path_and_frame(path, &raw);
            raw = options;
            vec![file]
        }
        None => args.inputs.volume,
    };
    let session_args = session::SessionArgs {
        graph: resolved.graph,
        scene: resolved.scene,
        volume,
        raw,
        named,
        named_tfs,
        tf,
        tf_map: args.inputs.tf_map,
        viewport,
        features: args.inputs.features,
        shaders: args.inputs.shaders,
        gpu_memory_mb: args.inputs.gpu_memory_mb,
        memory_mb: args.inputs.memory_mb,
        cuts: resolved.cuts,
        lights: resolved.lights,
        environment: resolved.environment,
    };
    let view = ViewOptions {
        camera,
        camera_is_default: resolved.camera_is_default,
        patient_view: args.inputs.view.clone(),
        frames: args.frames,
        screenshot: args.screenshot,
        panel: !args.no_panel,
        turn_degrees: args.turn,
        slices: args.slices,
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

#[cfg(test)]
mod scene_names {
    use std::path::{Path, PathBuf};

    use super::with_scene_names;

    /// A scene's `volumes:` and `tfs:` reach the viewer as `render --scene` takes them: its
    /// `volume:` is the input `volume`, the command line's names win.
    #[test]
    fn a_scenes_named_inputs_are_the_viewers() {
        let text = "Scene(graph: \"g.ron\", volume: Generated(\"organs32\"), volumes: {\"labels\": \"organs_labels32\"}, \
                    tfs: {\"label_table\": \"t.txt\", \"tf\": \"ct-bone\"})";
        let scene = crate::scene::Scene::from_str(text, Path::new("/scenes/s.ron")).expect("scene");
        let (named, tfs) = with_scene_names(Some(&scene), &[], Vec::new(), vec![("tf".into(), "ct-lung".into())]);
        let names: Vec<&str> = named.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["volume", "labels"]);
        assert_eq!(named[0].1, PathBuf::new(), "the scene's volume: loaded from the scene");
        let tf = tfs.iter().find(|(n, _)| n == "tf").map(|(_, p)| p.clone());
        assert_eq!(tf, Some(PathBuf::from("ct-lung")), "the command line's TF wins");
        assert!(tfs.iter().any(|(n, _)| n == "label_table"));
        // Volumes on the command line: the scene's names are not used.
        let (named, _) = with_scene_names(Some(&scene), &[PathBuf::from("ct.nii")], Vec::new(), Vec::new());
        assert!(named.is_empty());
    }
}
