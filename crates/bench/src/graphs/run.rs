//! The run: load every graph and dataset once (skipping, with a note, what is missing), then
//! time each graph × dataset × TF × viewport (× sweep value) ([`super::case`]), run the preset's
//! peer, and finally compute speed-ups and Pareto fronts across rows and the report's notes.

use std::collections::{BTreeSet, HashMap};

use anyhow::bail;
use indicatif::{ProgressBar, ProgressStyle};
use volgraph_core::runtime::{Gpu, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Diagnostics, Registry};

use super::accuracy;
use super::args::{BenchConfig, graph_label};
use super::case::{Case, Context, Dataset, GraphFile, run_case};
use super::dataset;
use super::peer;
use super::report::{GraphBenchReport, MemoryFigure, Row};

/// Measures every case of `config` on `gpu`.
pub fn run(gpu: std::sync::Arc<Gpu>, config: &BenchConfig) -> anyhow::Result<GraphBenchReport> {
    let adapter = gpu.adapter_name.clone();
    let first_graph = config.graphs.first().cloned().unwrap_or_default();
    let (sources, _) = volgraph_app::shader_dir::sources_for(&first_graph, config.shaders.as_deref());
    let mut ctx = Context {
        runtime: Runtime::new(gpu, ShaderLibrary::new(sources)),
        registry: volgraph_app::registry(),
        config,
        progress: ProgressBar::hidden(),
        skipped: Vec::new(),
        skip_seen: BTreeSet::new(),
        spp_cache: HashMap::new(),
        reference_cache: HashMap::new(),
        ceiling_cache: HashMap::new(),
    };
    ctx.runtime.set_gpu_memory_budget(config.gpu_memory_budget);
    ctx.runtime.set_light(config.light);
    let graphs: Vec<GraphFile> = config
        .graphs
        .iter()
        .filter_map(|path| match volgraph_app::inputs::read_graph(path) {
            Ok(source) => Some(GraphFile { label: graph_label(path), path: path.clone(), source }),
            Err(e) => {
                ctx.skip(
                    format!("graph {}", path.display()),
                    format!("cannot read the graph file ({e}); it is left out of this run"),
                );
                None
            }
        })
        .collect();
    let mut stand_in_notes = Vec::new();
    let mut stand_in_taken = config.datasets.iter().any(|d| d == dataset::STAND_IN);
    let datasets: Vec<Dataset> = config
        .datasets
        .iter()
        .filter_map(|name| match dataset::load_or_stand_in(name) {
            // One stand-in at most, and none beside the generated volume itself: the same
            // volume measured twice under two names says nothing new.
            Ok(loaded) if loaded.stand_in_note.is_some() && std::mem::replace(&mut stand_in_taken, true) => {
                ctx.skip(
                    format!("dataset {name}"),
                    format!(
                        "not in the data folder {} (give --data DIR), and the generated {} is measured already",
                        volgraph_accel::data_dir::data_dir().display(),
                        dataset::STAND_IN
                    ),
                );
                None
            }
            Ok(loaded) => {
                if let Some(note) = loaded.stand_in_note {
                    ctx.progress.suspend(|| volgraph_app::stdout::eprintln_escaped!("note: {note}"));
                    stand_in_notes.push(note);
                }
                Some(Dataset { name: name.clone(), label: loaded.label, volume: loaded.volume })
            }
            Err(e) => {
                ctx.skip(format!("dataset {name}"), format!("{e:#}"));
                None
            }
        })
        .collect();
    let sweep_values: Vec<Option<&(String, ron::Value)>> =
        config.sweep.as_ref().map_or_else(|| vec![None], |s| s.values.iter().map(Some).collect());
    let measured_cases = config.cases.iter().filter(|(d, _)| datasets.iter().any(|ds| &ds.name == d)).count();
    let cases = graphs.len() * measured_cases * config.viewports.len() * sweep_values.len();
    if !config.quiet {
        ctx.progress = ProgressBar::new((cases as u64) * (config.frames as u64 + 1));
        ctx.progress.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} frames {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
    }
    let mut rows = Vec::new();
    for dataset in &datasets {
        for (_, tf) in config.cases.iter().filter(|(d, _)| *d == dataset.name) {
            let lut = match tf.lut_for(&dataset.volume) {
                Ok(lut) => lut,
                Err(e) => {
                    ctx.skip(format!("transfer function {}", tf.name()), format!("{e:#}"));
                    continue;
                }
            };
            for &viewport in &config.viewports {
                for &sweep_value in &sweep_values {
                    for graph in &graphs {
                        let case = Case { graph, dataset, tf_name: tf.name(), lut: &lut, viewport, sweep_value };
                        ctx.progress.set_message(case.name());
                        if let Some(row) = run_case(&mut ctx, &case) {
                            rows.push(row);
                        }
                    }
                }
            }
        }
    }
    ctx.progress.finish_and_clear();
    let mut notes = notes(config);
    notes.extend(stand_in_notes);
    if config.peer
        && let Some(spec) = config.preset.and_then(|p| p.peer)
    {
        match run_peer(config, &spec, &rows) {
            Ok(peer) => {
                notes.push(format!("{} ({}).", spec.about, peer.ran));
                rows.extend(peer.rows);
                // Each peer row beside the rows of its case.
                let case_index = |r: &Row| config.cases.iter().position(|(d, t)| *d == r.dataset && t.name() == r.tf);
                rows.sort_by_key(|r| (case_index(r), r.viewport));
            }
            Err(reason) => ctx.skip(format!("peer {}", spec.label), reason),
        }
    }
    if rows.is_empty() {
        let why: Vec<String> = ctx.skipped.iter().map(|s| format!("{}: {}", s.what, s.reason)).collect();
        bail!("nothing was measured:\n  {}", why.join("\n  "));
    }
    if !rows.iter().any(|r| r.graph == config.baseline) {
        ctx.skip(
            format!("baseline {}", config.baseline),
            "the baseline graph was not measured, so there are no speed-ups".to_string(),
        );
    }
    fill_speedups(&mut rows, &config.baseline, &config.baselines);
    let antialias = config.antialias.as_ref().and_then(|(study, viewport)| {
        let run = super::antialias_study::run(
            &mut ctx.runtime,
            &ctx.registry,
            study,
            *viewport,
            &config.camera,
            config.degrees_per_frame,
        );
        run.map_err(|reason| ctx.skip("the antialiasing study".to_string(), reason)).ok()
    });
    let memory = config
        .memory
        .iter()
        .filter_map(|(graph, size)| {
            memory_figure(&mut ctx.runtime, &ctx.registry, graph, *size)
                .map_err(|reason| ctx.skip(format!("memory of {}", graph.display()), reason))
                .ok()
        })
        .collect();
    if config.sweep.is_some() {
        fill_pareto(&mut rows);
    }
    Ok(GraphBenchReport {
        program: "volgraph bench graphs".to_string(),
        preset: config.preset.map(|p| p.name.to_string()),
        about: config.preset.map(|p| p.about.to_string()),
        adapter,
        timestamps: rows.iter().all(|r| r.clock == "gpu"),
        frames: config.frames,
        warmup_frames: 1,
        degrees_per_frame: config.degrees_per_frame,
        camera: [config.camera.azimuth_deg, config.camera.elevation_deg, config.camera.distance],
        scale: config.scale,
        baseline: config.baseline.clone(),
        baselines: config.baselines.clone(),
        sweep: config.sweep.as_ref().map(|s| s.key.clone()),
        reference_step_voxels: config.accuracy.then_some(config.reference_step),
        notes,
        rows,
        skipped: ctx.skipped,
        antialias,
        memory,
    })
}

/// The pooled vs unpooled transient memory of `graph`'s plan at `size` (compiled, not run).
fn memory_figure(
    runtime: &mut Runtime,
    registry: &Registry,
    graph: &std::path::Path,
    size: (u32, u32),
) -> Result<MemoryFigure, String> {
    let source = volgraph_app::inputs::read_graph(graph).map_err(|e| format!("{e:#}"))?;
    let file = graph.display().to_string();
    let plan = runtime
        .compile(&file, &source, registry, &CompileOptions::new(size.0, size.1))
        .map_err(|d: Diagnostics| d.to_string())?;
    let memory = plan.memory();
    let shared_slots = plan
        .slots
        .iter()
        .filter(|s| s.holds.len() > 1)
        .map(|s| s.holds.iter().map(|&r| plan.resources[r].name.clone()).collect())
        .collect();
    Ok(MemoryFigure {
        graph: graph.display().to_string(),
        viewport: [size.0, size.1],
        pooled_bytes: memory.pooled_bytes,
        unpooled_bytes: memory.unpooled_bytes,
        history_bytes: memory.history_bytes,
        shared_slots,
    })
}

/// Runs the preset's peer on the measured cases whose TF is a named file (the peer reads
/// `$VOLGRAPH_DATA/tf/<name>.ron`), at each viewport, with the run's frames and step.
fn run_peer(config: &BenchConfig, spec: &peer::PeerSpec, rows: &[Row]) -> Result<peer::PeerResult, String> {
    let mut cases: Vec<peer::PeerCase> = Vec::new();
    for (dataset, tf) in &config.cases {
        let measured = rows.iter().any(|r| &r.dataset == dataset && r.tf == tf.name());
        if measured && matches!(tf, super::tf_choice::TfChoice::File { .. }) {
            cases.push(peer::PeerCase { dataset: dataset.clone(), tf: tf.name() });
        }
    }
    if cases.is_empty() {
        return Err("no measured case has a transfer function from $VOLGRAPH_DATA/tf for the peer to read".into());
    }
    let step = config.params.iter().find(|(k, _)| k.ends_with("step_voxels")).map_or(0.5, |(_, v)| *v);
    let mut result = peer::PeerResult { rows: Vec::new(), ran: String::new() };
    for &viewport in &config.viewports {
        let r = peer::run(spec, &volgraph_accel::data_dir::data_dir(), &cases, viewport, config.frames, step)?;
        result.rows.extend(r.rows);
        result.ran = r.ran;
    }
    Ok(result)
}

fn notes(config: &BenchConfig) -> Vec<String> {
    let mut notes = Vec::new();
    if config.gpu_count {
        notes.push(
            "GPU samples/px: samples the graph's own passes took (passes with `count_samples`), counted in an extra \
             frame of the middle view; GPU Msamples/s = that × viewport pixels / median ms/frame; of fetch ceiling = \
             GPU Msamples/s / the Msamples/s of `volgraph bench fetch`'s probe on the same dataset, viewport, step \
             and views, measured in this run."
                .to_string(),
        );
    }
    if config.spp_size > 0 {
        notes.push(format!(
            "samples/px: volume samples per pixel of the f64 CPU reference run with each graph's raycast parameters, \
             at a reduced size (longest side {} px, same aspect) from the middle frame's view; it counts early ray \
             termination but not empty-space skipping. Msamples/s = samples/px × viewport pixels / median ms/frame.",
            config.spp_size
        ));
    } else {
        notes.push("samples/px: not counted (--spp-size 0).".to_string());
    }
    if config.accuracy {
        notes.push(format!(
            "error: the GPU `image` output (linear premultiplied RGBA, all four channels) at a reduced size (longest side {} px) \
             from the first frame's view vs the f64 CPU reference at step {} voxel with no early termination; PSNR for a peak of 1.",
            config.accuracy_size, config.reference_step
        ));
    }
    notes
}

/// Speed-up = baseline median / row median for rows of the same dataset, TF, viewport and sweep
/// value; a graph of `pairs` is measured against its own baseline.
fn fill_speedups(rows: &mut [Row], baseline: &str, pairs: &[(String, String)]) {
    let same = |a: &Row, b: &Row| {
        a.dataset == b.dataset && a.tf == b.tf && a.viewport == b.viewport && a.sweep_value == b.sweep_value
    };
    let all: Vec<Row> = rows.to_vec();
    for row in rows.iter_mut() {
        let base = pairs.iter().find(|(g, _)| *g == row.graph).map_or(baseline, |(_, b)| b.as_str());
        row.speedup_vs_baseline = all
            .iter()
            .find(|b| b.graph == base && same(b, row))
            .map(|b| b.median_ms / row.median_ms)
            .filter(|x| x.is_finite());
    }
}

/// Marks the Pareto front of (ms/frame, mean abs error) within each graph × dataset × TF × viewport.
fn fill_pareto(rows: &mut [Row]) {
    let group = |r: &Row| format!("{}|{}|{}|{:?}", r.graph, r.dataset, r.tf, r.viewport);
    let groups: BTreeSet<String> = rows.iter().map(group).collect();
    for g in groups {
        let idx: Vec<usize> = (0..rows.len()).filter(|&i| group(&rows[i]) == g).collect();
        let points: Vec<(f64, f64)> =
            idx.iter().map(|&i| (rows[i].median_ms, rows[i].error.map_or(f64::NAN, |e| e.mean_abs))).collect();
        for (&i, on) in idx.iter().zip(accuracy::pareto_front(&points)) {
            rows[i].pareto = Some(on);
        }
    }
}
