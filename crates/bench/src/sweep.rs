//! `volgraph sweep`: what accuracy costs in time, every knob in one command. Each knob — step
//! size, termination threshold, accumulation precision, empty-space block size, shading,
//! pre-integration, jitter, reconstruction filter — is swept alone on the graph it matters to,
//! over several datasets, with the error of every image against the converged f64 reference of
//! the same model (same effects, step 0.1 voxel, no termination) beside the median ms per frame
//! and the samples per pixel counted on the GPU. One table, one JSON row per (knob, value,
//! dataset), one error-vs-time plot per knob with the Pareto front marked. `docs/accuracy.md`
//! shows the plots and the defaults chosen from them.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context as _, anyhow, bail};
use serde::Serialize;

use crate::graphs::GraphsArgs;

/// One knob: what it sweeps, on which graph, and why there.
#[derive(Clone, Copy, Debug)]
pub struct Knob {
    /// Its name in `--knobs` and the JSON.
    pub name: &'static str,
    /// The graph swept (workspace-relative).
    pub graph: &'static str,
    /// The `--sweep` of `volgraph bench graphs`.
    pub sweep: &'static str,
    /// The value graphs/scenes use by default.
    pub default: &'static str,
}

/// Every knob. The single-pass knobs are swept on the fastest graph (samples counted on the GPU);
/// precision on Krüger–Westermann's multipass loop, whose accumulation target it is.
pub const KNOBS: [Knob; 8] = [
    Knob { name: "step", graph: "graphs/modern/fastest.ron", sweep: "march.step_voxels=0.25,0.5,1,2", default: "0.5" },
    Knob {
        name: "threshold",
        graph: "graphs/modern/fastest.ron",
        sweep: "march.threshold=0.9,0.95,0.99,0.996078431372549,1",
        default: "0.996078431372549",
    },
    Knob {
        name: "precision",
        graph: "graphs/kruger_westermann_2003/rc.ron",
        sweep: "scene.precision=f16,f32",
        default: "f32",
    },
    Knob { name: "block_size", graph: "graphs/modern/fastest.ron", sweep: "input.block_size=4,8,16", default: "4" },
    Knob { name: "shading", graph: "graphs/modern/fastest.ron", sweep: "feature.shading=off,on", default: "off" },
    Knob {
        name: "preintegration",
        graph: "graphs/modern/fastest.ron",
        sweep: "feature.preintegration=off,on",
        default: "off",
    },
    Knob { name: "jitter", graph: "graphs/modern/fastest.ron", sweep: "feature.jitter=off,on", default: "off" },
    Knob { name: "filter", graph: "graphs/modern/fastest.ron", sweep: "feature.tricubic=off,on", default: "off" },
];

/// Flags of `volgraph sweep`.
#[derive(clap::Args, Debug, Clone)]
pub struct SweepArgs {
    /// Knobs, comma separated (default: every one): step, threshold, precision, block_size,
    /// shading, preintegration, jitter, filter.
    #[arg(long, value_delimiter = ',')]
    pub knobs: Vec<String>,
    /// Datasets, comma separated (generated ml64 plus real ones, as for `bench graphs`).
    #[arg(long, value_delimiter = ',', default_value = "ml64,hydrogen_atom,neghip,fuel")]
    pub datasets: Vec<String>,
    /// Viewport WIDTHxHEIGHT of the timed frames.
    #[arg(long, default_value = "256x256")]
    pub size: String,
    /// Timed frames per case (after one warm-up frame).
    #[arg(long, default_value_t = 6)]
    pub frames: u32,
    /// Longest side of the images compared with the reference.
    #[arg(long, default_value_t = 128)]
    pub accuracy_size: u32,
    /// Write every row as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write one error-vs-time plot per knob into this folder (`<knob>.png`).
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Also write the markdown table here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// One JSON row.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// The knob.
    pub knob: String,
    /// Its value.
    pub value: String,
    /// The dataset.
    pub dataset: String,
    /// The graph swept.
    pub graph: String,
    /// Median ms per frame.
    pub median_ms: f64,
    /// `"gpu"` or `"wall"`.
    pub clock: String,
    /// Largest absolute channel error against the converged reference.
    pub max_error: Option<f64>,
    /// Mean absolute channel error.
    pub mean_error: Option<f64>,
    /// PSNR for a peak of 1 (`None` when identical).
    pub psnr_db: Option<f64>,
    /// Samples per pixel counted on the GPU (graphs with a counting pass).
    pub gpu_samples_per_pixel: Option<f64>,
    /// Samples per pixel of the CPU reference (graphs without one).
    pub samples_per_pixel: Option<f64>,
    /// On the Pareto front of (ms, mean error) for this knob and dataset.
    pub pareto: Option<bool>,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct SweepReport {
    /// `"volgraph sweep"`.
    pub program: String,
    /// The adapter.
    pub adapter: String,
    /// Viewport of the timed frames.
    pub viewport: [u32; 2],
    /// Size of the compared images (longest side).
    pub accuracy_size: u32,
    /// Step of the converged reference, voxels.
    pub reference_step_voxels: f64,
    /// Rows.
    pub rows: Vec<SweepRow>,
    /// The pre-integration table rebuilt after a TF change: extra ms of that frame over a steady
    /// one (median of several changes), and the steady frame's ms.
    pub preintegration_rebuild: Option<TableRebuild>,
    /// What was skipped and why.
    pub skipped: Vec<String>,
}

/// What rebuilding the pre-integration table costs.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TableRebuild {
    /// The dataset and viewport the frames drew.
    pub viewport: [u32; 2],
    /// Median ms of a frame right after a TF change (table rebuilt).
    pub changed_ms: f64,
    /// Median ms of a steady frame (table reused).
    pub steady_ms: f64,
    /// `changed_ms - steady_ms`.
    pub rebuild_ms: f64,
}

/// Times frames of `graphs/modern/fastest.ron` with pre-integration on ml64: steady frames, and
/// frames right after the TF changed (alternating two TFs), so the difference is the table's
/// rebuild on the GPU.
pub fn measure_table_rebuild(
    gpu: std::sync::Arc<volgraph_core::runtime::Gpu>,
    viewport: (u32, u32),
) -> anyhow::Result<TableRebuild> {
    use volgraph_accel::transfer_function::{Preset, TransferFunction};
    use volgraph_core::runtime::{CameraData, Runtime, ShaderLibrary};
    let path = PathBuf::from("graphs/modern/fastest.ron");
    let source = volgraph_app::inputs::read_graph(&path)?;
    let registry = volgraph_app::registry();
    let (sources, _) = volgraph_app::shader_dir::sources_for(&path, None);
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
    let volume = volgraph_accel::generate::marschner_lobb(64);
    let luts: Vec<Vec<[f32; 4]>> = [Preset::Default, Preset::Sparse]
        .into_iter()
        .map(|p| TransferFunction::preset(p, volume.value_range).to_lut_for(&volume, volgraph_app::inputs::LUT_SIZE))
        .collect();
    let options = volgraph_core::CompileOptions::new(viewport.0, viewport.1).with_features(["preintegration"]);
    let plan = runtime.compile("fastest.ron", &source, &registry, &options).map_err(|d| anyhow!("{d}"))?;
    let inputs = plan.inputs.clone();
    runtime.bind_scene(&inputs, &volume, &luts[0]).map_err(|e| anyhow!(e))?;
    runtime.apply(plan, &registry).map_err(|e| anyhow!(e))?;
    let camera = CameraData::from_orbit(&volgraph_accel::camera::OrbitCamera::default(), viewport);
    let frame =
        |runtime: &mut Runtime| -> anyhow::Result<f64> { Ok(runtime.render(camera).map_err(|e| anyhow!(e))?.frame_ms) };
    for _ in 0..3 {
        frame(&mut runtime)?;
    }
    let (mut changed, mut steady) = (Vec::new(), Vec::new());
    for i in 0..7 {
        runtime.bind_scene(&inputs, &volume, &luts[(i + 1) % 2]).map_err(|e| anyhow!(e))?;
        changed.push(frame(&mut runtime)?);
        steady.push(frame(&mut runtime)?);
    }
    let (changed_ms, steady_ms) = (crate::graphs::measure::median(&changed), crate::graphs::measure::median(&steady));
    Ok(TableRebuild { viewport: [viewport.0, viewport.1], changed_ms, steady_ms, rebuild_ms: changed_ms - steady_ms })
}

fn chosen(args: &SweepArgs) -> anyhow::Result<Vec<Knob>> {
    if args.knobs.is_empty() {
        return Ok(KNOBS.to_vec());
    }
    args.knobs
        .iter()
        .map(|name| {
            KNOBS.iter().copied().find(|k| k.name == name).ok_or_else(|| {
                let names: Vec<&str> = KNOBS.iter().map(|k| k.name).collect();
                anyhow!(
                    "--knobs {name}: {}",
                    volgraph_core::suggest::guess_then(
                        name,
                        names.iter().copied(),
                        "",
                        format!("the knobs are: {}", names.join(", "))
                    )
                )
            })
        })
        .collect()
}

/// Runs `volgraph sweep`.
pub fn run(args: &SweepArgs) -> anyhow::Result<SweepReport> {
    let knobs = chosen(args)?;
    if args.frames == 0 {
        bail!("--frames 0: at least one timed frame is needed");
    }
    let viewport = volgraph_app::inputs::parse_size(&args.size)?;
    if let Some(dir) = &args.plots {
        std::fs::create_dir_all(dir).with_context(|| format!("--plots {}: cannot create the folder", dir.display()))?;
    }
    let gpu = std::sync::Arc::new(volgraph_core::runtime::Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let reference_step = 0.1;
    for knob in &knobs {
        volgraph_app::stdout::eprintln_escaped!("sweep {}: {} on {}", knob.name, knob.sweep, args.datasets.join(", "));
        let graphs_args = GraphsArgs {
            graphs: vec![PathBuf::from(knob.graph)],
            datasets: args.datasets.clone(),
            size: vec![args.size.clone()],
            scale: 1.0,
            frames: Some(args.frames),
            sweep: Some(knob.sweep.to_string()),
            accuracy_size: args.accuracy_size,
            reference_step,
            spp_size: 64,
            quiet: true,
            plot: args.plots.as_ref().map(|d| d.join(format!("{}.png", knob.name))),
            ..GraphsArgs::default()
        };
        let config = graphs_args.resolve()?;
        let report = crate::graphs::run::run(gpu.clone(), &config)?;
        if let Some(plot) = &config.plot {
            crate::graphs::plot::write_plot(plot, &report)?;
        }
        skipped.extend(report.skipped.iter().map(|s| format!("{}: {}: {}", knob.name, s.what, s.reason)));
        for r in report.rows {
            rows.push(SweepRow {
                knob: knob.name.to_string(),
                value: r.sweep_value.clone().unwrap_or_default(),
                dataset: r.dataset.clone(),
                graph: r.graph.clone(),
                median_ms: r.median_ms,
                clock: r.clock.clone(),
                max_error: r.error.map(|e| e.max_abs),
                mean_error: r.error.map(|e| e.mean_abs),
                psnr_db: r.error.and_then(|e| e.psnr_db),
                gpu_samples_per_pixel: r.gpu_samples_per_pixel,
                samples_per_pixel: r.samples_per_pixel,
                pareto: r.pareto,
            });
        }
    }
    let preintegration_rebuild = if knobs.iter().any(|k| k.name == "preintegration") {
        match measure_table_rebuild(gpu.clone(), viewport) {
            Ok(t) => Some(t),
            Err(e) => {
                skipped.push(format!("pre-integration table rebuild: {e:#}"));
                None
            }
        }
    } else {
        None
    };
    let report = SweepReport {
        program: "volgraph sweep".to_string(),
        preintegration_rebuild,
        adapter: gpu.adapter_name.clone(),
        viewport: [viewport.0, viewport.1],
        accuracy_size: args.accuracy_size,
        reference_step_voxels: reference_step,
        rows,
        skipped,
    };
    let markdown = to_markdown(&report, &knobs);
    volgraph_app::stdout::write_stdout(&markdown)?;
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)? + "\n")
            .with_context(|| format!("--json {}: cannot write the file", path.display()))?;
    }
    if let Some(path) = &args.markdown {
        std::fs::write(path, &markdown)
            .with_context(|| format!("--markdown {}: cannot write the file", path.display()))?;
    }
    Ok(report)
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite()).map_or_else(|| "n/a".to_string(), |x| format!("{x:.digits$}"))
}

/// The markdown table.
pub fn to_markdown(r: &SweepReport, knobs: &[Knob]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## volgraph sweep — what accuracy costs\n");
    let _ = writeln!(
        s,
        "Adapter: {}. {}×{} timed frames (median, {} clock); error of a {}-px image against the f64 reference of the \
         same model at step {} voxel, no termination (max and mean absolute, premultiplied RGBA; PSNR for a peak of 1). \
         ★: on the Pareto front of (ms, mean error) for the knob and dataset.\n",
        r.adapter,
        r.viewport[0],
        r.viewport[1],
        r.rows.first().map_or("wall", |row| row.clock.as_str()),
        r.accuracy_size,
        r.reference_step_voxels
    );
    let _ = writeln!(
        s,
        "| knob | value | dataset | graph | ms/frame | max err | mean err | PSNR dB | samples/px | Pareto |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for row in &r.rows {
        let default = knobs.iter().find(|k| k.name == row.knob).is_some_and(|k| {
            let value = row.value.as_str();
            k.default == value
                || (k.default == "off" && value == "off")
                || value.parse::<f64>().ok().zip(k.default.parse::<f64>().ok()).is_some_and(|(a, b)| a == b)
        });
        let spp = row.gpu_samples_per_pixel.map(|v| format!("{v:.1} (GPU)")).unwrap_or_else(|| {
            row.samples_per_pixel.map_or_else(|| "n/a".to_string(), |v| format!("{v:.1} (CPU ref.)"))
        });
        let _ = writeln!(
            s,
            "| {} | {}{} | {} | {} | {:.2} | {} | {} | {} | {} | {} |",
            row.knob,
            row.value,
            if default { " (default)" } else { "" },
            row.dataset,
            row.graph,
            row.median_ms,
            opt(row.max_error, 4),
            row.mean_error.map_or_else(|| "n/a".to_string(), |e| format!("{e:.2e}")),
            row.psnr_db.map_or_else(
                || if row.max_error == Some(0.0) { "∞".to_string() } else { "n/a".to_string() },
                |p| format!("{p:.1}")
            ),
            spp,
            if row.pareto == Some(true) { "★" } else { "" }
        );
    }
    if let Some(t) = &r.preintegration_rebuild {
        let _ = writeln!(
            s,
            "\nPre-integration table (256², on the GPU) after a TF change: {:.2} ms more than a steady frame ({:.2} vs {:.2} ms, \
             fastest.ron on ml64 at {}×{}, median of 7 changes).",
            t.rebuild_ms, t.changed_ms, t.steady_ms, t.viewport[0], t.viewport[1]
        );
    }
    let ratios: Vec<String> = r
        .rows
        .iter()
        .filter(|row| row.knob == "filter" && row.value == "on")
        .filter_map(|on| {
            let off = r.rows.iter().find(|o| o.knob == "filter" && o.value == "off" && o.dataset == on.dataset)?;
            Some(format!("{} {:.2}×", on.dataset, on.median_ms / off.median_ms))
        })
        .collect();
    if !ratios.is_empty() {
        let _ = writeln!(s, "\nTricubic vs trilinear, ms per frame: {}.", ratios.join(", "));
    }
    if !r.skipped.is_empty() {
        let _ = writeln!(s, "\nSkipped:");
        for k in &r.skipped {
            let _ = writeln!(s, "- {k}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_knob_has_a_valid_sweep_and_a_graph() {
        for k in KNOBS {
            crate::graphs::args::parse_sweep(k.sweep).unwrap_or_else(|e| panic!("{}: {e}", k.name));
            assert!(
                volgraph_app::builtin_graphs::find(std::path::Path::new(k.graph)).is_some(),
                "{}: {}",
                k.name,
                k.graph
            );
        }
        let err = chosen(&SweepArgs {
            knobs: vec!["stepp".into()],
            datasets: vec![],
            size: "8x8".into(),
            frames: 1,
            accuracy_size: 8,
            json: None,
            plots: None,
            markdown: None,
        })
        .expect_err("unknown knob")
        .to_string();
        assert!(err.contains("did you mean \"step\""), "{err}");
    }

    /// A tiny sweep of one knob writes a JSON row per value and dataset with the fields the
    /// issue names, all finite.
    #[test]
    fn a_tiny_sweep_writes_every_field() {
        let dir = std::env::temp_dir().join(format!("volgraph-sweep-{}", std::process::id()));
        let json = dir.join("sweep.json");
        std::fs::create_dir_all(&dir).expect("temp dir");
        let report = run(&SweepArgs {
            knobs: vec!["shading".into()],
            datasets: vec!["ml16".into()],
            size: "32x32".into(),
            frames: 1,
            accuracy_size: 16,
            json: Some(json.clone()),
            plots: Some(dir.clone()),
            markdown: None,
        })
        .expect("sweeps");
        assert_eq!(report.rows.len(), 2, "off and on");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parses");
        for row in v["rows"].as_array().expect("rows") {
            for field in ["knob", "value", "dataset"] {
                assert!(row[field].is_string(), "{field}: {row}");
            }
            for field in ["median_ms", "max_error", "mean_error"] {
                assert!(row[field].as_f64().is_some_and(f64::is_finite), "{field}: {row}");
            }
            assert!(row["psnr_db"].is_number() || row["max_error"].as_f64() == Some(0.0), "{row}");
        }
        assert!(dir.join("shading.png").is_file(), "the knob's plot");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
