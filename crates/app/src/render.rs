//! `volgraph render`: every input is read and checked (scene, graph, volume, transfer function,
//! sizes, the output file's kind) before the GPU is opened, then frames are drawn and the last
//! one is written. A scene (`--scene`) supplies what flags do not.

use crate::stream_progress::StreamProgress;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::anyhow;
use volgraph_accel::volume::VoxelData;
use volgraph_core::compile;
use volgraph_core::runtime::{CameraData, Gpu, Runtime, ShaderLibrary, VolumeDesc, VolumeFormat, scene_values_of};

use crate::cli::{CliError, check_user_names, compile_options, display_name, warning_lines};
use crate::image_out::{self, ImageKind};
use crate::inputs;
use crate::named_inputs::{NamedBindings, NamedTf};
use crate::scene::{CameraSpec, Scene};
use crate::scene_args::{Resolved, SceneArgs};
use volgraph_core::runtime::OpacityReference;

/// The arguments of `volgraph render` (its command line, flattened into the CLI).
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// What to render: graph, scene, volume, TF, camera, viewport.
    #[command(flatten)]
    pub inputs: SceneArgs,
    /// Frames to render (the last one is written); each rotates the volume 1° about y, or
    /// follows the scene's camera path [default: the scene's, else 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: Option<u32>,
    /// Samples per pixel a progressive graph (`graphs/cinematic/path_traced.ron`) accumulates at
    /// one camera: this many frames with the camera still, each adding a sample to the running
    /// mean.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536), conflicts_with = "frames")]
    pub spp: Option<u32>,
    /// The graph output to write; default: "display" for PNG when the graph has it, else "image".
    #[arg(long)]
    pub output: Option<String>,
    /// Where to write the image (.png or .exr).
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Sort-last rendering over MPI: run under `mpirun -n N` (a build with `--features mpi`);
    /// each rank reads and renders its box of `--volume` (.raw, .nrrd, .mha) and rank 0 writes the
    /// composited image. See docs/scaling.md.
    #[arg(long)]
    pub distributed: bool,
    /// How --distributed ranks composite their images.
    #[arg(long, value_enum, default_value = "radix-k", requires = "distributed")]
    pub composite: crate::distributed::CompositeAlgorithm,
    /// With a streaming graph (graphs/streaming/ray_guided.ron): stop refining after this many
    /// milliseconds from the first frame and write what is drawn (bricks still being read are
    /// drawn from a coarser level) [default: wait for the full image].
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=86_400_000))]
    pub time_budget_ms: Option<u64>,
    /// Time every pass by wall clock, each submitted on its own and waited for: per-pass costs
    /// where GPU timestamps do not cover compute work (lavapipe). The frames get slower.
    #[arg(long)]
    pub time_each_pass: bool,
    /// Show volumes of different DICOM frames of reference (FrameOfReferenceUID) as their files
    /// place them, with a warning, instead of refusing them: for series known to line up.
    #[arg(long)]
    pub allow_frame_mismatch: bool,
    /// The largest group of a radix-k round (IceT's default: 8; 2 is binary swap).
    #[arg(long = "radix-k", default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=64), requires = "distributed")]
    pub radix_k: u32,
}

/// Everything `render` needs, read and checked, before the GPU is opened.
pub struct Prepared {
    args: RenderArgs,
    graph: PathBuf,
    kind: ImageKind,
    camera: CameraSpec,
    frames: u32,
    /// `--spp`: every frame from the first frame's camera.
    still: bool,
    opacity: OpacityReference,
    cuts: volgraph_accel::cuts::Cuts,
    /// The scene's light.
    lights: volgraph_accel::light::Lights,
    /// The scene's environment map, read and checked.
    environment: Option<Arc<volgraph_accel::environment::EnvironmentMap>>,
    volume: volgraph_accel::volume::Volume,
    lut: Vec<[f32; 4]>,
    /// Inputs bound by name (`--volume NAME=PATH`, `--tf NAME=…`), if any.
    bindings: Option<NamedBindings>,
    /// The store or large file a streaming graph reads brick by brick (then `volume` is its coarsest level).
    streamed: Option<Arc<dyn volgraph_accel::pyramid::PyramidSource>>,
    plan: volgraph_core::Plan,
    output: String,
    /// Notes and warnings for stderr (repairs, choices made, capped counts, invisible data).
    pub notes: Vec<String>,
}

/// Reads and checks every input of `volgraph render`; touches no GPU, prints nothing.
pub fn prepare(args: RenderArgs) -> Result<Prepared, CliError> {
    let kind = ImageKind::from_path("-o", &args.out)?;
    let Resolved { scene, graph, size, camera, camera_is_default, cuts, lights, environment } =
        args.inputs.resolve("volgraph render GRAPH -o out.png", "512x512")?;
    let source = inputs::read_graph(&graph)?;
    let mut features = scene.as_ref().map(|s| s.effects.clone()).unwrap_or_default();
    features.extend(args.inputs.features.iter().cloned());
    // A crop or clip is compiled in only when the scene (or --crop/--clip) asks for it.
    features.extend(volgraph_core::cut_effects::features_of(&cuts));
    let mut options = compile_options(&size, &features, &[])?;
    options.precision = scene.as_ref().and_then(|s| s.precision);
    let frames = args.spp.or(args.frames).or(scene.as_ref().map(Scene::frame_count)).unwrap_or(1);
    let still = args.spp.is_some();
    let raw = inputs::raw_options(&args.inputs.raw)?;
    // `--volume NAME=PATH` / `--tf NAME=…` bind inputs by name; the frame's volume is the one
    // bound to `volume`, else the first named (crate::named_inputs).
    let mut named = crate::named_inputs::named_volumes(&args.inputs.volume)?;
    let (plain_tf, mut named_tfs) = crate::named_inputs::split_tfs(&args.inputs.tf)?;
    // A scene's named inputs, where the command line names no volume: its `volume:` is then the
    // input `volume` (an empty path: loaded from the scene below). Its TFs under the command
    // line's of the same name.
    let scene_named = args.inputs.volume.is_empty() && scene.as_ref().is_some_and(|s| !s.volumes.is_empty());
    if let Some(scene) = scene.as_ref().filter(|_| scene_named) {
        named = std::iter::once((volgraph_core::runtime::inputs::PRIMARY_VOLUME.to_string(), PathBuf::new()))
            .chain(scene.volumes.iter().cloned())
            .collect();
    }
    for (name, path) in scene.as_ref().map_or(&[][..], |s| s.tfs.as_slice()) {
        if !named_tfs.iter().any(|(n, _)| n == name) {
            named_tfs.push((name.clone(), path.clone()));
        }
    }
    let primary = NamedBindings::primary_index(&named);
    let shown_paths = match named.get(primary) {
        Some((_, path)) if !scene_named => vec![path.clone()],
        _ => args.inputs.volume.clone(),
    };
    // A named volume may pick one volume of a 4D file (`cells.nii#1`: channels bound by name).
    let (shown_paths, primary_raw) = match shown_paths.as_slice() {
        [one] if !named.is_empty() => {
            let (file, options) = crate::named_inputs::path_and_frame(one, &raw);
            (vec![file], options)
        }
        _ => (shown_paths, raw.clone()),
    };
    // An OME-Zarr store, or a file over the memory budget, shown by a streaming graph is read
    // brick by brick, never whole: what is loaded here is its coarsest level (the TF's fit, the
    // camera's frame). Another graph refuses a file too large to read whole.
    let streamed = match shown_paths.as_slice() {
        [one] if volgraph_zarr::is_zarr(one) && crate::zarr_input::graph_streams(&source) => {
            Some(crate::zarr_input::stream(one, &primary_raw, args.inputs.memory_mb)?)
        }
        [one] if crate::zarr_input::graph_streams(&source) => {
            crate::zarr_input::stream_file(one, &primary_raw, args.inputs.memory_mb, |line| {
                crate::stdout::eprintln_escaped!("{line}")
            })?
        }
        [one] => {
            crate::zarr_input::refuse_large_file(one, &primary_raw)?;
            None
        }
        _ => None,
    };
    let (volume, generated, mut notes) = match &streamed {
        Some(s) => (s.coarsest.clone(), false, s.notes.clone()),
        None => {
            let shown = crate::scene::load_shown_volume(&shown_paths, scene.as_ref(), &primary_raw)?;
            (shown.volume, shown.marschner_lobb_tf, shown.notes)
        }
    };
    crate::scene_args::check_view_frame(args.inputs.view.as_deref(), &volume)?;
    let camera = Resolved::camera_for(camera, camera_is_default, &volume);
    let (tf, tf_notes) = match (&plain_tf, &scene) {
        (None, Some(scene)) => {
            let (tf, _, notes) =
                crate::scene::load_transfer_function(scene, args.inputs.tf_map.as_deref(), &volume, generated)?;
            (tf, notes)
        }
        (tf, _) => inputs::transfer_function(tf.as_ref(), args.inputs.tf_map.as_deref(), &volume, generated)?,
    };
    notes.extend(tf_notes);
    let lut = tf.to_lut_for(&volume, inputs::LUT_SIZE);
    let scene_path = scene.as_ref().filter(|_| scene_named).map(|s| s.path.as_path());
    let others = load_other_volumes(&named, primary, &raw, scene_path, &mut notes)?;
    let registry = crate::program::registry();
    let file = display_name(&graph);
    let opacity = scene.as_ref().map(|s| s.opacity_reference).unwrap_or_default();
    options.scene = scene_values_of(&match &streamed {
        Some(s) => {
            let source = volgraph_accel::pyramid::PyramidSource::levels(s.source.as_ref())[0];
            VolumeDesc::of_box(source.dims, volgraph_accel::pyramid::PyramidSource::spacing(s.source.as_ref()))
        }
        None => VolumeDesc::of(&volume),
    });
    options.scene.extend(crate::inputs::data_scene_values(&volume));
    let plan = compile(&file, &source, &registry, &options).map_err(CliError::Graph)?;
    let environment = environment.as_deref().map(crate::environment_file::load_environment).transpose()?.map(Arc::new);
    if let Some(spp) = args.spp
        && !accumulates(&plan)
    {
        return Err(CliError::Other(anyhow!(
            "--spp {spp}: {} keeps no running mean to add samples to (no history entry with \
             `while_camera_still: true`); use a progressive graph such as graphs/cinematic/path_traced.ron, or \
             --frames N for frames that turn the camera",
            graph.display()
        )));
    }
    let frame_path = shown_paths.first().map(PathBuf::as_path);
    let bindings = named_bindings(
        &plan,
        (&named, primary, frame_path),
        others,
        (&named_tfs, plain_tf.as_ref()),
        &volume,
        args.inputs.tf_map.as_deref(),
    )?;
    let bindings =
        bindings.map(|(b, notes)| (NamedBindings { allow_frame_mismatch: args.allow_frame_mismatch, ..b }, notes));
    if let Some((bindings, binding_notes)) = &bindings {
        notes.extend(binding_notes.iter().cloned());
        notes.extend(bindings.check(&plan, &file, &source, &volume)?);
    }
    notes.extend(unnamed_volume_notes(&plan, &named));
    let bindings = bindings.map(|(b, _)| b);
    // A scene's effect the graph does not offer is a note (the scene may be shown with another
    // graph); a --features name it does not know is the user's typo: an error.
    let mut user = options.clone();
    user.features.retain(|f| {
        let from_scene = scene.as_ref().is_some_and(|s| s.effects.contains(f)) && !args.inputs.features.contains(f);
        if from_scene && !plan.known_features.contains(f) {
            notes.push(format!(
                "note: graph \"{}\" does not offer the scene's effect \"{f}\"; it is left out",
                plan.name
            ));
            return false;
        }
        true
    });
    check_user_names(&plan, &user)?;
    notes.extend(warning_lines(&plan));
    notes.extend(budget_note(&plan, &registry, args.inputs.gpu_memory_mb));
    let output = match &args.output {
        Some(name) => name.clone(),
        None if kind == ImageKind::Png && plan.outputs.contains_key("display") => "display".to_string(),
        None => "image".to_string(),
    };
    if !plan.outputs.contains_key(&output) {
        let known: Vec<&str> = plan.outputs.keys().map(String::as_str).collect();
        return Err(CliError::Other(anyhow!(
            "--output \"{output}\": graph \"{}\" has no such output; {}",
            plan.name,
            volgraph_core::suggest::guess_then(
                &output,
                known.iter().copied(),
                "",
                format!("its outputs are: {}", volgraph_core::suggest::comma_list(&known))
            )
        )));
    }
    // (A label map coloured by its own table — `label_table` with no `labels` input — ignores the TF.)
    let volume_is_labels = plan.inputs.iter().any(|(name, kind)| {
        *kind == volgraph_core::graph::ast::InputKind::LabelTable
            && crate::label_tables::map_input_of(name, &volume_input_names(&plan)).is_none()
    });
    if plan.inputs.values().any(|k| *k == volgraph_core::graph::ast::InputKind::TransferFunction)
        && !volume_is_labels
        && let Some(note) = inputs::invisible_volume_note(&volume, &lut)
    {
        notes.push(note);
    }
    Ok(Prepared {
        args,
        graph,
        kind,
        camera,
        frames,
        still,
        opacity,
        cuts,
        lights,
        environment,
        volume,
        lut,
        bindings,
        streamed: streamed.map(|s| s.source),
        plan,
        output,
        notes,
    })
}

/// The inputs bound by name, with the notes their reading gave: the named volumes (`others`,
/// loaded; `named[primary]` is the frame's `volume`, read from `frame_path`), each named `--tf` as a transfer function
/// or, for a `LabelTable` input, a label table, and every label table the graph reads (the
/// map's own names or the default palette where none is named). `None` when nothing is named
/// and the graph reads no label table.
pub(crate) fn named_bindings(
    plan: &volgraph_core::Plan,
    (named, primary, frame_path): (&[(String, PathBuf)], usize, Option<&Path>),
    others: Vec<(String, volgraph_accel::volume::Volume)>,
    (named_tfs, plain_tf): (&[(String, PathBuf)], Option<&PathBuf>),
    volume: &volgraph_accel::volume::Volume,
    tf_map: Option<&str>,
) -> anyhow::Result<Option<(NamedBindings, Vec<String>)>> {
    use volgraph_core::graph::ast::InputKind;
    let table_inputs: Vec<&String> =
        plan.inputs.iter().filter(|(_, k)| **k == InputKind::LabelTable).map(|(n, _)| n).collect();
    if named.is_empty() && named_tfs.is_empty() && table_inputs.is_empty() {
        return Ok(None);
    }
    let mut notes = Vec::new();
    let by_name = |n: &str| others.iter().find(|(o, _)| o == n).map(|(_, v)| v);
    let mut tfs = Vec::new();
    // The volume input a TF input classifies: `X` for `X_tf` where X is bound by name.
    let base_name = |name: &str| name.strip_suffix("_tf").filter(|b| by_name(b).is_some()).map(str::to_string);
    for (name, path) in named_tfs.iter().filter(|(n, _)| !table_inputs.contains(&n)) {
        // A TF named NAME_tf is fitted to (and its presets read in the units of) volume NAME.
        let base = name.strip_suffix("_tf").and_then(by_name).unwrap_or(volume);
        let (tf, tf_notes) =
            inputs::transfer_function(Some(path), tf_map, base, false).map_err(|e| anyhow!("--tf {name}=…: {e:#}"))?;
        notes.extend(tf_notes);
        let lut = tf.to_lut_for(base, inputs::LUT_SIZE);
        tfs.push(NamedTf { input: name.clone(), base: base_name(name), tf, given: Some(path.clone()), lut });
    }
    // An unnamed TF input X_tf of another volume X takes the plain --tf (or the default) fitted
    // to X: the frame volume's LUT would read X's normalized values in the frame volume's range.
    for name in plan.inputs.iter().filter(|(_, k)| **k == InputKind::TransferFunction).map(|(n, _)| n) {
        let Some(base) = name.strip_suffix("_tf").and_then(by_name) else { continue };
        if named_tfs.iter().any(|(n, _)| n == name) {
            continue;
        }
        let (tf, tf_notes) =
            inputs::transfer_function(plain_tf, tf_map, base, false).map_err(|e| anyhow!("{name}: {e:#}"))?;
        notes.extend(tf_notes);
        let lut = tf.to_lut_for(base, inputs::LUT_SIZE);
        // Not the plain --tf's file: that is the frame volume's, which "save TF" of this one must
        // not overwrite.
        tfs.push(NamedTf { input: name.clone(), base: base_name(name), tf, given: None, lut });
    }
    let volume_inputs = volume_input_names(plan);
    let mut tables = Vec::new();
    for name in table_inputs {
        let map_name = crate::label_tables::map_input_of(name, &volume_inputs);
        let map = map_name.as_deref().and_then(by_name).unwrap_or(volume);
        // The map's file (a .seg.nrrd or DICOM SEG names its own labels): a named one's, or the frame volume's.
        let map_path = match map_name.as_deref().and_then(|m| named.iter().find(|(n, _)| n == m)) {
            Some((_, path)) => Some(path.as_path()),
            None => frame_path,
        };
        let given = named_tfs.iter().find(|(n, _)| n == name).map(|(_, p)| p.as_path());
        let flag = crate::label_tables::blamed_flag(name, given.is_some(), map_name.as_deref());
        let (lut, table_notes) = crate::label_tables::label_lut(map, map_path, given, &flag)?;
        notes.extend(table_notes);
        tables.push((name.clone(), lut));
    }
    let primary = named.get(primary).map(|(n, _)| n.clone());
    Ok(Some((NamedBindings { primary, others, tfs, tables, allow_frame_mismatch: false }, notes)))
}

/// With no volume named, a graph reading several volume inputs gets the one volume in each (a
/// label map would be the scan itself): a note per other input, saying how to name them.
pub(crate) fn unnamed_volume_notes(plan: &volgraph_core::Plan, named: &[(String, PathBuf)]) -> Vec<String> {
    let inputs = volume_input_names(plan);
    if !named.is_empty() || inputs.len() < 2 {
        return Vec::new();
    }
    let frame = volgraph_core::runtime::inputs::PRIMARY_VOLUME;
    let frame = if inputs.contains(&frame) { frame } else { inputs[0] };
    inputs
        .iter()
        .filter(|n| **n != frame)
        .map(|n| {
            format!(
                "note: graph \"{}\" reads the volume input \"{n}\" too, and no --volume {n}=PATH names it: the one \
                 volume given is bound to it as well; give each by name (--volume {frame}=scan.nii.gz --volume \
                 {n}=other.nii.gz)",
                plan.name
            )
        })
        .collect()
}

/// The named volumes but the frame volume (`named[primary]`), loaded (a `#N` suffix picks a
/// volume of a 4D file); their notes go to `notes`. An error names the input (and the scene
/// file `scene_path` whose `volumes:` gave it).
pub(crate) fn load_other_volumes(
    named: &[(String, PathBuf)],
    primary: usize,
    raw: &volgraph_accel::load::LoadOptions<'static>,
    scene_path: Option<&Path>,
    notes: &mut Vec<String>,
) -> anyhow::Result<Vec<(String, volgraph_accel::volume::Volume)>> {
    let mut others = Vec::new();
    for (i, (name, path)) in named.iter().enumerate() {
        if i != primary {
            let (file, options) = crate::named_inputs::path_and_frame(path, raw);
            let shown = crate::scene::load_shown_volume(std::slice::from_ref(&file), None, &options).map_err(|e| {
                match scene_path {
                    Some(scene) => anyhow!("{}: volumes: \"{name}\": {e:#}", scene.display()),
                    None => anyhow!("--volume {name}=…: {e:#}"),
                }
            })?;
            notes.extend(shown.notes);
            others.push((name.clone(), shown.volume));
        }
    }
    Ok(others)
}

/// The graph's volume inputs, by name.
pub(crate) fn volume_input_names(plan: &volgraph_core::Plan) -> Vec<&str> {
    let volume = volgraph_core::graph::ast::InputKind::Volume;
    plan.inputs.iter().filter(|(_, k)| **k == volume).map(|(n, _)| n.as_str()).collect()
}

/// A note when `--gpu-memory-mb` was given to a graph none of whose passes streams data within
/// a budget (only the brick pool does): the flag changes nothing there.
pub fn budget_note(plan: &volgraph_core::Plan, registry: &volgraph_core::Registry, mb: Option<u64>) -> Option<String> {
    let mb = mb?;
    let uses = plan.steps.iter().any(|s| registry.get(&s.kind).is_some_and(|p| p.uses_gpu_memory_budget()));
    (!uses).then(|| {
        format!(
            "note: --gpu-memory-mb {mb}: graph \"{}\" has no pass that streams within a memory budget (the brick \
             pool of graphs/ruijters_vilanova_2006 does); the flag changes nothing here",
            plan.name
        )
    })
}

/// Opens the GPU, renders the frames and writes the image.
pub fn execute(prepared: Prepared) -> Result<(), CliError> {
    let Prepared {
        args,
        graph,
        kind,
        camera,
        frames,
        still,
        opacity,
        cuts,
        lights,
        environment,
        volume,
        lut,
        bindings,
        streamed,
        plan,
        output,
        ..
    } = prepared;
    let registry = crate::program::registry();
    let viewport = plan.viewport;
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let (sources, _) = crate::shader_dir::sources_for(&graph, args.inputs.shaders.as_deref());
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
    runtime.set_opacity_reference(opacity);
    runtime.set_cuts(cuts);
    runtime.set_lights(lights);
    runtime.set_environment(environment);
    runtime.set_gpu_memory_budget(args.inputs.gpu_memory_mb.map(|mb| mb << 20));
    match &bindings {
        Some(bindings) => bindings.bind(&mut runtime, &plan, &volume, &lut),
        None => runtime.bind_scene(&plan.inputs, &volume, &lut),
    }
    .map_err(|e| anyhow!(e))?;
    if let Some(source) = &streamed {
        runtime.bind_pyramid(volgraph_core::runtime::inputs::PRIMARY_VOLUME, source.clone());
    }
    if runtime.volume().is_some_and(|(_, f)| f == VolumeFormat::R16Float) && !matches!(volume.data, VoxelData::U8(_)) {
        crate::stdout::eprintln_escaped!(
            "note: this GPU filters neither 16-bit normalized nor 32-bit float textures; the volume is sampled as \
             16-bit float (11 significant bits)"
        );
    }
    runtime.apply(plan, &registry).map_err(|e| anyhow!(e))?;
    runtime.set_step_profiling(args.time_each_pass);
    // Frames one at a time, so each has its own time (the first includes pipeline JIT).
    let mut stats = Vec::new();
    // `--spp N`: the mean's error, estimated from the `image` at the powers of two of samples
    // (read after the frame, outside its time). The camera never moves, so a reprojecting path
    // tracer's mean is the plain running mean too.
    let has_image = runtime.plan().is_some_and(|p| p.outputs.contains_key("image"));
    let mut noise = (still && has_image).then(volgraph_accel::progressive_error::ErrorTracker::default);
    let started = std::time::Instant::now();
    for f in 0..frames {
        let at = if still { 0 } else { f };
        stats.push(runtime.render(CameraData::from_orbit(&camera.at(at), viewport)).map_err(|e| anyhow!(e))?);
        if let Some(tracker) = noise.as_mut() {
            let history = runtime.history_stats();
            if tracker.wants(history.run + 1) {
                let image = runtime.read_output("image").map_err(|e| anyhow!(e))?;
                tracker.offer(history.restarts, history.run + 1, image.to_rgba_f64());
            }
        }
    }
    // A streaming graph: frames at the last camera until the rays lack nothing (or the budget
    // is spent); the first frame was drawn from what was resident.
    let streaming = StreamProgress::of(&runtime.pass_counters());
    if !streaming.is_empty() {
        let last_camera = CameraData::from_orbit(&camera.at(if still { 0 } else { frames - 1 }), viewport);
        let budget = args.time_budget_ms.map(std::time::Duration::from_millis);
        let (complete, progress) =
            crate::stream_progress::refine_runtime(&mut runtime, last_camera, started, budget, |s| stats.push(s))?;
        if !complete {
            let missing: f64 = progress.iter().map(|p| p.missing).sum();
            crate::stdout::eprintln_escaped!(
                "note: --time-budget-ms {}: the last frame lacked {missing} bricks; they are drawn from a coarser level",
                args.time_budget_ms.unwrap_or(0)
            );
        }
        crate::stdout::eprintln_escaped!(
            "  {} frames, {:.0} ms from the first frame to the {} image",
            stats.len(),
            started.elapsed().as_secs_f64() * 1e3,
            if complete { "full" } else { "last" }
        );
    }
    let warm: Vec<f64> = stats.iter().skip(1).map(|s| s.frame_ms).collect();
    let last = stats.pop();
    let image = runtime.read_output(&output).map_err(|e| anyhow!(e))?;
    let plan = runtime.plan().ok_or_else(|| anyhow!("internal: no plan after rendering"))?;
    // An Rgba8Unorm output (`present`'s display) holds sRGB-encoded values.
    let srgb = image.channels == 4
        && plan.outputs.get(&output).is_some_and(|&r| {
            matches!(
                plan.resources[r].desc,
                volgraph_core::plan::ResourceDesc::Target { format: volgraph_core::TargetFormat::Rgba8Unorm, .. }
            )
        });
    match kind {
        ImageKind::Exr => image_out::write_exr(&args.out, &image, srgb)?,
        ImageKind::Png => image_out::write_png(&args.out, &image, srgb)?,
    }
    if let Some(stats) = last {
        let clock = match (stats.steps_serialised, stats.wall_time_fallback) {
            (true, _) => "wall time, passes one by one",
            (false, true) => "wall time",
            (false, false) => "GPU time",
        };
        crate::stdout::eprintln_escaped!(
            "{}: {}x{} on {}, last frame {:.2} ms {clock} → {}",
            graph.display(),
            viewport.0,
            viewport.1,
            runtime.gpu().adapter_name,
            stats.frame_ms,
            args.out.display()
        );
        if !warm.is_empty() {
            crate::stdout::eprintln_escaped!(
                "  median of frames 2..{}: {:.2} ms {clock}",
                warm.len() + 1,
                volgraph_accel::stats::median(&warm)
            );
        }
        if stats.step_gpu_ms.is_some() {
            // Per pass, repeat-group instances summed, in schedule order.
            let list: Vec<String> = stats.per_pass_ms().iter().map(|(id, ms)| format!("{id} {ms:.2}")).collect();
            let caveat = if runtime.gpu().timestamps_cover_work || stats.steps_serialised {
                ""
            } else {
                " (timestamps of a CPU adapter: compute passes are not covered; --time-each-pass times them)"
            };
            crate::stdout::eprintln_escaped!("  per pass (ms){caveat}: {}", list.join(", "));
        }
        if let Some(source) = &streamed {
            for line in volgraph_accel::pyramid::PyramidSource::notes(source.as_ref()) {
                crate::stdout::eprintln_escaped!("{line}");
            }
        }
        for line in crate::render::counter_lines(&runtime.pass_counters()) {
            crate::stdout::eprintln_escaped!("  {line}");
        }
        for b in runtime.bypass_status() {
            crate::stdout::eprintln_escaped!("  {}", bypass_line(&b));
        }
        if accumulates(plan) {
            // The mean holds the frames since history last started over.
            let history = runtime.history_stats();
            let samples = history.run + 1;
            crate::stdout::eprintln_escaped!("  {samples} samples per pixel accumulated");
            if let Some(estimate) = noise.as_ref().and_then(|t| t.last(history.restarts)) {
                crate::stdout::eprintln_escaped!("  {}", estimate.line(samples));
            }
        }
    }
    Ok(())
}

/// What passes reported about the last frame, one line per pass: the brick pool's uploads and
/// occupancy (`march: uploaded 3.2 MiB (52 bricks) in 1 batch; pool 120/120 slots, 48.0 MiB;
/// 118 of 512 bricks visible`), other counters as `name value`.
pub fn counter_lines(counters: &[(String, &'static str, f64)]) -> Vec<String> {
    let mut passes: Vec<&str> = counters.iter().map(|(p, _, _)| p.as_str()).collect();
    passes.dedup();
    let streaming = StreamProgress::of(counters);
    passes
        .into_iter()
        .map(|pass| {
            if let Some(progress) = streaming.iter().find(|p| p.pass == pass) {
                return progress.line();
            }
            let get = |name: &str| counters.iter().find(|(p, n, _)| p == pass && *n == name).map(|c| c.2);
            let mib = |b: f64| b / (1024.0 * 1024.0);
            match (get("uploaded_bytes"), get("pool_slots")) {
                (Some(up), Some(slots)) => format!(
                    "{pass}: uploaded {:.1} MiB ({} bricks) in {} batch(es); pool {}/{} slots, {:.1} MiB; {} of {} bricks \
                     visible; last TF classification {:.2} ms",
                    mib(up),
                    get("uploaded_bricks").unwrap_or(0.0),
                    get("batches").unwrap_or(0.0),
                    get("resident_bricks").unwrap_or(0.0),
                    slots,
                    mib(get("pool_bytes").unwrap_or(0.0)),
                    get("visible_bricks").unwrap_or(0.0),
                    get("bricks").unwrap_or(0.0),
                    get("classify_ms").unwrap_or(0.0),
                ),
                _ => {
                    let all: Vec<String> = counters
                        .iter()
                        .filter(|(p, _, _)| p == pass)
                        .map(|(_, n, v)| format!("{n} {v}"))
                        .collect();
                    format!("{pass}: {}", all.join(", "))
                }
            }
        })
        .collect()
}

/// Whether `plan` keeps a running mean over still frames (a progressive graph: `--spp` adds to
/// it): a history that restarts on any camera move, or a `samples` output — each pixel's own
/// sample count in `.x`, which a mean that follows the view across moves (a reprojecting path
/// tracer) keeps (docs/graph_format.md, "Outputs").
pub fn accumulates(plan: &volgraph_core::Plan) -> bool {
    plan.history.values().any(|h| h.while_camera_still) || plan.outputs.contains_key(SAMPLES_OUTPUT)
}

/// The output of a progressive graph whose pixels keep their own sample counts (in `.x`).
pub const SAMPLES_OUTPUT: &str = "samples";

/// Whether the view's error of `plan` can be estimated from its own `image` at powers of two of
/// samples (`volgraph_accel::progressive_error`): a running mean of independent samples per
/// pixel, started over on any change (`while_camera_still`) — a reprojected mean holds its own
/// count per pixel after a move, which the doubling estimate does not know.
pub fn estimates_noise(plan: Option<&volgraph_core::Plan>) -> bool {
    plan.is_some_and(|p| p.history.values().any(|h| h.while_camera_still) && p.outputs.contains_key("image"))
}

/// One line saying what a graph's bypass did over the frames rendered.
pub(crate) fn bypass_line(b: &volgraph_core::runtime::BypassStatus) -> String {
    let frames = b.frames_bypassed + b.frames_run;
    let measure = b.measure.map_or("not measured yet".to_string(), |m| format!("last measure {m:.1} per pixel"));
    format!(
        "bypass {}: left out in {} of {frames} frames ({measure}, threshold {}; the last frame {})",
        b.name,
        b.frames_bypassed,
        b.below,
        if b.bypassed { "left them out" } else { "ran them" }
    )
}
