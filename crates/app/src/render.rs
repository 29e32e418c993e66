//! `volgraph render`: every input is read and checked (graph, volume, transfer function, sizes,
//! the output file's kind) before the GPU is opened, then frames are drawn and the last one is
//! written.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::anyhow;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::VoxelData;
use volgraph_core::compile;
use volgraph_core::runtime::{CameraData, Gpu, Runtime, ShaderLibrary, VolumeDesc, VolumeFormat, scene_values_of};
use volgraph_passes::builtin_registry;

use crate::cli::{CliError, RawArgs, check_user_names, compile_options, display_name, warning_lines};
use crate::image_out::{self, ImageKind};
use crate::inputs;

/// The arguments of `volgraph render`.
pub struct RenderArgs {
    pub graph: PathBuf,
    pub volume: Option<PathBuf>,
    pub raw: RawArgs,
    pub tf: Option<PathBuf>,
    pub tf_map: Option<String>,
    pub size: String,
    pub camera: String,
    pub frames: u32,
    pub features: Vec<String>,
    pub output: Option<String>,
    pub out: PathBuf,
    pub shaders: Option<PathBuf>,
}

/// Everything `render` needs, read and checked, before the GPU is opened.
pub struct Prepared {
    args: RenderArgs,
    kind: ImageKind,
    camera: OrbitCamera,
    volume: volgraph_accel::volume::Volume,
    lut: Vec<[f32; 4]>,
    plan: volgraph_core::Plan,
    output: String,
    /// Notes and warnings for stderr (repairs, choices made, capped counts, invisible data).
    pub notes: Vec<String>,
}

/// Reads and checks every input of `volgraph render`; touches no GPU, prints nothing.
pub fn prepare(args: RenderArgs) -> Result<Prepared, CliError> {
    let kind = ImageKind::from_path(&args.out)?;
    let source = inputs::read_graph(&args.graph)?;
    let options = compile_options(&args.size, &args.features, &[])?;
    let camera = inputs::parse_camera(&args.camera)?;
    let generated = args.volume.is_none();
    let (volume, mut notes) = inputs::volume(args.volume.as_ref(), &inputs::raw_options(&args.raw)?)?;
    let (tf, tf_notes) = inputs::transfer_function(args.tf.as_ref(), args.tf_map.as_deref(), &volume, generated)?;
    notes.extend(tf_notes);
    let lut = tf.to_lut_for(&volume, inputs::LUT_SIZE);
    let registry = builtin_registry();
    let file = display_name(&args.graph);
    let mut options = options;
    options.scene = scene_values_of(&VolumeDesc::of(&volume));
    let plan = compile(&file, &source, &registry, &options).map_err(CliError::Graph)?;
    check_user_names(&plan, &options)?;
    notes.extend(warning_lines(&plan));
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
    if plan.inputs.values().any(|k| *k == volgraph_core::graph::ast::InputKind::TransferFunction)
        && let Some(note) = inputs::invisible_volume_note(&volume, &lut)
    {
        notes.push(note);
    }
    Ok(Prepared { args, kind, camera, volume, lut, plan, output, notes })
}

/// Opens the GPU, renders the frames and writes the image.
pub fn execute(prepared: Prepared) -> Result<(), CliError> {
    let Prepared { args, kind, camera, volume, lut, plan, output, .. } = prepared;
    let registry = builtin_registry();
    let viewport = plan.viewport;
    let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let (sources, _) = crate::shader_dir::sources_for(&args.graph, args.shaders.as_deref());
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
    runtime.bind_scene(&plan.inputs, &volume, &lut).map_err(|e| anyhow!(e))?;
    if runtime.volume().is_some_and(|(_, f)| f == VolumeFormat::R16Float) && !matches!(volume.data, VoxelData::U8(_)) {
        eprintln!(
            "note: this GPU filters neither 16-bit normalized nor 32-bit float textures; the volume is sampled as \
             16-bit float (11 significant bits)"
        );
    }
    runtime.apply(plan, &registry).map_err(|e| anyhow!(e))?;
    // Frames one at a time, so each has its own time (the first includes pipeline JIT).
    let mut stats = Vec::new();
    for f in 0..args.frames {
        let cam = OrbitCamera { azimuth_deg: camera.azimuth_deg + f as f64, ..camera };
        stats.push(runtime.render(CameraData::from_orbit(&cam, viewport)).map_err(|e| anyhow!(e))?);
    }
    let warm: Vec<f64> = stats.iter().skip(1).map(|s| s.frame_ms).collect();
    let last = stats.pop();
    let image = runtime.read_output(&output).map_err(|e| anyhow!(e))?;
    let plan = runtime.plan().ok_or_else(|| anyhow!("internal: no plan after rendering"))?;
    match kind {
        ImageKind::Exr => image_out::write_exr(&args.out, &image)?,
        ImageKind::Png => {
            let srgb = image.channels == 4
                && plan.outputs.get(&output).is_some_and(|&r| {
                    matches!(
                        plan.resources[r].desc,
                        volgraph_core::plan::ResourceDesc::Target {
                            format: volgraph_core::TargetFormat::Rgba8Unorm,
                            ..
                        }
                    )
                });
            image_out::write_png(&args.out, &image, srgb)?;
        }
    }
    if let Some(stats) = last {
        let clock = if stats.wall_time_fallback { "wall time" } else { "GPU time" };
        eprintln!(
            "{}: {}x{} on {}, last frame {:.2} ms {clock} → {}",
            args.graph.display(),
            viewport.0,
            viewport.1,
            runtime.gpu().adapter_name,
            stats.frame_ms,
            args.out.display()
        );
        if !warm.is_empty() {
            eprintln!(
                "  median of frames 2..{}: {:.2} ms {clock}",
                warm.len() + 1,
                crate::bench_graphs::measure::median(&warm)
            );
        }
        if stats.step_gpu_ms.is_some() {
            // Per pass, repeat-group instances summed, in schedule order.
            let list: Vec<String> = stats.per_pass_ms().iter().map(|(id, ms)| format!("{id} {ms:.2}")).collect();
            let caveat = if runtime.gpu().timestamps_cover_work {
                ""
            } else {
                " (timestamps of a CPU adapter: compute passes are not covered)"
            };
            eprintln!("  per pass (ms){caveat}: {}", list.join(", "));
        }
    }
    Ok(())
}
