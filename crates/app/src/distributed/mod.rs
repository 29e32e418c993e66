//! `volgraph render --distributed`: sort-last rendering over MPI (`docs/scaling.md`).
//!
//! Rank 0's command line is the job (it is broadcast, so ranks cannot disagree). Then:
//! 1. every rank reads the file's header (an OME-Zarr store's finest level: its boxes are read
//!    chunk by chunk, `volgraph_zarr::StoreBoxes`), and the file is surveyed once in total, a z-slab per
//!    rank ([`survey`]): value range, a preview for the default transfer function, per-brick
//!    histograms;
//! 2. every rank builds the same kd-tree over the bricks, balanced by voxels visible under the
//!    transfer function (`volgraph_accel::kd_split`), and reads only the part of its box the
//!    view needs (the bounding box of its bricks that can show anything, [`need`]) plus an
//!    apron of [`APRON`] voxels ([`APRON_TRILINEAR`] without tricubic filtering);
//! 3. every rank renders its box with the same graph and camera into premultiplied RGBA f32 —
//!    rays meet the whole volume's box, so samples lie on the single-process step grid, and
//!    each rank takes only the samples in its own box (`Runtime::set_volume_window`);
//! 4. the images are composited in the kd-tree's visibility order for the camera, by radix-k
//!    or direct-send (`volgraph_composite`), and rank 0 writes the image.
//!
//! After every step that can fail on one rank, the ranks agree on the outcome, so an error on
//! one rank ends every rank with that rank's message and a non-zero exit, never a hang.

pub mod bench;
pub mod need;
pub mod survey;

use std::sync::Arc;
use std::time::Instant;

use anyhow::anyhow;
use glam::{DVec3, DVec4, UVec3};
use volgraph_accel::kd_split::{KdTree, VoxelBox, radix_factors};
use volgraph_accel::load::VolumeHeader;
use volgraph_composite::{CompositeStats, Compositor, Exchange, ExchangeError, Layer, agree};
use volgraph_core::runtime::{CameraData, Gpu, Runtime, ShaderLibrary, VolumeDesc, VolumeWindow, scene_values_of};
use volgraph_core::{TargetFormat, compile};

use crate::cli::{CliError, compile_options, display_name};
use crate::image_out::{self, ImageKind};
use crate::inputs;
use crate::render::RenderArgs;

/// Voxels each rank holds beyond its box on every side when a march filters tricubically:
/// trilinear filtering reaches 1, central differences for shading 1 more, the tricubic B-spline
/// 2 — 4 covers them all.
pub const APRON: u32 = 4;
/// The apron of a graph without tricubic filtering: trilinear 1, central differences 1.
pub const APRON_TRILINEAR: u32 = 2;

/// The apron `plan`'s marches need ([`APRON`] or [`APRON_TRILINEAR`]): at a fifth of a 100-voxel
/// box's bytes, the apron is most of what a rank holds beyond what the view needs.
fn apron_of(plan: &volgraph_core::Plan) -> u32 {
    let tricubic = plan.steps.iter().any(|s| s.params.declares("tricubic") && s.params.boolean("tricubic"));
    if tricubic { APRON } else { APRON_TRILINEAR }
}

/// How ranks composite their images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
pub enum CompositeAlgorithm {
    /// Every rank owns a tile and receives every other rank's pixels in it (one round).
    DirectSend,
    /// Rounds of k-way exchanges (Peterka et al. 2009), k per round chosen as IceT does.
    RadixK,
}

/// What one rank did, for its line and the benchmarks.
#[derive(Clone, Debug, Default)]
pub struct RankReport {
    /// This rank.
    pub rank: usize,
    /// The number of ranks.
    pub ranks: usize,
    /// Bytes of voxels this rank holds (its box and apron).
    pub voxel_bytes: u64,
    /// Bytes of the bricks the view needs, over all ranks (`need::Needed::bytes`).
    pub needed_bytes: u64,
    /// The box it owns.
    pub own: Option<VoxelBox>,
    /// The box it holds: its own and the apron.
    pub held: Option<VoxelBox>,
    /// The last frame's render and readback, ms.
    pub render_ms: f64,
    /// The last frame's compositing and gather, ms.
    pub composite_ms: f64,
    /// What compositing sent.
    pub composite: CompositeStats,
}

impl RankReport {
    /// `rank R of N holds B bytes of voxels (P % of the V bytes the view needs), rendered in X
    /// ms, composited in Y ms`.
    /// When the view needs nothing (a transfer function that shows nothing):
    /// `… bytes of voxels (the view needs none), …`.
    pub fn line(&self) -> String {
        let share = match self.needed_bytes {
            0 => "the view needs none".to_string(),
            needed => {
                format!("{:.1} % of the {needed} bytes the view needs", 100.0 * self.voxel_bytes as f64 / needed as f64)
            }
        };
        format!(
            "rank {} of {} holds {} bytes of voxels ({share}), rendered in {:.2} ms, composited in {:.2} ms",
            self.rank, self.ranks, self.voxel_bytes, self.render_ms, self.composite_ms
        )
    }
}

/// Runs `volgraph render --distributed` under MPI: initializes it, takes rank 0's command
/// line, renders and composites. Each rank prints its line; rank 0 writes the image.
#[cfg(feature = "mpi")]
pub fn launch() -> Result<(), CliError> {
    use clap::Parser;
    let mut ex = volgraph_composite::mpi_exchange::MpiExchange::initialize()
        .ok_or_else(|| CliError::Other(anyhow!("internal: MPI was initialized twice")))?;
    let argv: Vec<String> = std::env::args().collect();
    let job = volgraph_composite::broadcast_from_root(&mut ex, argv.join("\0").into_bytes()).map_err(other)?;
    let argv: Vec<String> = String::from_utf8_lossy(&job).split('\0').map(str::to_string).collect();
    let parsed = crate::cli::Cli::try_parse_from(&argv).map_err(|e| e.to_string());
    let args = agree(&mut ex, parsed)
        .map_err(other)?
        .into_render_args()
        .ok_or_else(|| CliError::Other(anyhow!("internal: rank 0's command is not render")))?;
    let outcome = run(&mut ex, &args);
    // One write of the whole line: lines of ranks sharing a stderr pipe never interleave. An
    // error the ranks agreed on is the same on every rank (naming the rank it came from unless
    // every rank failed alike): rank 0 prints it once. Any other error (compositing's exchanges)
    // is this rank's own: it prints it, naming itself.
    use std::io::Write as _;
    let text = |e: &CliError| volgraph_core::terminal::escape_controls(&crate::cli::error_text(e)).into_owned();
    let line = match &outcome {
        Ok(report) => format!("{}\n", report.line()),
        Err(e) if is_agreed(e) => match ex.rank() {
            0 => format!("error: {}\n", text(e)),
            _ => String::new(),
        },
        Err(e) => format!("error: rank {}: {}\n", ex.rank(), text(e)),
    };
    let _ = std::io::stderr().write_all(line.as_bytes());
    if outcome.is_err() {
        // Wait until rank 0 has printed the error, since mpirun ends the job as soon as one rank
        // exits non-zero; then leave MPI and exit without printing it again.
        let _ = agree(&mut ex, Ok(()));
        drop(ex);
        std::process::exit(1);
    }
    Ok(())
}

/// Without MPI: says how to get a build with it.
#[cfg(not(feature = "mpi"))]
pub fn launch() -> Result<(), CliError> {
    Err(CliError::Other(anyhow!(
        "--distributed: this volgraph was built without MPI; build it with `cargo build --release -p volgraph-app \
         --features mpi` (needs openmpi-bin, libopenmpi-dev and libclang-dev) and run it under `mpirun -n N`"
    )))
}

fn other(e: ExchangeError) -> CliError {
    CliError::Other(anyhow!("{e}"))
}

/// Agrees on a step's outcome: every rank gets the first failing rank's message (or, when every
/// rank failed alike, the message naming no rank), kept as the [`ExchangeError`] it is, so that
/// [`is_agreed`] knows it.
fn step<E: Exchange + ?Sized, T>(ex: &mut E, outcome: anyhow::Result<T>) -> Result<T, CliError> {
    agree(ex, outcome.map_err(|e| format!("{e:#}"))).map_err(|e| match e {
        ExchangeError::Remote { .. } | ExchangeError::Everywhere { .. } => CliError::Other(anyhow::Error::new(e)),
        transport => other(transport),
    })
}

/// True for an error every rank holds alike (a [`step`]'s): one rank prints it for all.
#[cfg(feature = "mpi")]
fn is_agreed(e: &CliError) -> bool {
    matches!(e, CliError::Other(e) if e.downcast_ref::<ExchangeError>().is_some())
}

/// Renders the job `args` as rank `ex.rank()` of `ex.size()`: the whole of `--distributed`
/// over any transport (MPI, or threads in a test).
pub fn run<E: Exchange + ?Sized>(ex: &mut E, args: &RenderArgs) -> Result<RankReport, CliError> {
    let (rank, ranks) = (ex.rank(), ex.size());
    let job = step(ex, Job::read(args))?;
    let factors = radix_factors(ranks, args.radix_k.max(2) as usize);
    let brick = step(ex, survey::brick_for(job.header.dims, &factors).map_err(|e| anyhow!("{e}")))?;
    let surveyed = survey::survey(ex, &job.header, brick).map_err(|e| anyhow!(e));
    let survey = step(ex, surveyed)?;
    let (lut, plan) = step(ex, job.compile(&survey))?;
    if rank == 0
        && let Some(threshold) = early_termination_below_one(&plan)
    {
        crate::stdout::eprintln_escaped!(
            "note: this graph stops rays at opacity {threshold}; each rank stops only its own part of a ray, and the \
             ranks behind still add their light, so the image may differ from the single-process one by up to \
             {:.3} where rays saturate (it is nearer the converged image); a threshold of 1 makes them equal",
            1.0 - threshold
        );
    }
    // The tree balances the bytes the view needs, and each rank holds and marches only the part
    // of its box the view needs (`need`).
    let needed = need::Needed::of(&survey, job.header.dims, &need::shown_bins(&plan, &lut));
    let tree = step(ex, KdTree::balanced(&needed.weights(), &factors).map_err(|e| anyhow!("{e}")))?;
    let own = needed.tight(tree.boxes[rank]);
    let held = own.with_apron(apron_of(&plan), job.header.dims);
    let volume = step(ex, job.header.read_box(held, survey.value_range).map_err(|e| anyhow!("{e}")))?;
    let mut report = RankReport {
        rank,
        ranks,
        voxel_bytes: volume.voxel_count() as u64 * job.header.dtype.size_bytes() as u64,
        needed_bytes: needed.bytes(job.header.dtype.size_bytes() as u64),
        own: Some(own),
        held: Some(held),
        ..Default::default()
    };
    let window = VolumeWindow::new(job.header.dims, job.header.spacing, held.lo, own.lo, own.hi);
    let background = present_background(&plan);
    let mut runtime = step(ex, job.runtime(&volume, &lut, window, plan))?;
    let viewport = job.viewport;
    let whole = VolumeDesc::of_window(
        job.header.dims,
        &VolumeWindow::new(job.header.dims, job.header.spacing, UVec3::ZERO, UVec3::ZERO, job.header.dims),
    );
    let mut compositor = Compositor::new();
    let mut last = None;
    for frame in 0..job.frames {
        let orbit = job.camera.at(frame);
        let camera = CameraData::from_orbit(&orbit, viewport);
        let started = Instant::now();
        let rendered = runtime.render(camera).and_then(|_| runtime.read_output("image")).map_err(|e| anyhow!(e));
        let image = step(ex, rendered)?;
        report.render_ms = started.elapsed().as_secs_f64() * 1e3;
        let mut layer = Layer {
            width: image.width,
            height: image.height,
            pixels: image.data.chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]).collect(),
        };
        let eye_voxels = (camera.eye / (2.0 * whole.half_extent) + DVec3::splat(0.5)) * job.header.dims.as_dvec3();
        let rows = screen_rows(&camera, viewport, &whole, job.header.dims, &own);
        let started = Instant::now();
        let stats = match job.algorithm {
            CompositeAlgorithm::DirectSend => {
                compositor.direct_send(ex, &mut layer, rows, &tree.visibility_order(eye_voxels))
            }
            CompositeAlgorithm::RadixK => {
                let rounds: Vec<usize> = tree.factors.iter().rev().copied().collect();
                let orders: Vec<Vec<usize>> =
                    (0..rounds.len()).map(|round| tree.children_order(rank, round, eye_voxels)).collect();
                compositor.radix_k(ex, &mut layer, &rounds, &orders)
            }
        }
        .map_err(other)?;
        let whole = compositor.gather(ex, &mut layer).map_err(other)?;
        report.composite_ms = started.elapsed().as_secs_f64() * 1e3;
        report.composite = stats;
        last = whole.then_some(layer);
    }
    let written = match (&last, rank) {
        (Some(image), 0) => job.write(image, background),
        _ => Ok(()),
    };
    step(ex, written)?;
    Ok(report)
}

/// The `present` pass's background grey of `plan` (0 when it has none): what PNG output shows
/// behind the composited colour, as the single render's display does.
fn present_background(plan: &volgraph_core::Plan) -> f32 {
    plan.steps
        .iter()
        .find(|s| s.kind == "present" && s.params.declares("background"))
        .map_or(0.0, |s| s.params.float("background")) as f32
}

/// The lowest early-termination threshold of `plan`'s passes below 1 − 1/255 (where one rank's
/// rays stop before the single-process ones would), if any.
fn early_termination_below_one(plan: &volgraph_core::Plan) -> Option<f64> {
    plan.steps
        .iter()
        .filter(|s| s.params.declares("threshold"))
        .map(|s| s.params.float("threshold"))
        .filter(|t| *t < 1.0 - 1.0 / 255.0)
        .reduce(f64::min)
}

/// The image rows the box `own` may cover for `camera`: its corners projected, or every row
/// when a corner lies behind the near plane (the eye inside or beside the box).
pub fn screen_rows(
    camera: &CameraData,
    viewport: (u32, u32),
    whole: &VolumeDesc,
    dims: UVec3,
    own: &VoxelBox,
) -> std::ops::Range<u32> {
    let h = viewport.1;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..8 {
        let corner = UVec3::new(
            if i & 1 == 0 { own.lo.x } else { own.hi.x },
            if i & 2 == 0 { own.lo.y } else { own.hi.y },
            if i & 4 == 0 { own.lo.z } else { own.hi.z },
        );
        let world = (corner.as_dvec3() / dims.as_dvec3() - DVec3::splat(0.5)) * 2.0 * whole.half_extent;
        let clip = camera.clip_from_world * DVec4::new(world.x, world.y, world.z, 1.0);
        if clip.w <= camera.near * 0.5 {
            return 0..h;
        }
        let y = (1.0 - clip.y / clip.w) * 0.5 * h as f64;
        lo = lo.min(y);
        hi = hi.max(y);
    }
    let lo = (lo.floor() - 1.0).clamp(0.0, h as f64) as u32;
    let hi = (hi.ceil() + 1.0).clamp(0.0, h as f64) as u32;
    lo..hi.max(lo)
}

/// The job every rank runs: what `render` reads, without the voxels.
struct Job {
    header: VolumeHeader,
    graph: std::path::PathBuf,
    shaders: Option<std::path::PathBuf>,
    source: String,
    options: volgraph_core::CompileOptions,
    tf: Option<std::path::PathBuf>,
    tf_map: Option<String>,
    camera: crate::scene::CameraSpec,
    viewport: (u32, u32),
    frames: u32,
    kind: ImageKind,
    out: std::path::PathBuf,
    algorithm: CompositeAlgorithm,
    /// `--crop` and `--clip`: each rank takes the samples its own box and the cuts keep.
    cuts: volgraph_accel::cuts::Cuts,
    /// `--light` (or the scene's): every rank shades with it.
    lights: volgraph_accel::light::Lights,
}

impl Job {
    fn read(args: &RenderArgs) -> anyhow::Result<Job> {
        let kind = ImageKind::from_path("-o", &args.out)?;
        let resolved =
            args.inputs.resolve("volgraph render GRAPH --distributed --volume FILE.raw -o out.png", "512x512")?;
        if resolved.scene.is_some() {
            return Err(anyhow!(
                "--distributed takes its inputs from flags (--volume, --tf, --camera); --scene is not supported yet"
            ));
        }
        let path = match args.inputs.volume.as_slice() {
            [path] => path,
            [] => {
                return Err(anyhow!(
                    "--distributed needs --volume: a .raw, .nrrd, .nhdr, .mha or .mhd file or a DICOM folder; each rank reads its box of it"
                ));
            }
            _ => return Err(anyhow!("--distributed reads one volume file or DICOM folder; give one --volume")),
        };
        let mut raw = inputs::raw_options(&args.inputs.raw)?;
        // A dataset's name reads its file, with the manifest's spacing unless --spacing is given.
        let dataset_file;
        let path = match inputs::volume_name(path) {
            None => path,
            Some(inputs::VolumeName::Generated(name)) => {
                return Err(anyhow!(
                    "--distributed: each rank reads its box of a volume file, and {name} is generated; give a file"
                ));
            }
            Some(inputs::VolumeName::Dataset(name)) => {
                let (file, spacing) =
                    volgraph_accel::data_dir::dataset_file(&name).map_err(|e| anyhow!("--volume {name}: {e}"))?;
                raw.raw.spacing = raw.raw.spacing.or(spacing);
                dataset_file = file;
                &dataset_file
            }
        };
        // An OME-Zarr store: each rank reads its box of the finest level, chunk by chunk.
        let header = if volgraph_zarr::is_zarr(path) {
            crate::zarr_input::store_header(path, &raw)?
        } else {
            VolumeHeader::read(path, &raw).map_err(|e| anyhow!("{e}"))?
        };
        let source = inputs::read_graph(&resolved.graph)?;
        let mut options = compile_options(&resolved.size, &args.inputs.features, &[])?;
        options.features.extend(volgraph_core::cut_effects::features_of(&resolved.cuts));
        Ok(Job {
            header,
            graph: resolved.graph,
            shaders: args.inputs.shaders.clone(),
            source,
            viewport: options.viewport,
            options,
            tf: args.inputs.single_tf("volgraph render --distributed")?,
            tf_map: args.inputs.tf_map.clone(),
            camera: resolved.camera,
            frames: args.frames.unwrap_or(1),
            kind,
            out: args.out.clone(),
            algorithm: args.composite,
            cuts: resolved.cuts,
            lights: resolved.lights,
        })
    }

    /// The LUT (fitted to the whole volume's histogram when no --tf is given) and the plan,
    /// compiled with the whole volume's scene values.
    fn compile(&self, survey: &survey::Survey) -> anyhow::Result<(Vec<[f32; 4]>, volgraph_core::Plan)> {
        // Fitted to the whole file's histogram, which every rank holds: every rank gets the TF
        // one process would fit (the preview alone would differ, and knows no units).
        let (tf, _) = inputs::transfer_function_fitted(
            self.tf.as_ref(),
            self.tf_map.as_deref(),
            &survey.preview,
            &survey.values,
            false,
        )?;
        let lut = tf.to_lut_for(&survey.preview, inputs::LUT_SIZE);
        let mut options = self.options.clone();
        let whole =
            VolumeWindow::new(self.header.dims, self.header.spacing, UVec3::ZERO, UVec3::ZERO, self.header.dims);
        options.scene = scene_values_of(&VolumeDesc::of_window(self.header.dims, &whole));
        options.scene.extend(inputs::data_scene_values_of(&survey.values));
        let registry = crate::program::registry();
        let plan = compile(&display_name(&self.graph), &self.source, &registry, &options)
            .map_err(|e| anyhow!("{}", crate::cli::error_text(&CliError::Graph(e))))?;
        let unsplittable: Vec<String> = plan
            .steps
            .iter()
            .filter(|s| !registry.get(&s.kind).is_some_and(|p| p.honours_volume_window()))
            .map(|s| format!("\"{}\" ({})", s.pass_id, s.kind))
            .collect();
        if !unsplittable.is_empty() {
            return Err(anyhow!(
                "graph \"{}\": --distributed cannot split pass {} between ranks: only passes that take the samples of \
                 a ray in a rank's own box composite with the over operator (the raycasters: e.g. basic/fragment_raycast, \
                 modern/fastest, kruger_westermann_2003/rc_b, ruijters_vilanova_2006/bricks_octree_ert); render this \
                 graph without --distributed",
                plan.name,
                unsplittable.join(", ")
            ));
        }
        let image = plan.outputs.get("image").map(|&r| &plan.resources[r].desc);
        let float = matches!(
            image,
            Some(volgraph_core::plan::ResourceDesc::Target {
                format: TargetFormat::Rgba32Float | TargetFormat::Rgba16Float,
                ..
            })
        );
        if !float {
            return Err(anyhow!(
                "graph \"{}\": --distributed composites the graph's output \"image\", which must be a premultiplied \
                 Rgba32Float or Rgba16Float target (the raycasters' colour); this graph has none",
                plan.name
            ));
        }
        Ok((lut, plan))
    }

    fn runtime(
        &self,
        volume: &volgraph_accel::volume::Volume,
        lut: &[[f32; 4]],
        window: VolumeWindow,
        plan: volgraph_core::Plan,
    ) -> anyhow::Result<Runtime> {
        let gpu = Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
        let (sources, _) = crate::shader_dir::sources_for(&self.graph, self.shaders.as_deref());
        let mut runtime = Runtime::new(gpu, ShaderLibrary::new(sources));
        runtime.set_volume_window(Some(window));
        runtime.set_cuts(self.cuts);
        runtime.set_lights(self.lights);
        runtime.bind_scene(&plan.inputs, volume, lut).map_err(|e| anyhow!(e))?;
        runtime.apply(plan, &crate::program::registry()).map_err(|e| anyhow!(e))?;
        Ok(runtime)
    }

    /// Rank 0's output: EXR holds the composited premultiplied colour; PNG shows it over the
    /// graph's `present` background in sRGB, as the single-process display output does.
    fn write(&self, image: &Layer, background: f32) -> anyhow::Result<()> {
        let data: Vec<f32> = match self.kind {
            ImageKind::Exr => image.pixels.iter().flatten().copied().collect(),
            ImageKind::Png => image
                .pixels
                .iter()
                .flat_map(|p| {
                    let t = 1.0 - p[3];
                    [p[0] + t * background, p[1] + t * background, p[2] + t * background, 1.0]
                })
                .collect(),
        };
        let out = volgraph_core::runtime::Image { width: image.width, height: image.height, channels: 4, data };
        match self.kind {
            ImageKind::Exr => image_out::write_exr(&self.out, &out, false),
            ImageKind::Png => image_out::write_png(&self.out, &out, false),
        }
    }
}
