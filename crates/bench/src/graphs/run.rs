//! The case loop: load every graph and dataset once (skipping, with a note, what is missing),
//! then time each graph × dataset × TF × viewport (× sweep value), count samples and measure
//! error, and finally compute speed-ups and Pareto fronts across rows.

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;

use anyhow::bail;
use indicatif::{ProgressBar, ProgressStyle};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::render_reference;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Gpu, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Diagnostics, Plan, Registry};

use super::accuracy::{self, ImageError};
use super::args::{BenchConfig, graph_label, reduced_viewport};
use super::dataset;
use super::gpu_count;
use super::measure::{self, frame_camera, median};
use super::peer;
use super::report::{GraphBenchReport, MemoryFigure, Row, Skipped};

/// A graph file that could be read.
struct GraphFile {
    label: String,
    path: PathBuf,
    source: String,
}

/// A dataset with its volume.
struct Dataset {
    /// The `--datasets` name the cases refer to.
    name: String,
    /// Its name in tables (`NAME→ml64` for a generated stand-in).
    label: String,
    volume: Volume,
}

/// What stays fixed while a case runs.
struct Context<'a> {
    /// One runtime for every case: a dataset's volume is uploaded once for all graphs, and a
    /// graph's pipelines are built once for all datasets.
    runtime: Runtime,
    registry: Registry,
    config: &'a BenchConfig,
    progress: ProgressBar,
    skipped: Vec<Skipped>,
    skip_seen: BTreeSet<(String, String)>,
    /// samples/pixel by (dataset, tf, size, settings).
    spp_cache: HashMap<String, f64>,
    /// converged reference colour by (dataset, tf, size, settings).
    reference_cache: HashMap<String, Vec<[f64; 4]>>,
    /// fetch ceiling by (dataset, size, step); `None` when it could not be measured.
    ceiling_cache: HashMap<String, Option<crate::fetch::Ceiling>>,
}

impl Context<'_> {
    fn skip(&mut self, what: String, reason: String) {
        if self.skip_seen.insert((what.clone(), reason.clone())) {
            self.progress.suspend(|| volgraph_app::stdout::eprintln_escaped!("note: skipping {what}: {reason}"));
            self.skipped.push(Skipped { what, reason });
        }
    }
}

/// One case's inputs.
struct Case<'a> {
    graph: &'a GraphFile,
    dataset: &'a Dataset,
    tf_name: String,
    lut: &'a [[f32; 4]],
    viewport: (u32, u32),
    sweep_value: Option<&'a (String, ron::Value)>,
}

impl Case<'_> {
    fn name(&self) -> String {
        let sweep = self.sweep_value.map(|(v, _)| format!(" {v}")).unwrap_or_default();
        format!(
            "{} on {} ({}, {}×{}{sweep})",
            self.graph.label, self.dataset.name, self.tf_name, self.viewport.0, self.viewport.1
        )
    }

    fn options(&self, config: &BenchConfig, viewport: (u32, u32)) -> CompileOptions {
        let mut options = CompileOptions::new(viewport.0, viewport.1);
        // The preset's per-dataset values, then the fixed ones (`--set` last, so it wins).
        for (_, key, value) in config.dataset_params.iter().filter(|(d, _, _)| *d == self.dataset.name) {
            set_knob(&mut options, key, &ron::Value::from(*value));
        }
        for (key, value) in &config.params {
            set_knob(&mut options, key, &ron::Value::from(*value));
        }
        if let (Some(sweep), Some((_, value))) = (&config.sweep, self.sweep_value) {
            set_knob(&mut options, &sweep.key, value);
        }
        options
    }
}

/// Sets one knob: `input.NAME` is a Scalar graph input (a scene value shared by several passes,
/// e.g. Krüger–Westermann's segment length M), `feature.NAME` a scene effect (`on`/`off`),
/// `scene.precision` the float target precision (`f16`/`f32`), anything else `pass.param`.
fn set_knob(options: &mut CompileOptions, key: &str, value: &ron::Value) {
    if let Some(name) = key.strip_prefix("feature.") {
        let on = matches!(value, ron::Value::Bool(true)) || matches!(value, ron::Value::String(s) if s == "on");
        if on {
            options.features.insert(name.to_string());
        } else {
            options.features.remove(name);
        }
        return;
    }
    if key == "scene.precision" {
        if let ron::Value::String(s) = value {
            options.precision = volgraph_core::Precision::from_name(s);
        }
        return;
    }
    match (key.strip_prefix("input."), value) {
        (Some(name), ron::Value::Number(n)) => {
            options.scalars.insert(name.to_string(), (*n).into_f64());
        }
        _ => {
            options.param_overrides.insert(key.to_string(), value.clone());
        }
    }
}

/// A `--sweep` over a Scalar input or a feature the graph does not have would measure the same
/// graph at every "value": an error naming what the graph has instead. (A `pass.param` the graph
/// lacks is already a compile error.)
fn sweep_applies(plan: &Plan, key: &str) -> Result<(), String> {
    let (what, name, known) = if let Some(name) = key.strip_prefix("input.") {
        ("Scalar input", name, &plan.known_scalars)
    } else if let Some(name) = key.strip_prefix("feature.") {
        ("feature", name, &plan.known_features)
    } else {
        return Ok(());
    };
    if known.contains(name) {
        return Ok(());
    }
    let list: Vec<&str> = known.iter().map(String::as_str).collect();
    Err(format!(
        "--sweep {key}: graph \"{}\" has no {what} \"{name}\", so every value would measure the same thing; {}",
        plan.name,
        volgraph_core::suggest::guess_then(
            name,
            list.iter().copied(),
            if what == "feature" { "feature." } else { "input." },
            format!("it has: {}", volgraph_core::suggest::comma_list(&list))
        )
    ))
}

/// Binds the case's volume and LUT (uploads only what changed) and compiles the case at
/// `viewport` with the runtime's scene values (the volume's longest ray, which multipass graphs
/// size their segment loop by).
fn compile_case(ctx: &mut Context<'_>, case: &Case<'_>, viewport: (u32, u32)) -> Result<Plan, String> {
    let file = case.graph.path.display().to_string();
    let options = case.options(ctx.config, viewport);
    let bind = |runtime: &mut Runtime| {
        runtime.bind_scene(&gpu_count::scene_inputs(), &case.dataset.volume, case.lut).map_err(|e| e.to_string())
    };
    bind(&mut ctx.runtime)?;
    let plan = ctx
        .runtime
        .compile(&file, &case.graph.source, &ctx.registry, &options)
        .map_err(|d: Diagnostics| d.to_string())?;
    if let Some(sweep) = &ctx.config.sweep {
        sweep_applies(&plan, &sweep.key)?;
    }
    ctx.runtime.bind_scene(&plan.inputs, &case.dataset.volume, case.lut).map_err(|e| e.to_string())?;
    Ok(plan)
}

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

fn key(case: &Case<'_>, size: (u32, u32), settings: &impl std::fmt::Debug) -> String {
    format!("{}|{}|{}x{}|{settings:?}", case.dataset.name, case.tf_name, size.0, size.1)
}

/// Times one case; `None` (after a note) when it cannot run.
fn run_case(ctx: &mut Context<'_>, case: &Case<'_>) -> Option<Row> {
    let config = ctx.config;
    let file = case.graph.path.display().to_string();
    let plan = match compile_case(ctx, case, case.viewport) {
        Ok(plan) => plan,
        Err(d) => {
            ctx.skip(format!("graph {}", case.graph.label), format!("does not compile for this case: {}", d.trim()));
            ctx.progress.inc(config.frames as u64 + 1);
            return None;
        }
    };
    let settings = accuracy::raycast_settings(&plan);
    let progress = ctx.progress.clone();
    let timing = ctx.runtime.apply(plan, &ctx.registry).and_then(|_| {
        measure::time_frames(&mut ctx.runtime, &config.camera, config.degrees_per_frame, config.frames, || {
            progress.inc(1)
        })
    });
    let timing = match timing {
        Ok(t) => t,
        Err(e) => {
            ctx.skip(case.name(), format!("rendering failed: {e}"));
            return None;
        }
    };
    let median_ms = median(&timing.frame_ms);
    let counters =
        ctx.runtime.pass_counters().into_iter().map(|(pass, name, v)| (format!("{pass}.{name}"), v)).collect();
    let bypass = ctx
        .runtime
        .bypass_status()
        .iter()
        .map(|b| {
            let measure = b.measure.map_or("not measured".to_string(), |m| format!("last {m:.1}/px"));
            let frames = b.frames_bypassed + b.frames_run;
            format!("{} left out {}/{frames} frames ({measure}, below {})", b.name, b.frames_bypassed, b.below)
        })
        .collect();
    let counted = if config.gpu_count { count_on_gpu(ctx, case) } else { None };
    let step = settings.map_or(0.5, |s| s.step_voxels);
    let ceiling = counted.and_then(|_| fetch_ceiling(ctx, case, step));
    let spp_viewport = reduced_viewport(case.viewport, config.spp_size.max(1));
    let spp = settings.filter(|_| config.spp_size > 0).map(|s| {
        let k = key(case, spp_viewport, &s);
        *ctx.spp_cache.entry(k).or_insert_with(|| {
            let camera = frame_camera(&config.camera, config.degrees_per_frame, config.frames / 2);
            accuracy::samples_per_pixel(&case.dataset.volume, case.lut, &camera, spp_viewport, &s)
        })
    });
    let pixels = case.viewport.0 as f64 * case.viewport.1 as f64;
    let error_viewport = reduced_viewport(case.viewport, config.accuracy_size);
    let error = if config.accuracy { measure_error(ctx, case, settings, error_viewport) } else { None };
    Some(Row {
        graph: case.graph.label.clone(),
        graph_file: file,
        dataset: case.dataset.label.clone(),
        dims: case.dataset.volume.dims.to_array(),
        tf: case.tf_name.clone(),
        viewport: [case.viewport.0, case.viewport.1],
        sweep_value: case.sweep_value.map(|(v, _)| v.clone()),
        median_ms,
        min_ms: timing.frame_ms.iter().copied().fold(f64::INFINITY, f64::min),
        max_ms: timing.frame_ms.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        median_wall_ms: median(&timing.wall_ms),
        clock: if timing.wall_time_fallback { "wall" } else { "gpu" }.to_string(),
        speedup_vs_baseline: None,
        pass_ms: timing.pass_ms,
        samples_per_pixel: spp,
        spp_viewport: spp.map(|_| [spp_viewport.0, spp_viewport.1]),
        msamples_per_s: spp.map(|s| s * pixels / (median_ms * 1e-3) / 1e6),
        gpu_samples_per_pixel: counted.map(|c| c.samples_per_pixel),
        gpu_msamples_per_s: counted.map(|c| c.samples_per_pixel * pixels / (median_ms * 1e-3) / 1e6),
        fetch_ceiling_msamples_per_s: ceiling.map(|c| c.msamples_per_s),
        fraction_of_fetch_ceiling: counted
            .zip(ceiling)
            .map(|(c, ceiling)| c.samples_per_pixel * pixels / (median_ms * 1e-3) / 1e6 / ceiling.msamples_per_s),
        error,
        error_viewport: error.map(|_| [error_viewport.0, error_viewport.1]),
        pareto: None,
        counters,
        bypass,
    })
}

/// Renders the middle frame's view once more with every sample-counting pass counting (see
/// [`gpu_count`]); `None` (with a note the first time) when no pass of the graph counts.
fn count_on_gpu(ctx: &mut Context<'_>, case: &Case<'_>) -> Option<gpu_count::Counted> {
    let config = ctx.config;
    let camera = frame_camera(&config.camera, config.degrees_per_frame, config.frames / 2);
    let previous = OrbitCamera { azimuth_deg: camera.azimuth_deg - config.degrees_per_frame, ..camera };
    let mut options = case.options(config, case.viewport);
    let result = ctx
        .runtime
        .bind_scene(&gpu_count::scene_inputs(), &case.dataset.volume, case.lut)
        .map_err(|e| e.to_string())
        .and_then(|_| {
            gpu_count::count(
                &mut ctx.runtime,
                &ctx.registry,
                &case.graph.path.display().to_string(),
                &case.graph.source,
                &mut options,
                &previous,
                &camera,
            )
        });
    match result {
        Ok(Some(counted)) => Some(counted),
        Ok(None) => {
            ctx.skip(
                format!("GPU sample count of {}", case.graph.label),
                "no pass of the graph counts its samples (a `count_samples` parameter); samples/px comes from the CPU \
                 reference"
                    .to_string(),
            );
            None
        }
        Err(reason) => {
            ctx.skip(format!("GPU sample count of {}", case.name()), reason);
            None
        }
    }
}

/// The fetch ceiling of the case's dataset and viewport at `step` (measured once per run, with
/// the case's views; see `volgraph bench fetch`).
fn fetch_ceiling(ctx: &mut Context<'_>, case: &Case<'_>, step: f64) -> Option<crate::fetch::Ceiling> {
    let config = ctx.config;
    let k = format!("{}|{}x{}|{step}", case.dataset.name, case.viewport.0, case.viewport.1);
    if let Some(c) = ctx.ceiling_cache.get(&k) {
        return *c;
    }
    let measured = crate::fetch::measure_ceiling(
        &mut ctx.runtime,
        &ctx.registry,
        &case.dataset.volume,
        case.viewport,
        &config.camera,
        config.degrees_per_frame,
        config.frames,
        step,
    );
    let ceiling = match measured {
        Ok(c) => Some(c),
        Err(reason) => {
            ctx.skip(format!("fetch ceiling of {}", case.dataset.name), reason);
            None
        }
    };
    ctx.ceiling_cache.insert(k, ceiling);
    ceiling
}

/// Renders the case once at `size` and compares its `image` output with the converged reference.
fn measure_error(
    ctx: &mut Context<'_>,
    case: &Case<'_>,
    settings: Option<volgraph_accel::reference::RaycastSettings>,
    size: (u32, u32),
) -> Option<ImageError> {
    let config = ctx.config;
    let Some(settings) = settings else {
        ctx.skip(
            format!("error of {}", case.graph.label),
            "no step has a step_voxels parameter, so there is no reference integral".to_string(),
        );
        return None;
    };
    let camera: OrbitCamera = config.camera;
    let image = compile_case(ctx, case, size).and_then(|plan| {
        if !plan.outputs.contains_key("image") {
            return Err("the graph has no \"image\" output to compare".to_string());
        }
        let viewport = plan.viewport;
        ctx.runtime.apply(plan, &ctx.registry).map_err(|e| e.to_string())?;
        ctx.runtime.render(CameraData::from_orbit(&camera, viewport)).map_err(|e| e.to_string())?;
        ctx.runtime.read_output("image").map_err(|e| e.to_string())
    });
    let image = match image {
        Ok(image) => image,
        Err(reason) => {
            ctx.skip(format!("error of {}", case.name()), reason);
            return None;
        }
    };
    let reference_settings = accuracy::converged(&settings, config.reference_step);
    let k = key(case, size, &reference_settings);
    let reference = ctx.reference_cache.entry(k).or_insert_with(|| {
        render_reference(&case.dataset.volume, case.lut, &camera, size.0, size.1, &reference_settings).color
    });
    accuracy::image_error(&image, reference)
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
