//! One case of the run: a graph on a dataset, TF, viewport (and sweep value). Compiles it with
//! the case's knobs, times its frames, and adds what was asked for: samples per pixel (CPU
//! reference or the graph's own counting passes), the fetch ceiling, and error against the
//! converged reference. What stays fixed across cases (runtime, caches, notes of what was
//! skipped) is the [`Context`] that [`super::run`] builds.

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;

use indicatif::ProgressBar;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::render_reference;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Runtime};
use volgraph_core::{CompileOptions, Diagnostics, Plan, Registry};

use super::accuracy::{self, ImageError};
use super::args::{BenchConfig, reduced_viewport};
use super::gpu_count;
use super::measure::{self, frame_camera, median};
use super::report::{Row, Skipped};

/// A graph file that could be read.
pub(super) struct GraphFile {
    pub(super) label: String,
    pub(super) path: PathBuf,
    pub(super) source: String,
}

/// A dataset with its volume.
pub(super) struct Dataset {
    /// The `--datasets` name the cases refer to.
    pub(super) name: String,
    /// Its name in tables (`NAME→ml64` for a generated stand-in).
    pub(super) label: String,
    pub(super) volume: Volume,
}

/// What stays fixed while a case runs.
pub(super) struct Context<'a> {
    /// One runtime for every case: a dataset's volume is uploaded once for all graphs, and a
    /// graph's pipelines are built once for all datasets.
    pub(super) runtime: Runtime,
    pub(super) registry: Registry,
    pub(super) config: &'a BenchConfig,
    pub(super) progress: ProgressBar,
    pub(super) skipped: Vec<Skipped>,
    pub(super) skip_seen: BTreeSet<(String, String)>,
    /// samples/pixel by (dataset, tf, size, settings).
    pub(super) spp_cache: HashMap<String, f64>,
    /// converged reference colour by (dataset, tf, size, settings).
    pub(super) reference_cache: HashMap<String, Vec<[f64; 4]>>,
    /// fetch ceiling by (dataset, size, step); `None` when it could not be measured.
    pub(super) ceiling_cache: HashMap<String, Option<crate::fetch::Ceiling>>,
}

impl Context<'_> {
    pub(super) fn skip(&mut self, what: String, reason: String) {
        if self.skip_seen.insert((what.clone(), reason.clone())) {
            self.progress.suspend(|| volgraph_app::stdout::eprintln_escaped!("note: skipping {what}: {reason}"));
            self.skipped.push(Skipped { what, reason });
        }
    }
}

/// One case's inputs.
pub(super) struct Case<'a> {
    pub(super) graph: &'a GraphFile,
    pub(super) dataset: &'a Dataset,
    pub(super) tf_name: String,
    pub(super) lut: &'a [[f32; 4]],
    pub(super) viewport: (u32, u32),
    pub(super) sweep_value: Option<&'a (String, ron::Value)>,
}

impl Case<'_> {
    pub(super) fn name(&self) -> String {
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

fn key(case: &Case<'_>, size: (u32, u32), settings: &impl std::fmt::Debug) -> String {
    format!("{}|{}|{}x{}|{settings:?}", case.dataset.name, case.tf_name, size.0, size.1)
}

/// Times one case; `None` (after a note) when it cannot run.
pub(super) fn run_case(ctx: &mut Context<'_>, case: &Case<'_>) -> Option<Row> {
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
    // The reference is lit as the GPU is (`--light`).
    let settings = accuracy::raycast_settings(&plan)
        .map(|s| volgraph_accel::reference::RaycastSettings { lights: config.light.into(), ..s });
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
