//! Command-line arguments and the subcommands they run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use clap::{Parser, Subcommand};
use volgraph_core::{CompileOptions, Diagnostics, compile};

use crate::inputs;

/// volgraph: GPU volume rendering assembled from a declarative render graph.
#[derive(Parser, Debug)]
#[command(name = "volgraph", version)]
pub struct Cli {
    /// The data folder: volumes/ (with MANIFEST.md) and tf/ (default: $VOLGRAPH_DATA, else
    /// ../shared/data).
    #[arg(long, global = true, value_name = "DIR")]
    data: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

impl Cli {
    /// The arguments of a `render` command line (`None` for another command).
    pub fn into_render_args(self) -> Option<crate::render::RenderArgs> {
        match self.command {
            Command::Render(args) => Some(args),
            _ => None,
        }
    }
}

/// The subcommands every volgraph program has (a plugin's binary too, `crate::main_with`).
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
        /// Scene features that are on, comma separated: the scene effects shading, preintegration,
        /// jitter, tricubic (e.g. shading,jitter), or a feature the graph gates passes on (`when:`).
        #[arg(long, value_delimiter = ',')]
        features: Vec<String>,
        /// Scene values, NAME=VALUE (repeat counts, ...).
        #[arg(long = "scalar", value_parser = parse_scalar)]
        scalars: Vec<(String, f64)>,
        /// Print the plan as a Graphviz DOT picture instead (passes, values with their slots,
        /// culled passes greyed, repeat groups boxed, history edges dashed): `| dot -Tsvg`.
        #[arg(long, conflicts_with = "svg")]
        dot: bool,
        /// Print the plan as an SVG picture instead, drawn by volgraph itself (no Graphviz): the
        /// viewer's picture, passes in rows by dependency, history edges dashed in a side lane.
        #[arg(long)]
        svg: bool,
    },
    /// List every pass kind a graph can use (summary, paper section), or show one kind's ports,
    /// parameters (type, default, range, doc), features and shaders.
    Passes {
        /// The kind to show in full.
        kind: Option<String>,
        /// Also list the WGSL-only kinds this graph file declares (its `kinds:` block).
        #[arg(long)]
        graph: Option<PathBuf>,
    },
    /// Render a graph to an image (PNG: 8-bit sRGB; EXR: 32-bit float linear).
    Render(crate::render::RenderArgs),
    /// Show a graph live in a window, hot-reloading the graph, its shaders and its transfer
    /// function; an overlay shows per-pass GPU time, the plan and every parameter.
    View(crate::view::ViewArgs),
    /// What a volume holds: dimensions, voxel type, spacing, value range, histogram percentiles,
    /// its background (air or the scanner's noise floor) and where the fitted default transfer
    /// function starts.
    Info {
        /// The volume: a file (.raw named NAME_XxYxZ_TYPE.raw, .nrrd, .nhdr, .mhd, .mha, .nii,
        /// .nii.gz), a folder of DICOM slices (its series are listed), or DICOM slice files. Or
        /// several as NAME=PATH (`ct=ct.nii.gz pet=pet.nii.gz`): each described, then whether
        /// they share a grid and frame and where their boxes overlap.
        #[arg(required = true, num_args = 1..)]
        volume: Vec<PathBuf>,
        /// The volume is a label map (a segmentation): list its labels — value, name, voxels and
        /// volume in mL (a default palette names them without --label-table).
        #[arg(long)]
        labels: bool,
        /// The label map's names and colours: an ITK-SNAP label description file, a 3D Slicer
        /// colour table (.ctbl, .txt) or segmentation (.seg.nrrd, whose header names its
        /// segments, or a DICOM SEG; either given as the volume names its own). Implies --labels.
        #[arg(long, value_name = "TABLE")]
        label_table: Option<PathBuf>,
        /// How to read a headerless raw volume.
        #[command(flatten)]
        raw: RawArgs,
    },
    /// Write a volume as an OME-Zarr pyramid (NGFF 0.5, zstd): levels halving to 64³, every
    /// chunk's value range beside it, with a progress bar. The input is anything --volume
    /// takes (a file, a DICOM folder, a dataset or a generated volume by name: `vessels512`).
    Convert(crate::convert_cmd::ConvertArgs),
    /// List the graphs built into the binary (name, paper, description): every one can be given
    /// by name where a graph file is asked for (`volgraph render klein_2005/leap_iso -o x.png`).
    /// `--export NAME [DIR]` writes one out to edit (DIR/NAME.ron, e.g. ./modern/fastest.ron).
    Graphs {
        /// Write this built-in graph to DIR/NAME.ron (never over an existing file).
        #[arg(long, value_name = "NAME")]
        export: Option<String>,
        /// The folder --export writes into (created when missing).
        #[arg(requires = "export", default_value = ".")]
        dir: PathBuf,
    },
    /// List the scenes built into the binary (name, graph, effects): `--scene NAME` renders one
    /// from any folder; `--export NAME [DIR]` writes one out to edit.
    Scenes {
        /// Write this built-in scene to DIR/NAME.ron (never over an existing file).
        #[arg(long, value_name = "NAME")]
        export: Option<String>,
        /// The folder --export writes into (created when missing).
        #[arg(requires = "export", default_value = ".")]
        dir: PathBuf,
    },
    /// Write values into a graph file at their place (only the values' text changes; comments,
    /// order and layout stay): `volgraph set graph.ron march.step_voxels=0.25 input.threshold=0.99`.
    /// The edited graph is compiled first; a bad value or unknown name leaves the file untouched.
    Set {
        /// The graph file (RON).
        graph: PathBuf,
        /// PASS.PARAM=VALUE or input.NAME=VALUE (RON values: 0.25, true, "feature.shading").
        #[arg(required = true, num_args = 1..)]
        assignments: Vec<String>,
    },
    /// Times sort-last compositing alone under mpirun (synthetic rank images); what
    /// `volgraph bench distributed` runs. Rank 0 prints one JSON line.
    #[command(hide = true)]
    CompositeBench(crate::distributed::bench::CompositeBenchArgs),
}

/// How to read the volume: a headerless `.raw` whose name does not say (or to override the
/// name), the series of a DICOM folder, the frame of a 4D NIfTI file.
#[derive(clap::Args, Debug, Default, Clone)]
pub struct RawArgs {
    /// The DICOM series to read from a folder holding several: its number in the listing
    /// (`volgraph info DIR`), its SeriesInstanceUID or its SeriesDescription.
    #[arg(long)]
    pub series: Option<String>,
    /// The volume to read from a 4D NIfTI file (0-based).
    #[arg(long)]
    pub frame: Option<u64>,
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

fn parse_scalar(text: &str) -> Result<(String, f64), String> {
    let (name, value) = text.split_once('=').ok_or_else(|| format!("\"{text}\": expected NAME=VALUE"))?;
    let value: f64 = value.parse().map_err(|_| format!("\"{text}\": \"{value}\" is not a number"))?;
    Ok((name.to_string(), value))
}

/// What went wrong, split so graph diagnostics can be drawn with their source excerpts.
#[derive(Debug)]
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

/// The text of an error as the CLI prints it (graph diagnostics as `file:line:col: message`).
pub fn error_text(e: &CliError) -> String {
    match e {
        CliError::Graph(diagnostics) => diagnostics.to_string(),
        CliError::Other(e) => format!("{e:#}"),
    }
}

/// Compile options from `--size`, `--features` and `--scalar`.
pub fn compile_options(size: &str, features: &[String], scalars: &[(String, f64)]) -> anyhow::Result<CompileOptions> {
    let (w, h) = inputs::parse_size(size)?;
    let mut o = CompileOptions::new(w, h).with_features(features.iter().filter(|f| !f.is_empty()).cloned());
    o.scalars = scalars.iter().cloned().collect::<BTreeMap<_, _>>();
    Ok(o)
}

/// How a graph path is named in messages.
pub fn display_name(path: &Path) -> String {
    path.display().to_string()
}

/// Every `--features` and `--scalar` name must be one the graph reads: a typo would otherwise
/// render without the effect and exit 0.
pub fn check_user_names(plan: &volgraph_core::Plan, options: &CompileOptions) -> Result<(), CliError> {
    use volgraph_core::suggest::{comma_list, guess_then};
    let mut problems = Vec::new();
    let known: Vec<&str> = plan.known_features.iter().map(String::as_str).collect();
    for f in options.features.iter().filter(|f| !plan.known_features.contains(*f)) {
        let help = format!("its features are: {}", comma_list(&known));
        problems.push(format!(
            "--features \"{f}\": graph \"{}\" has no such feature; {}",
            plan.name,
            guess_then(f, known.iter().copied(), "", help)
        ));
    }
    let known: Vec<&str> = plan.known_scalars.iter().map(String::as_str).collect();
    for name in options.scalars.keys().filter(|n| !plan.known_scalars.contains(*n)) {
        let help = format!("its scalars are: {}", comma_list(&known));
        problems.push(format!(
            "--scalar \"{name}\": graph \"{}\" reads no such scalar; {}",
            plan.name,
            guess_then(name, known.iter().copied(), "", help)
        ));
    }
    if problems.is_empty() { Ok(()) } else { Err(CliError::Other(anyhow!(problems.join("\nerror: ")))) }
}

/// The plan's warnings (a repeat count capped by its max, ...) as stderr lines.
pub fn warning_lines(plan: &volgraph_core::Plan) -> Vec<String> {
    plan.warnings
        .items
        .iter()
        .map(|d| {
            let mut line = format!("warning: {}: {}", plan.warnings.position(d), d.message);
            if let Some(help) = &d.help {
                line.push_str(&format!("\n  help: {help}"));
            }
            line
        })
        .collect()
}

/// A `plan` or `render` command line with every input read and checked, no GPU touched.
pub enum Checked {
    /// `plan`: the text to print and the notes for stderr.
    Plan {
        /// The plan text.
        text: String,
        /// Warnings for stderr.
        notes: Vec<String>,
    },
    /// `render`: ready to open the GPU.
    Render(Box<crate::render::Prepared>),
}

/// Reads and checks the inputs of a `plan` or `render` command line: what a user's typo can
/// break, without the GPU (the CLI fuzzer runs this). Other commands are not checked here.
pub fn check(cli: Cli) -> Result<Checked, CliError> {
    match cli.command {
        Command::Plan { graph, size, features, scalars, dot, svg } => {
            let source = inputs::read_graph(&graph)?;
            let options = compile_options(&size, &features, &scalars)?;
            let plan = compile(&display_name(&graph), &source, &crate::program::registry(), &options)
                .map_err(CliError::Graph)?;
            check_user_names(&plan, &options)?;
            // Shader bindings against ports, without a GPU: what node creation would reject.
            let (sources, _) = crate::shader_dir::sources_for(&graph, None);
            let problems = volgraph_core::check_plan_bindings(&plan, &crate::program::registry(), &sources);
            if !problems.is_empty() {
                return Err(CliError::Graph(volgraph_core::Diagnostics {
                    file: display_name(&graph),
                    text: std::sync::Arc::from(source.as_str()),
                    items: problems,
                }));
            }
            let text = match (dot, svg) {
                (true, _) => plan.to_dot(),
                (_, true) => crate::plan_svg::plan_svg(&plan),
                _ => plan.to_text(),
            };
            Ok(Checked::Plan { text, notes: warning_lines(&plan) })
        }
        Command::Render(args) => Ok(Checked::Render(Box::new(crate::render::prepare(args)?))),
        Command::View(_)
        | Command::Passes { .. }
        | Command::Graphs { .. }
        | Command::Scenes { .. }
        | Command::Info { .. }
        | Command::Convert(_)
        | Command::Set { .. }
        | Command::CompositeBench(_) => {
            Err(CliError::Other(anyhow!("only plan and render are checked ahead of running")))
        }
    }
}

/// `graphs --export` / `scenes --export`: writes the built-in out and says where.
fn export_builtin(kind: crate::builtin_scenes::Builtin, name: &str, dir: &Path) -> Result<(), CliError> {
    let path = crate::builtin_scenes::export(kind, name, dir)?;
    crate::stdout::println_escaped!("wrote {}", path.display());
    Ok(())
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Render(args) if args.distributed => crate::distributed::launch(),
        Command::CompositeBench(args) => crate::distributed::bench::launch(&args),
        Command::Plan { .. } | Command::Render(_) => match check(cli)? {
            Checked::Plan { text, notes } => {
                for note in notes {
                    crate::stdout::eprintln_escaped!("{note}");
                }
                crate::stdout::write_stdout(&text)?;
                Ok(())
            }
            Checked::Render(prepared) => {
                for note in &prepared.notes {
                    crate::stdout::eprintln_escaped!("{note}");
                }
                crate::render::execute(*prepared)
            }
        },
        Command::View(args) => crate::view::run(args),
        Command::Set { graph, assignments } => {
            crate::stdout::write_stdout(&crate::set_cmd::run(&graph, &assignments)?)?;
            Ok(())
        }
        Command::Graphs { export: None, .. } => {
            crate::stdout::write_stdout(&crate::builtin_graphs::listing())?;
            Ok(())
        }
        Command::Scenes { export: None, .. } => {
            crate::stdout::write_stdout(&crate::builtin_scenes::listing())?;
            Ok(())
        }
        Command::Graphs { export: Some(name), dir } => {
            export_builtin(crate::builtin_scenes::Builtin::Graph, &name, &dir)
        }
        Command::Scenes { export: Some(name), dir } => {
            export_builtin(crate::builtin_scenes::Builtin::Scene, &name, &dir)
        }
        Command::Info { volume, labels, label_table, raw } => {
            let labels = (labels || label_table.is_some()).then_some(crate::info_cmd::Labels { table: label_table });
            crate::stdout::write_stdout(&crate::info_cmd::run(&volume, &inputs::raw_options(&raw)?, labels.as_ref())?)?;
            Ok(())
        }
        Command::Convert(args) => {
            crate::stdout::write_stdout(&crate::convert_cmd::run(&args)?)?;
            Ok(())
        }
        Command::Passes { kind, graph } => {
            let registry = match &graph {
                Some(path) => crate::passes_cmd::with_graph_kinds(&crate::program::registry(), path)?,
                None => crate::program::registry(),
            };
            let text = crate::passes_cmd::describe(&registry, kind.as_deref())?;
            crate::stdout::write_stdout(&text)?;
            Ok(())
        }
    }
}
