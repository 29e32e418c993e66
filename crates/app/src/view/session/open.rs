//! Opening a live session: the volume, the transfer function and the graph of a scene or the
//! command line, compiled (a failure here is the command's error, with located diagnostics) and
//! applied on a new runtime.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::anyhow;
use volgraph_core::runtime::{Gpu, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Registry, cut_effects};

use super::tf::scanner_preset_named;
use super::{Event, LiveSession, SessionArgs, summary};
use crate::inputs;
use crate::view::workbench::{GraphEdits, TfEdits, Workbench};

impl LiveSession {
    /// Loads the scene and the graph on `gpu`; fails (with located diagnostics) when the graph
    /// does not compile at start.
    pub fn open(gpu: Arc<Gpu>, args: &SessionArgs) -> Result<(Self, Event), crate::cli::CliError> {
        Self::open_with(gpu, args, crate::program::registry())
    }

    /// [`Self::open`] with another registry (built-ins plus a plugin crate's kinds).
    pub fn open_with(
        gpu: Arc<Gpu>,
        args: &SessionArgs,
        registry: Registry,
    ) -> Result<(Self, Event), crate::cli::CliError> {
        let start = Instant::now();
        let source = inputs::read_graph(&args.graph)?;
        // An OME-Zarr store shown by a streaming graph is read brick by brick as frames go on
        // (the panel counts the bricks pending); the session holds its coarsest level.
        let streamed = match args.volume.as_slice() {
            [one] if volgraph_zarr::is_zarr(one) && crate::zarr_input::graph_streams(&source) => {
                Some((one.clone(), crate::zarr_input::stream(one, &args.raw, args.memory_mb)?))
            }
            [one] if crate::zarr_input::graph_streams(&source) => {
                crate::zarr_input::stream_file(one, &args.raw, args.memory_mb, |line| {
                    crate::stdout::eprintln_escaped!("{line}")
                })?
                .map(|s| (one.clone(), s))
            }
            [one] => {
                crate::zarr_input::refuse_large_file(one, &args.raw)?;
                None
            }
            _ => None,
        };
        let shown = match &streamed {
            Some((path, s)) => crate::scene::ShownVolume {
                volume: s.coarsest.clone(),
                source: Ok(crate::scene::VolumeSource::File(path.display().to_string())),
                options: args.raw.clone(),
                marschner_lobb_tf: false,
                notes: s.notes.clone(),
            },
            None => crate::scene::load_shown_volume(&args.volume, args.scene.as_ref(), &args.raw)?,
        };
        let pyramid: Option<Arc<dyn volgraph_accel::pyramid::PyramidSource>> = streamed.map(|(_, s)| s.source);
        let (volume, generated, notes) = (shown.volume, shown.marschner_lobb_tf, shown.notes);
        for note in notes {
            crate::stdout::eprintln_escaped!("note: {note}");
        }
        let (tf, tf_path, tf_notes) = match (&args.tf, &args.scene) {
            (None, Some(scene)) => {
                crate::scene::load_transfer_function(scene, args.tf_map.as_deref(), &volume, generated)?
            }
            (tf, _) => {
                let (t, notes) = inputs::transfer_function(tf.as_ref(), args.tf_map.as_deref(), &volume, generated)?;
                (t, tf_file_and_source(tf.as_ref()).0, notes)
            }
        };
        let tf_source = match (&args.tf, &args.scene) {
            (None, Some(scene)) => scene.transfer_function.clone(),
            (tf, _) => tf_file_and_source(tf.as_ref()).1,
        };
        for note in tf_notes {
            crate::stdout::eprintln_escaped!("note: {note}");
        }
        let lut = tf.to_lut_for(&volume, inputs::LUT_SIZE);
        let tf = TfEdits::new(tf, tf_path, args.tf_map.clone(), tf_source, &volume, generated);
        let (sources, _) = crate::shader_dir::sources_for(&args.graph, args.shaders.as_deref());
        // Every folder read (and so watched), in search order: the start line and the panel name
        // all of them, not just the first.
        let shader_dirs: Vec<PathBuf> = sources.disk_roots().into_iter().map(Path::to_path_buf).collect();
        let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
        runtime.set_gpu_memory_budget(args.gpu_memory_mb.map(|mb| mb << 20));
        let mut options = CompileOptions::new(args.viewport.0, args.viewport.1)
            .with_features(args.features.iter().filter(|f| !f.is_empty()).cloned());
        options.features.extend(cut_effects::features_of(&args.cuts));
        runtime.set_cuts(args.cuts);
        runtime.set_lights(args.lights);
        if let Some(path) = &args.environment {
            runtime.set_environment(Some(std::sync::Arc::new(crate::environment_file::load_environment(path)?)));
        }
        if let Some(scene) = &args.scene {
            options.features.extend(scene.effects.iter().cloned());
            options.precision = scene.precision;
            runtime.set_opacity_reference(scene.opacity_reference);
        }
        let mut graph = GraphEdits::new(&args.graph, source, options.clone(), registry, &volume);
        if let Some(p) = &pyramid {
            graph.set_volume_box(&volgraph_core::runtime::VolumeDesc::of_box(p.levels()[0].dims, p.spacing()));
        }
        let plan = graph.compile(graph.source(), &options).map_err(crate::cli::CliError::Graph)?;
        // A scene's effect the graph does not offer is left out with a note; a --features typo is
        // an error.
        if let Some(scene) = &args.scene {
            for effect in &scene.effects {
                if !plan.known_features.contains(effect) && !args.features.contains(effect) {
                    crate::stdout::eprintln_escaped!(
                        "note: graph \"{}\" does not offer the scene's effect \"{effect}\"; it is left out",
                        plan.name
                    );
                    options.features.remove(effect);
                }
            }
        }
        crate::cli::check_user_names(&plan, &options)?;
        if let Some(note) = crate::render::budget_note(&plan, graph.registry(), args.gpu_memory_mb) {
            crate::stdout::eprintln_escaped!("{note}");
        }
        let shaders = match shader_dirs.as_slice() {
            [] => "built-in shaders".to_string(),
            dirs => format!(
                "shaders from {} (watched), then the built-in ones",
                dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
            ),
        };
        let loaded = format!("{}, {shaders}", summary(&plan));
        for note in crate::render::unnamed_volume_notes(&plan, &args.named) {
            crate::stdout::eprintln_escaped!("{note}");
        }
        // Inputs bound by name, as `render` binds them (the others loaded, checked for one frame).
        let bindings = if args.named.is_empty() && args.named_tfs.is_empty() {
            None
        } else {
            let primary = crate::named_inputs::NamedBindings::primary_index(&args.named);
            let mut notes = Vec::new();
            let others = crate::render::load_other_volumes(&args.named, primary, &args.raw, None, &mut notes)?;
            let frame_path = args.volume.first().map(PathBuf::as_path);
            let named = (args.named.as_slice(), primary, frame_path);
            let tfs = (args.named_tfs.as_slice(), args.tf.as_ref());
            let found = crate::render::named_bindings(&plan, named, others, tfs, &volume, args.tf_map.as_deref())?;
            found
                .map(|(bindings, binding_notes)| {
                    notes.extend(binding_notes);
                    let file = graph.path().display().to_string();
                    notes.extend(bindings.check(&plan, &file, graph.source(), &volume)?);
                    for note in &notes {
                        crate::stdout::eprintln_escaped!("{note}");
                    }
                    anyhow::Ok(bindings)
                })
                .transpose()?
        };
        match &bindings {
            Some(b) => b.bind(&mut runtime, &plan, &volume, &lut),
            None => runtime.bind_scene(&plan.inputs, &volume, &lut),
        }
        .map_err(|e| crate::cli::CliError::Other(anyhow!(e)))?;
        if let Some(p) = &pyramid {
            runtime.bind_pyramid(volgraph_core::runtime::inputs::PRIMARY_VOLUME, p.clone());
        }
        // A graph that reads a label table shows its label map's list: the volume input the
        // table colours (`label_tables::map_input_of`), else the frame volume; named by the
        // table given, the map's own file (.seg.nrrd) or the default palette.
        let table_input = plan.inputs.iter().find(|(_, k)| **k == volgraph_core::graph::ast::InputKind::LabelTable);
        let map_name = table_input
            .and_then(|(t, _)| crate::label_tables::map_input_of(t, &crate::render::volume_input_names(&plan)));
        let labels_are_the_volume = table_input.is_some() && map_name.is_none();
        let labels = if let Some((table_name, _)) = table_input {
            let other = |name: &str| bindings.as_ref().and_then(|b| b.others.iter().find(|(n, _)| n == name));
            let map = map_name.as_deref().and_then(other).map_or(&volume, |(_, v)| v);
            let map_path = match map_name.as_deref().and_then(|m| args.named.iter().find(|(n, _)| n == m)) {
                Some((_, path)) => Some(path.as_path()),
                None => args.volume.first().map(PathBuf::as_path),
            };
            let given = args.named_tfs.iter().find(|(n, _)| n == table_name).map(|(_, p)| p.as_path());
            let flag = crate::label_tables::blamed_flag(table_name, given.is_some(), map_name.as_deref());
            let (table, _, notes) = crate::label_tables::label_table(map, map_path, given, &flag)?;
            for note in notes {
                crate::stdout::eprintln_escaped!("{note}");
            }
            let list = crate::view::label_list::LabelList::of(map, &table).map_err(|e| anyhow!(e))?;
            super::bind_label_list(&mut runtime, &plan.inputs, Some(&list)).map_err(|e| anyhow!(e))?;
            Some(list)
        } else {
            None
        };
        // One TF editor per scalar volume: each TF bound by name or of another volume; the
        // editor starts on the frame volume's unless every TF input is named.
        let named_tfs: Vec<(String, TfEdits)> = bindings.as_ref().map_or_else(Vec::new, |b| {
            b.tfs
                .iter()
                .map(|t| {
                    let (path, source) = tf_file_and_source(t.given.as_ref());
                    let edits =
                        TfEdits::new(t.tf.clone(), path, args.tf_map.clone(), source, b.base_of(t, &volume), false);
                    (t.input.clone(), edits.for_input(&t.input))
                })
                .collect()
        });
        let every_tf_named = plan
            .inputs
            .iter()
            .filter(|(_, k)| **k == volgraph_core::graph::ast::InputKind::TransferFunction)
            .all(|(n, _)| named_tfs.iter().any(|(t, _)| t == n));
        let tf_target = if every_tf_named { named_tfs.first().map(|(n, _)| n.clone()) } else { None };
        runtime.apply(plan, graph.registry()).map_err(|e| crate::cli::CliError::Other(anyhow!(e)))?;
        graph.set_options(options);
        let graph_name = graph.name().to_string();
        let session = Self {
            runtime,
            bench: Workbench { graph, tf, named_tfs, tf_target },
            volume,
            pyramid,
            lut,
            shader_dirs,
            error: None,
            validated: None,
            unproven: true,
            volume_source: shown.source,
            volume_options: shown.options,
            opacity_reference: args.scene.as_ref().map(|s| s.opacity_reference).unwrap_or_default(),
            labels,
            labels_are_the_volume,
            label_map_input: map_name,
            bindings,
            environment: args.environment.clone(),
            noise: Default::default(),
            resting: Default::default(),
            slices: None,
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        Ok((session, Event::Loaded { graph: graph_name, ms, summary: loaded }))
    }
}

/// What `--tf` gave (`given`), as the TF editor keeps it: the file to watch — none for a
/// preset's or a built-in TF's name, which "save TF" writes elsewhere — and where the TF came
/// from, for "save view" (`None`: fitted to the data).
fn tf_file_and_source(given: Option<&PathBuf>) -> (Option<PathBuf>, Option<crate::scene::TfSource>) {
    let Some(p) = given else { return (None, None) };
    let file = scanner_preset_named(p).is_none() && crate::builtin_graphs::find_tf(p).is_none();
    let source = match scanner_preset_named(p) {
        Some(name) => crate::scene::TfSource::Preset(name.to_string()),
        None => crate::scene::TfSource::File(p.display().to_string()),
    };
    (file.then(|| p.clone()), Some(source))
}
