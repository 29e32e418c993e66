//! Command-line arguments and the subcommands they run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow};
use clap::{Parser, Subcommand};
use volgraph_accel::camera::OrbitCamera;
use volgraph_core::executor::{Gpu, ShaderLibrary};
use volgraph_core::shader_source::default_shader_root;
use volgraph_core::{CompileOptions, Diagnostics, compile};
use volgraph_passes::builtin_registry;
use volgraph_passes::session::{RenderSession, SessionError};

use crate::{image_out, inputs};

/// volgraph: GPU volume rendering assembled from a declarative render graph.
#[derive(Parser, Debug)]
#[command(name = "volgraph", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Compile a graph and print its schedule: ordered passes, culled passes, targets → slots,
    /// pooled vs unpooled transient memory.
    Plan {
        /// The graph file (RON).
        graph: PathBuf,
        /// Viewport, WIDTHxHEIGHT.
        #[arg(long, default_value = "1920x1080")]
        size: String,
        /// Scene features that are on, comma separated (e.g. shading,antialias).
        #[arg(long, value_delimiter = ',')]
        features: Vec<String>,
        /// Scene values, NAME=VALUE (repeat counts, ...).
        #[arg(long = "scalar", value_parser = parse_scalar)]
        scalars: Vec<(String, f64)>,
    },
    /// Render a graph to an image (PNG: 8-bit sRGB; EXR: 32-bit float linear).
    Render {
        /// The graph file (RON).
        graph: PathBuf,
        /// Volume file (.raw named NAME_XxYxZ_TYPE.raw, .nrrd, .nhdr, .mhd, .mha); default: a
        /// generated Marschner–Lobb 64³.
        #[arg(long)]
        volume: Option<PathBuf>,
        #[command(flatten)]
        raw: RawArgs,
        /// Transfer function (RON, or ParaView color-map .json); default: one fitted to the data.
        #[arg(long)]
        tf: Option<PathBuf>,
        /// Viewport, WIDTHxHEIGHT.
        #[arg(long, default_value = "512x512")]
        size: String,
        /// Orbit camera AZIMUTH,ELEVATION,DISTANCE (degrees, degrees, world units).
        #[arg(long, default_value = "30,20,3.2")]
        camera: String,
        /// Frames to render (the last one is written); each rotates the volume 1° about y.
        #[arg(long, default_value_t = 1)]
        frames: u32,
        /// Scene features that are on, comma separated.
        #[arg(long, value_delimiter = ',')]
        features: Vec<String>,
        /// The graph output to write; default: "display" for PNG when the graph has it, else "image".
        #[arg(long)]
        output: Option<String>,
        /// Where to write the image (.png or .exr).
        #[arg(short = 'o', long = "out")]
        out: PathBuf,
    },
    /// Measure: `volgraph bench accel` (CPU acceleration structures).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

/// How to read a headerless `.raw` volume whose name does not say (or to override the name).
#[derive(clap::Args, Debug, Default)]
pub struct RawArgs {
    /// Raw volume dimensions, XxYxZ (default: from the file name NAME_XxYxZ_TYPE.raw).
    #[arg(long)]
    pub dims: Option<String>,
    /// Raw voxel type: uint8, uint16, int16 or float32 (default: from the file name).
    #[arg(long)]
    pub dtype: Option<String>,
    /// Voxel spacing X,Y,Z (overrides the file's header; default 1,1,1 for raw files).
    #[arg(long)]
    pub spacing: Option<String>,
    /// Raw 16/32-bit voxels are big-endian.
    #[arg(long)]
    pub big_endian: bool,
}

#[derive(Subcommand, Debug)]
#[allow(clippy::large_enum_variant, reason = "parsed once per process; boxing would only obscure the clap derive")]
enum BenchCommand {
    /// Min/max grid + classification of the engine volume; octree rebuild after a TF change.
    Accel {
        /// Repetitions per figure (the median is reported).
        #[arg(long, default_value_t = 7)]
        repeats: usize,
        /// Write the figures as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Time render graphs over datasets, transfer functions and viewports (presets: basic,
    /// kw2003-table1, thesis-tables); speed-ups vs a baseline, samples/s, accuracy sweeps.
    Graphs(crate::bench_graphs::GraphsArgs),
    /// Compile time of a generated 30-pass graph; pooled vs unpooled transient memory of every
    /// graph in graphs/ at 1920x1080.
    Compile {
        /// Write the figures as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

fn parse_scalar(text: &str) -> Result<(String, f64), String> {
    let (name, value) = text.split_once('=').ok_or_else(|| format!("\"{text}\": expected NAME=VALUE"))?;
    let value: f64 = value.parse().map_err(|_| format!("\"{text}\": \"{value}\" is not a number"))?;
    Ok((name.to_string(), value))
}

/// What went wrong, split so graph diagnostics can be drawn with their source excerpts.
pub enum CliError {
    /// Problems in a graph file.
    Graph(Diagnostics),
    /// Anything else.
    Other(anyhow::Error),
}

impl From<anyhow::Error> for CliError {
    fn from(e: anyhow::Error) -> Self {
        CliError::Other(e)
    }
}

impl From<SessionError> for CliError {
    fn from(e: SessionError) -> Self {
        match e {
            SessionError::Graph(d) => CliError::Graph(d),
            other => CliError::Other(anyhow!(other)),
        }
    }
}

fn compile_options(size: &str, features: &[String], scalars: &[(String, f64)]) -> anyhow::Result<CompileOptions> {
    let (w, h) = inputs::parse_size(size)?;
    let mut o = CompileOptions::new(w, h).with_features(features.iter().filter(|f| !f.is_empty()).cloned());
    o.scalars = scalars.iter().cloned().collect::<BTreeMap<_, _>>();
    Ok(o)
}

fn display_name(path: &Path) -> String {
    path.display().to_string()
}

/// Multipass graphs size their segment loop by the scene value `longest_ray_steps` (K of
/// Krüger–Westermann §3): when the graph declares it and the user did not set it, compute it for
/// this volume and the graph's own step.
fn with_longest_ray(
    file: &str,
    source: &str,
    registry: &volgraph_core::Registry,
    mut options: CompileOptions,
    volume: &volgraph_accel::volume::Volume,
) -> Result<CompileOptions, CliError> {
    const K: &str = "longest_ray_steps";
    let plan = compile(file, source, registry, &options).map_err(CliError::Graph)?;
    if !plan.inputs.contains_key(K) || options.scalars.contains_key(K) {
        return Ok(options);
    }
    let step = plan
        .steps
        .iter()
        .find(|s| s.params.iter().any(|(name, _)| name == "step_voxels"))
        .map_or(0.5, |s| s.params.float("step_voxels"));
    options.scalars.insert(K.to_string(), volgraph_passes::scene::longest_ray_steps(volume, step));
    Ok(options)
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Plan { graph, size, features, scalars } => {
            let source = inputs::read_graph(&graph)?;
            let options = compile_options(&size, &features, &scalars)?;
            let plan =
                compile(&display_name(&graph), &source, &builtin_registry(), &options).map_err(CliError::Graph)?;
            crate::stdout::write_stdout(&plan.to_text())?;
            Ok(())
        }
        Command::Render { graph, volume, raw, tf, size, camera, frames, features, output, out } => {
            let source = inputs::read_graph(&graph)?;
            let options = compile_options(&size, &features, &[])?;
            let camera = inputs::parse_camera(&camera)?;
            let generated = volume.is_none();
            let volume = inputs::volume(volume.as_ref(), &inputs::raw_options(&raw)?)?;
            let tf = inputs::transfer_function(tf.as_ref(), &volume, generated)?;
            let lut = tf.to_lut_for(&volume, inputs::LUT_SIZE);
            let gpu = Gpu::new_headless().map_err(|e| anyhow!(e))?;
            let shaders = ShaderLibrary::new(default_shader_root());
            let registry = builtin_registry();
            let file = display_name(&graph);
            let options = with_longest_ray(&file, &source, &registry, options, &volume)?;
            let plan = compile(&file, &source, &registry, &options).map_err(CliError::Graph)?;
            let mut session = RenderSession::from_plan(&gpu, &shaders, &registry, plan, &volume, &lut)?;
            let is_exr = out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
            let output = output.unwrap_or_else(|| {
                if !is_exr && session.plan().outputs.contains_key("display") {
                    "display".to_string()
                } else {
                    "image".to_string()
                }
            });
            let mut last = None;
            for f in 0..frames.max(1) {
                let cam = OrbitCamera { azimuth_deg: camera.azimuth_deg + f as f64, ..camera };
                last = Some(session.render(&gpu, &cam)?);
            }
            let image = session.read(&gpu, &output)?;
            if is_exr {
                image_out::write_exr(&out, &image)?;
            } else {
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
                image_out::write_png(&out, &image, srgb)?;
            }
            if let Some(stats) = last {
                let clock = if stats.wall_time_fallback { "wall time (no GPU timestamps)" } else { "GPU time" };
                eprintln!(
                    "{}: {}x{} on {}, last frame {:.2} ms {clock} → {}",
                    graph.display(),
                    options.viewport.0,
                    options.viewport.1,
                    gpu.adapter_name,
                    stats.frame_ms,
                    out.display()
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
        Command::Bench { which: BenchCommand::Accel { repeats, json } } => {
            let opts = crate::bench_accel::AccelBenchOptions {
                data_dir: volgraph_accel::data_dir::data_dir(),
                repeats,
                json_out: json,
            };
            crate::bench_accel::run(&opts).context("bench accel")?;
            Ok(())
        }
        Command::Bench { which: BenchCommand::Compile { json } } => {
            crate::bench_compile::run(json.as_deref()).context("bench compile")?;
            Ok(())
        }
        Command::Bench { which: BenchCommand::Graphs(args) } => {
            crate::bench_graphs::run_cli(&args).context("bench graphs")?;
            Ok(())
        }
    }
}
