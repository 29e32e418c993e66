//! The report of `volgraph bench graphs`: one row per measured case, serialized as JSON and
//! printed as a markdown table.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use super::accuracy::ImageError;

/// The whole run.
#[derive(Clone, Debug, Serialize)]
pub struct GraphBenchReport {
    /// `"volgraph bench graphs"`.
    pub program: String,
    /// The preset, if one was used.
    pub preset: Option<String>,
    /// What the preset reproduces.
    pub about: Option<String>,
    /// The adapter (`"llvmpipe (LLVM …) / Vulkan"` on lavapipe).
    pub adapter: String,
    /// Whether the adapter has timestamp queries (GPU time) or frames are wall-timed.
    pub timestamps: bool,
    /// Timed frames per case (after 1 warm-up frame).
    pub frames: u32,
    /// Untimed warm-up frames per case.
    pub warmup_frames: u32,
    /// Degrees the volume turns about y per frame.
    pub degrees_per_frame: f64,
    /// Start camera: azimuth, elevation (degrees), distance.
    pub camera: [f64; 3],
    /// Factor applied to every viewport.
    pub scale: f64,
    /// The graph speed-ups are relative to (file stem), measured in this run.
    pub baseline: String,
    /// `(graph, baseline)` pairs measured against their own baseline instead.
    pub baselines: Vec<(String, String)>,
    /// The swept `pass.param`, if any.
    pub sweep: Option<String>,
    /// Step of the converged CPU reference (voxels), when error is measured.
    pub reference_step_voxels: Option<f64>,
    /// How samples/pixel and error were obtained, in words.
    pub notes: Vec<String>,
    /// One row per measured case.
    pub rows: Vec<Row>,
    /// Cases or inputs that were skipped, with the reason.
    pub skipped: Vec<Skipped>,
    /// The preset's antialiasing study, when it has one.
    pub antialias: Option<super::antialias_study::AntialiasReport>,
    /// Pooled vs unpooled transient memory of the preset's graphs.
    pub memory: Vec<MemoryFigure>,
}

/// Transient memory of one graph's plan at one viewport.
#[derive(Clone, Debug, Serialize)]
pub struct MemoryFigure {
    /// Graph file.
    pub graph: String,
    /// Viewport.
    pub viewport: [u32; 2],
    /// Bytes of the pooled slots.
    pub pooled_bytes: u64,
    /// Bytes if every transient target had its own texture.
    pub unpooled_bytes: u64,
    /// Bytes of history (both frames).
    pub history_bytes: u64,
    /// Slots holding more than one target: their targets, in order.
    pub shared_slots: Vec<Vec<String>>,
}

/// Something that was not measured.
#[derive(Clone, Debug, Serialize)]
pub struct Skipped {
    /// The graph, dataset or case.
    pub what: String,
    /// Why.
    pub reason: String,
}

/// One case: graph × dataset × transfer function × viewport (× sweep value).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Graph file stem.
    pub graph: String,
    /// Graph file path as given.
    pub graph_file: String,
    /// Dataset name.
    pub dataset: String,
    /// Volume dimensions.
    pub dims: [u32; 3],
    /// Transfer-function preset.
    pub tf: String,
    /// Viewport in pixels.
    pub viewport: [u32; 2],
    /// The swept parameter's value, if sweeping.
    pub sweep_value: Option<String>,
    /// Median ms per frame (`clock` says which clock).
    pub median_ms: f64,
    /// Fastest frame, ms.
    pub min_ms: f64,
    /// Slowest frame, ms.
    pub max_ms: f64,
    /// Median wall ms per frame (render call to completion, CPU side).
    pub median_wall_ms: f64,
    /// `"gpu"` (timestamp queries) or `"wall"`.
    pub clock: String,
    /// Baseline median / this median, same dataset, TF, viewport and sweep value, same run.
    pub speedup_vs_baseline: Option<f64>,
    /// Median GPU ms per frame of each pass id (repeat groups summed); empty with wall time.
    pub pass_ms: BTreeMap<String, f64>,
    /// Average volume samples per pixel (CPU reference with the graph's raycast parameters).
    pub samples_per_pixel: Option<f64>,
    /// Size of the CPU reference image that counted them.
    pub spp_viewport: Option<[u32; 2]>,
    /// `samples_per_pixel · pixels / median time`, in millions per second.
    pub msamples_per_s: Option<f64>,
    /// Samples per pixel the GPU took, counted by the graph's own passes in an extra frame of
    /// the middle view (passes with `count_samples`; includes empty-space leaping).
    pub gpu_samples_per_pixel: Option<f64>,
    /// `gpu_samples_per_pixel · pixels / median time`, in millions per second.
    pub gpu_msamples_per_s: Option<f64>,
    /// The fetch ceiling of this dataset and viewport measured in the same run (`fetch_probe`:
    /// samples only, no compositing), millions of trilinear samples per second.
    pub fetch_ceiling_msamples_per_s: Option<f64>,
    /// `gpu_msamples_per_s / fetch_ceiling_msamples_per_s`.
    pub fraction_of_fetch_ceiling: Option<f64>,
    /// Error of the GPU image against the converged CPU reference.
    pub error: Option<ImageError>,
    /// Size of the images the error was measured on.
    pub error_viewport: Option<[u32; 2]>,
    /// On the Pareto front of (ms/frame, mean abs error) among the sweep values of this
    /// graph × dataset × TF × viewport.
    pub pareto: Option<bool>,
    /// What the passes reported about the last timed frame (`pass.counter`: a brick pool's
    /// `march.uploaded_bytes`, `march.pool_bytes`, ...).
    #[serde(default)]
    pub counters: BTreeMap<String, f64>,
    /// What the graph's bypasses did over the case's frames: "NAME left out in X of Y frames
    /// (last measure M/px, threshold T)" (Klein's reprojection skipped where it cannot pay).
    #[serde(default)]
    pub bypass: Vec<String>,
}

fn mib(bytes: u64) -> String {
    format!("{:.1}", bytes as f64 / (1024.0 * 1024.0))
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite()).map_or_else(|| "n/a".to_string(), |x| format!("{x:.digits$}"))
}

impl GraphBenchReport {
    /// The markdown table (with a short header naming adapter, clock and settings).
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let title = self.preset.as_deref().map_or_else(|| "ad hoc".to_string(), |p| format!("preset `{p}`"));
        let _ = writeln!(s, "## volgraph bench graphs — {title}\n");
        if let Some(about) = &self.about {
            let _ = writeln!(s, "{about}\n");
        }
        // What this run measured, from its rows: a preset given other graphs, datasets or
        // viewports on the command line is described by what ran, not by the preset's text.
        let distinct = |f: &dyn Fn(&Row) -> String| {
            let mut v: Vec<String> = Vec::new();
            for r in &self.rows {
                let x = f(r);
                if !v.contains(&x) {
                    v.push(x);
                }
            }
            v.join(", ")
        };
        let _ = writeln!(
            s,
            "Measured: graphs {}; datasets {}; TFs {}; viewports {}.\n",
            distinct(&|r| format!("`{}`", r.graph)),
            distinct(&|r| format!("{} ({}×{}×{})", r.dataset, r.dims[0], r.dims[1], r.dims[2])),
            distinct(&|r| r.tf.clone()),
            distinct(&|r| format!("{}×{}", r.viewport[0], r.viewport[1])),
        );
        let speedup = if self.baselines.is_empty() {
            format!("median of `{}` / median of the row", self.baseline)
        } else {
            let pairs: Vec<String> = self.baselines.iter().map(|(g, b)| format!("`{g}` against `{b}`")).collect();
            format!("median of the row's baseline / median of the row ({})", pairs.join(", "))
        };
        let clock = if self.timestamps { "GPU time from timestamp queries" } else { "wall time (no GPU timestamps)" };
        let _ = writeln!(
            s,
            "Adapter: {}. ms/frame: median of {} frames after {} warm-up frame, {clock}; volume turns {}°/frame about y from camera {:?}; viewport scale {}; speed-up = {speedup}, same run.\n",
            self.adapter, self.frames, self.warmup_frames, self.degrees_per_frame, self.camera, self.scale,
        );
        for note in &self.notes {
            let _ = writeln!(s, "- {note}");
        }
        if !self.notes.is_empty() {
            s.push('\n');
        }
        let sweeping = self.sweep.is_some();
        let errors = self.rows.iter().any(|r| r.error.is_some());
        let counted = self.rows.iter().any(|r| r.gpu_samples_per_pixel.is_some());
        let pooled = self.rows.iter().any(|r| r.counters.keys().any(|k| k.ends_with(".uploaded_bytes")));
        let mut header = vec!["graph", "dataset", "TF", "viewport"];
        let sweep_key = self.sweep.clone().unwrap_or_default();
        if sweeping {
            header.push(&sweep_key);
        }
        header.extend(["ms/frame", "clock", "speed-up", "samples/px", "Msamples/s"]);
        if counted {
            header.extend(["GPU samples/px", "GPU Msamples/s", "of fetch ceiling"]);
        }
        if pooled {
            header.extend(["uploaded MiB/frame", "batches", "pool MiB", "bricks drawn"]);
        }
        let bypassing = self.rows.iter().any(|r| !r.bypass.is_empty());
        if bypassing {
            header.push("bypass");
        }
        header.push("per pass (ms)");
        if errors {
            header.extend(["max err", "mean err", "PSNR dB"]);
        }
        if sweeping {
            header.push("Pareto");
        }
        let _ = writeln!(s, "| {} |", header.join(" | "));
        let _ = writeln!(s, "|{}|", header.iter().map(|_| "---").collect::<Vec<_>>().join("|"));
        for r in &self.rows {
            let mut cells = vec![
                r.graph.clone(),
                format!("{} {}×{}×{}", r.dataset, r.dims[0], r.dims[1], r.dims[2]),
                r.tf.clone(),
                format!("{}×{}", r.viewport[0], r.viewport[1]),
            ];
            if sweeping {
                cells.push(r.sweep_value.clone().unwrap_or_default());
            }
            let passes = r.pass_ms.iter().map(|(p, ms)| format!("{p} {ms:.2}")).collect::<Vec<_>>().join(", ");
            cells.extend([
                format!("{:.2}", r.median_ms),
                r.clock.clone(),
                r.speedup_vs_baseline.map_or_else(|| "n/a".to_string(), |x| format!("{x:.2}×")),
                opt(r.samples_per_pixel, 1),
                opt(r.msamples_per_s, 1),
            ]);
            if counted {
                cells.push(opt(r.gpu_samples_per_pixel, 1));
                cells.push(opt(r.gpu_msamples_per_s, 1));
                cells.push(
                    r.fraction_of_fetch_ceiling.map_or_else(|| "n/a".to_string(), |f| format!("{:.0} %", f * 100.0)),
                );
            }
            if pooled {
                let sum = |name: &str| {
                    let v: Vec<f64> =
                        r.counters.iter().filter(|(k, _)| k.ends_with(&format!(".{name}"))).map(|(_, v)| *v).collect();
                    (!v.is_empty()).then(|| v.iter().sum::<f64>())
                };
                let mib = |b: Option<f64>| b.map_or_else(|| "n/a".to_string(), |b| format!("{:.1}", b / 1048576.0));
                cells.push(mib(sum("uploaded_bytes")));
                cells.push(opt(sum("batches"), 0));
                cells.push(mib(sum("pool_bytes")));
                cells.push(match (sum("visible_bricks"), sum("bricks")) {
                    (Some(v), Some(t)) => format!("{v:.0}/{t:.0}"),
                    _ => "n/a".to_string(),
                });
            }
            if bypassing {
                cells.push(if r.bypass.is_empty() { "n/a".to_string() } else { r.bypass.join("; ") });
            }
            cells.push(if passes.is_empty() { "n/a".to_string() } else { passes });
            if errors {
                cells.push(opt(r.error.map(|e| e.max_abs), 4));
                cells.push(r.error.map_or_else(|| "n/a".to_string(), |e| format!("{:.2e}", e.mean_abs)));
                cells.push(r.error.map_or_else(|| "n/a".to_string(), |e| e.psnr_label()));
            }
            if sweeping {
                cells.push(if r.pareto == Some(true) { "★".to_string() } else { String::new() });
            }
            let _ = writeln!(s, "| {} |", cells.join(" | "));
        }
        if let Some(aa) = &self.antialias {
            s.push_str(&aa.to_markdown());
        }
        if !self.memory.is_empty() {
            let _ = writeln!(s, "\n### Transient memory\n");
            for m in &self.memory {
                let shared: Vec<String> = m.shared_slots.iter().map(|h| h.join(" + ")).collect();
                let _ = writeln!(
                    s,
                    "- `{}` at {}×{}: pooled {} MiB, unpooled {} MiB ({:.1} % of unpooled); history {} MiB; shared slots: {}",
                    m.graph,
                    m.viewport[0],
                    m.viewport[1],
                    mib(m.pooled_bytes),
                    mib(m.unpooled_bytes),
                    100.0 * m.pooled_bytes as f64 / m.unpooled_bytes.max(1) as f64,
                    mib(m.history_bytes),
                    if shared.is_empty() { "none".to_string() } else { shared.join("; ") }
                );
            }
        }
        if !self.skipped.is_empty() {
            let _ = writeln!(s, "\nSkipped:");
            for k in &self.skipped {
                let _ = writeln!(s, "- {}: {}", k.what, k.reason);
            }
        }
        s
    }
}
