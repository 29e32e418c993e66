//! The `bench` and `sweep` subcommands, added to a volgraph program's command line.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{FromArgMatches as _, Subcommand};
use volgraph_app::cli::CliError;

// What `volgraph-bench` adds (no doc comment: clap would make it the program's about line).
#[derive(Subcommand, Debug)]
#[allow(clippy::large_enum_variant, reason = "parsed once per process; boxing would only obscure the clap derive")]
enum BenchCli {
    /// What accuracy costs in time: every knob (step, threshold, precision, block size, shading,
    /// pre-integration, jitter, filter) swept on several datasets, error against the converged
    /// f64 reference beside ms per frame; a table, JSON rows and one plot per knob.
    Sweep(crate::sweep::SweepArgs),
    /// Measure: graphs (speed, samples, accuracy), fetch (the device's sampling ceiling), live
    /// (reload latency, soak), compile, accel (CPU acceleration structures), load (DICOM vs raw).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
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
    /// kw2003-table1, thesis-tables, peer, …); speed-ups vs a baseline, samples counted on the
    /// GPU as a fraction of the fetch ceiling, accuracy sweeps.
    Graphs(crate::graphs::GraphsArgs),
    /// The fetch ceiling: trilinear samples per second of a pass that only samples the volume
    /// along the raycaster's rays (no classification, no compositing).
    Fetch(crate::fetch::FetchArgs),
    /// The live runtime: reload latency (parameter, graph and shader edits), frames in flight vs
    /// blocking, and a soak of frames and reloads with memory at start and end.
    Live(crate::live::LiveArgs),
    /// Loading a DICOM series (512 slices of 512² int16 by default) against reading the same
    /// voxels as one raw file.
    Load(crate::load::LoadArgs),
    /// Sort-last rendering under mpirun: compositing alone (direct-send vs radix-k, 256² …
    /// 2048², beside the memory-copy bound) and whole frames with 1, 2, 4 ranks.
    Distributed(crate::distributed::DistributedArgs),
    /// Light that scatters: the path tracer's RMSE against a converged image vs seconds of
    /// accumulation, with one or block majorants and ratio- or delta-tracked shadow rays, and the
    /// light-volume shadows effect beside it (the engine at 256² by default).
    Cinematic(crate::cinematic::CinematicArgs),
    /// Crop boxes and clip planes: ms/frame of crops to an eighth and a half and of a clip
    /// plane beside the whole volume (the engine with modern/fastest by default).
    Cuts(crate::cuts::CutsArgs),
    /// Several volumes in one march: a CT with a 117-label map (tinted, inside) against the CT
    /// alone, a label's visibility toggled → frame, smooth vs nearest label boundaries at 4× zoom.
    Multi(crate::multi::MultiArgs),
    /// Volumes beyond memory: a generated 4096³ vessel tree converted to OME-Zarr and streamed
    /// ray-guided at 800x600 (time to the first image, frames while moving, time to the full
    /// image, peak memory, bricks read), and a 512³ store streamed against in core.
    Stream(crate::stream::StreamArgs),
    /// One frame through the library API the Python package wraps (render, wait, read back):
    /// the baseline of the Python layer's cost.
    Api(crate::api::ApiArgs),
    /// The clinical viewer's slice panes: the update when the crosshair moves (512² panes) and
    /// the 3D view's frame with the panes open vs without.
    Slices(crate::slices::SlicesArgs),
    /// The viewer as a workbench: TF edit → frame on a 256³ volume at 800x600, and the frame
    /// time while the camera moves for every shipped graph.
    Workbench(crate::workbench::WorkbenchArgs),
    /// Compile time of a generated 30-pass graph; pooled vs unpooled transient memory of every
    /// built-in graph at 1920x1080.
    Compile {
        /// Write the figures as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

/// `bench` and `sweep` as [`volgraph_app::Commands`].
pub struct BenchCommands;

impl volgraph_app::Commands for BenchCommands {
    fn augment(&self, command: clap::Command) -> clap::Command {
        BenchCli::augment_subcommands(command)
    }

    fn handles(&self, name: &str) -> bool {
        BenchCli::has_subcommand(name)
    }

    fn run(&self, matches: &clap::ArgMatches) -> Result<ExitCode, CliError> {
        let cli = BenchCli::from_arg_matches(matches).unwrap_or_else(|e| e.exit());
        run(cli)?;
        Ok(ExitCode::SUCCESS)
    }
}

fn run(cli: BenchCli) -> anyhow::Result<()> {
    match cli {
        BenchCli::Sweep(args) => crate::sweep::run(&args).context("sweep").map(drop),
        BenchCli::Bench { which: BenchCommand::Accel { repeats, json } } => {
            let opts = crate::accel::AccelBenchOptions {
                data_dir: volgraph_accel::data_dir::data_dir(),
                repeats,
                json_out: json,
            };
            crate::accel::run(&opts).context("bench accel").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Compile { json } } => {
            crate::compile_time::run(json.as_deref()).context("bench compile").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Live(args) } => crate::live::run(&args).context("bench live").map(drop),
        BenchCli::Bench { which: BenchCommand::Graphs(args) } => {
            crate::graphs::run_cli(&args).context("bench graphs").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Distributed(args) } => {
            crate::distributed::run(&args).context("bench distributed")
        }
        BenchCli::Bench { which: BenchCommand::Load(args) } => crate::load::run(&args).context("bench load").map(drop),
        BenchCli::Bench { which: BenchCommand::Workbench(args) } => {
            crate::workbench::run(&args).context("bench workbench").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Api(args) } => crate::api::run(&args).context("bench api").map(drop),
        BenchCli::Bench { which: BenchCommand::Slices(args) } => {
            crate::slices::run(&args).context("bench slices").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Multi(args) } => {
            crate::multi::run(&args).context("bench multi").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Cinematic(args) } => {
            crate::cinematic::run(&args).context("bench cinematic").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Stream(args) } => {
            crate::stream::run(&args).context("bench stream").map(drop)
        }
        BenchCli::Bench { which: BenchCommand::Cuts(args) } => crate::cuts::run(&args).context("bench cuts").map(drop),
        BenchCli::Bench { which: BenchCommand::Fetch(args) } => {
            crate::fetch::run(&args).context("bench fetch").map(drop)
        }
    }
}
