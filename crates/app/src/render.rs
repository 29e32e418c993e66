//! `volgraph render`: every input is read and checked (graph, volume, transfer function, sizes,
//! the output file's kind) before the GPU is opened, then frames are drawn and the last one is
//! written.

use std::path::PathBuf;

use anyhow::anyhow;
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::VoxelData;
use volgraph_core::compile;
use volgraph_core::executor::{Gpu, ShaderLibrary, VolumeFormat};
use volgraph_core::shader_source::default_shader_root;
use volgraph_passes::builtin_registry;
use volgraph_passes::session::RenderSession;

use crate::cli::{CliError, RawArgs, check_user_names, compile_options, display_name, warning_lines, with_longest_ray};
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
    let options = with_longest_ray(&file, &source, &registry, options, &volume)?;
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
    let options_viewport = plan.viewport;
    let gpu = Gpu::new_headless().map_err(|e| anyhow!(e))?;
    let shaders = ShaderLibrary::new(default_shader_root());
    let mut session = RenderSession::from_plan(&gpu, &shaders, &registry, plan, &volume, &lut)?;
    if session.volume_format() == Some(VolumeFormat::R16Float) && !matches!(volume.data, VoxelData::U8(_)) {
        eprintln!(
            "note: this GPU filters neither 16-bit normalized nor 32-bit float textures; the volume is sampled as \
             16-bit float (11 significant bits)"
        );
    }
    let mut last = None;
    for f in 0..args.frames {
        let cam = OrbitCamera { azimuth_deg: camera.azimuth_deg + f as f64, ..camera };
        last = Some(session.render(&gpu, &cam)?);
    }
    let image = session.read(&gpu, &output)?;
    match kind {
        ImageKind::Exr => image_out::write_exr(&args.out, &image)?,
        ImageKind::Png => {
            let srgb = image.channels == 4
                && session.plan().outputs.get(&output).is_some_and(|&r| {
                    matches!(
                        session.plan().resources[r].desc,
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
        let clock = if stats.wall_time_fallback { "wall time (no GPU timestamps)" } else { "GPU time" };
        eprintln!(
            "{}: {}x{} on {}, last frame {:.2} ms {clock} → {}",
            args.graph.display(),
            options_viewport.0,
            options_viewport.1,
            gpu.adapter_name,
            stats.frame_ms,
            args.out.display()
        );
        if let Some(step_ms) = &stats.step_gpu_ms {
            // Per pass, repeat-group instances summed, in schedule order.
            let mut per_pass: Vec<(String, f64)> = Vec::new();
            for (step, ms) in session.plan().steps.iter().zip(step_ms) {
                match per_pass.iter_mut().find(|(id, _)| *id == step.pass_id) {
                    Some((_, total)) => *total += ms,
                    None => per_pass.push((step.pass_id.clone(), *ms)),
                }
            }
            let list: Vec<String> = per_pass.iter().map(|(id, ms)| format!("{id} {ms:.2}")).collect();
            eprintln!("  per pass (ms): {}", list.join(", "));
        }
    }
    Ok(())
}
