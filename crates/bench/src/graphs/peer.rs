//! A preset's peer measured in the same run: an external program (VTK's CPU raycaster, through
//! `bench/peer/vtk_cpu_raycast.py`) renders the preset's dataset/TF pairs at the same viewport,
//! step and views, and its median ms per frame become rows of the same table — so the speed-up
//! column is a ratio measured side by side, not a figure copied from elsewhere. When the peer
//! cannot run (no `python3`, no `vtk` module) the rows are missing and a note says how to
//! install it.

use std::path::Path;
use std::process::{Command, Stdio};

use serde::Deserialize;

use super::report::Row;

/// How to run a preset's peer.
#[derive(Clone, Copy, Debug)]
pub struct PeerSpec {
    /// The label of its rows (the "graph" column; may be the preset's baseline).
    pub label: &'static str,
    /// What it is, for the notes.
    pub about: &'static str,
    /// The script's name in reports (its path in the source tree).
    pub script: &'static str,
    /// The script's text, compiled in and handed to `python3` on its standard input, so the peer
    /// runs from any folder.
    pub script_text: &'static str,
    /// How to make it runnable, for the note when it is not.
    pub install: &'static str,
}

/// One dataset/TF pair for the peer: names it can find in `$VOLGRAPH_DATA`.
#[derive(Clone, Debug)]
pub struct PeerCase {
    /// Dataset name (`$VOLGRAPH_DATA/volumes/<name>_XxYxZ_uint8.raw`).
    pub dataset: String,
    /// Transfer-function name (`$VOLGRAPH_DATA/tf/<name>.ron`).
    pub tf: String,
}

#[derive(Deserialize)]
struct PeerOutput {
    vtk: String,
    mapper: String,
    rows: Vec<PeerRow>,
}

#[derive(Deserialize)]
struct PeerRow {
    dataset: String,
    tf: String,
    dims: [u32; 3],
    viewport: [u32; 2],
    frames_ms: Vec<f64>,
    median_ms: f64,
}

/// What the peer gave: its rows and a line naming what ran.
pub struct PeerResult {
    /// One row per case.
    pub rows: Vec<Row>,
    /// e.g. "VTK 9.7.2 vtkFixedPointVolumeRayCastMapper".
    pub ran: String,
}

/// Runs the peer on `cases` at `viewport` with `frames` views over a full turn and step
/// `step_voxels`; an error says why it could not (and how to fix that).
pub fn run(
    spec: &PeerSpec,
    data_dir: &Path,
    cases: &[PeerCase],
    viewport: (u32, u32),
    frames: u32,
    step_voxels: f64,
) -> Result<PeerResult, String> {
    let pairs: Vec<String> = cases.iter().map(|c| format!("{}:{}", c.dataset, c.tf)).collect();
    // The script goes to python3 on its standard input: nothing is written to disk.
    let mut child = Command::new("python3")
        .arg("-")
        .arg("--data")
        .arg(data_dir)
        .arg("--cases")
        .arg(pairs.join(","))
        .arg("--size")
        .arg(format!("{}x{}", viewport.0, viewport.1))
        .arg("--frames")
        .arg(frames.to_string())
        .arg("--step")
        .arg(step_voxels.to_string())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start python3 ({e}); {}", spec.install))?;
    if let Some(mut stdin) = child.stdin.take() {
        use std::io::Write as _;
        stdin
            .write_all(spec.script_text.as_bytes())
            .map_err(|e| format!("cannot hand {} to python3: {e}", spec.script))?;
    }
    let output = child.wait_with_output().map_err(|e| format!("{}: {e}", spec.script))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message");
        return Err(format!("{} failed: {last}; {}", spec.script, spec.install));
    }
    let parsed: PeerOutput = serde_json::from_slice(&output.stdout)
        .map_err(|e| format!("{} printed no report it understands: {e}", spec.script))?;
    let rows = parsed
        .rows
        .into_iter()
        .map(|r| Row {
            graph: spec.label.to_string(),
            graph_file: spec.script.to_string(),
            dataset: r.dataset,
            dims: r.dims,
            tf: r.tf,
            viewport: r.viewport,
            sweep_value: None,
            median_ms: r.median_ms,
            min_ms: r.frames_ms.iter().copied().fold(f64::INFINITY, f64::min),
            max_ms: r.frames_ms.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            median_wall_ms: r.median_ms,
            clock: "wall".to_string(),
            speedup_vs_baseline: None,
            pass_ms: Default::default(),
            samples_per_pixel: None,
            spp_viewport: None,
            msamples_per_s: None,
            gpu_samples_per_pixel: None,
            gpu_msamples_per_s: None,
            fetch_ceiling_msamples_per_s: None,
            fraction_of_fetch_ceiling: None,
            error: None,
            error_viewport: None,
            pareto: None,
            counters: Default::default(),
            bypass: Vec::new(),
        })
        .collect();
    Ok(PeerResult { rows, ran: format!("VTK {} {}", parsed.vtk, parsed.mapper) })
}
