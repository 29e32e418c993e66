//! `volgraph bench cinematic`: what light costs (issue "light that scatters", item 5). The
//! progressive path tracer's error against a converged image as it accumulates, against the
//! milliseconds it took — with one majorant and with block majorants, leaping over empty cubes
//! by the distance map or not, with ratio-tracked and delta-tracked shadow rays — and the
//! light-volume `shadows` effect of the raycasters beside it (its error against its own f64
//! reference). One run, one runtime, side by side.
//!
//! The converged image is the block-majorant path tracer at `--reference-spp` samples with a
//! seed no case uses; its own noise (σ/√K) is printed as the floor under every RMSE. A path
//! tracer's RMSE falls as σ/√n, so σ — estimated from the 1-sample RMSE, less the reference's
//! share — gives the samples, and with the ms a sample costs the seconds, each case needs to
//! reach `--target` (2/255 by default: the goal is ≤ 2 s on lavapipe at 256²).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::light::{Light, Lights};
use volgraph_accel::progressive_error::{ErrorTracker, rmse};
use volgraph_core::runtime::{CameraData, Gpu, Runtime, ShaderLibrary, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, compile};

use crate::graphs::measure::median;

/// `bench cinematic` arguments.
#[derive(clap::Args, Debug)]
pub struct CinematicArgs {
    /// Dataset of `$VOLGRAPH_DATA/volumes` by name.
    #[arg(long, default_value = "engine")]
    pub dataset: String,
    /// Transfer function file or preset [default: fitted to the volume, as `volgraph render`].
    #[arg(long)]
    pub tf: Option<PathBuf>,
    /// Viewport, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256")]
    pub size: String,
    /// The light: AZ,EL in degrees, or headlight.
    #[arg(long, default_value = "40,50")]
    pub light: String,
    /// Samples per pixel of the converged image.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(4..=65_536))]
    pub reference_spp: u32,
    /// Seconds of accumulation each path-traced case gets at most (it stops at the power of two
    /// of samples past this, or at a quarter of the reference's samples).
    #[arg(long, default_value_t = 20.0)]
    pub seconds: f64,
    /// The RMSE (in 1/255 of premultiplied linear RGBA) whose cost is reported.
    #[arg(long, default_value_t = 2.0)]
    pub target: f64,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the table as Markdown here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Draw RMSE against seconds of accumulation, one line per case (PNG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// A path-traced case: its name, graph and parameter overrides of the `trace` pass (values in
/// RON: `false`, `"delta"`).
struct Case {
    name: &'static str,
    graph: &'static str,
    overrides: &'static [(&'static str, &'static str)],
}

const CASES: [Case; 6] = [
    Case { name: "one majorant, ratio-tracked shadow rays", graph: "cinematic/path_traced", overrides: &[] },
    Case { name: "block majorants, ratio-tracked shadow rays", graph: "cinematic/path_traced_blocks", overrides: &[] },
    Case {
        name: "block majorants, ratio-tracked, no Russian roulette",
        graph: "cinematic/path_traced_blocks",
        overrides: &[("russian_roulette", "false")],
    },
    Case {
        name: "block majorants, delta-tracked shadow rays",
        graph: "cinematic/path_traced_blocks",
        overrides: &[("shadow_rays", "\"delta\"")],
    },
    Case {
        name: "block majorants, leaping over empty cubes (distance map)",
        graph: "cinematic/path_traced_distance",
        overrides: &[],
    },
    Case {
        name: "leaping, alpha by the path's interaction (0 or 1)",
        graph: "cinematic/path_traced_distance",
        overrides: &[("coverage", "\"interaction\"")],
    },
];

/// The seed of the converged image (no case uses it).
const REFERENCE_SEED: u64 = 0x5eed;

/// One case's curve: (samples, seconds of accumulation, RMSE) at each power of two, the RMSE of
/// the colour alone (premultiplied RGB), and the error the viewer would estimate there from the
/// images at n/2 and n alone.
struct Curve {
    name: &'static str,
    ms_per_sample: f64,
    points: Vec<(u32, f64, f64)>,
    colour_rmse: Vec<f64>,
    estimated: Vec<Option<f64>>,
}

/// Everything the cases share.
struct Bench {
    runtime: Runtime,
    registry: volgraph_core::Registry,
    volume: volgraph_accel::volume::Volume,
    lut: Vec<[f32; 4]>,
    size: String,
    camera: OrbitCamera,
}

impl Bench {
    /// Applies `graph` with `overrides` (and `seed`) to the runtime.
    fn apply(
        &mut self,
        graph: &str,
        overrides: &[(&str, &str)],
        seed: Option<u64>,
        features: &[String],
    ) -> anyhow::Result<volgraph_core::Plan> {
        let path = PathBuf::from(graph);
        let source = volgraph_app::inputs::read_graph(&path)?;
        let mut options: CompileOptions = volgraph_app::cli::compile_options(&self.size, features, &[])?;
        options.scene = scene_values_of(&VolumeDesc::of(&self.volume));
        options.scene.extend(volgraph_app::inputs::data_scene_values(&self.volume));
        for (name, value) in overrides {
            let value: ron::Value = ron::from_str(value).map_err(|e| anyhow!("override {name} = {value}: {e}"))?;
            options = options.with_param("trace", name, value);
        }
        if let Some(seed) = seed {
            options = options.with_param("trace", "seed", seed);
        }
        let plan = compile(graph, &source, &self.registry, &options).map_err(|d| anyhow!("{graph}: {d}"))?;
        self.runtime.bind_scene(&plan.inputs, &self.volume, &self.lut).map_err(|e| anyhow!(e))?;
        self.runtime.apply(plan.clone(), &self.registry).map_err(|e| anyhow!(e))?;
        Ok(plan)
    }

    /// One frame from the bench's camera: its wall-clock ms.
    fn frame(&mut self, viewport: (u32, u32)) -> anyhow::Result<f64> {
        let t0 = Instant::now();
        self.runtime.render(CameraData::from_orbit(&self.camera, viewport)).map_err(|e| anyhow!(e))?;
        Ok(t0.elapsed().as_secs_f64() * 1e3)
    }

    fn image(&mut self) -> anyhow::Result<Vec<[f64; 4]>> {
        Ok(self.runtime.read_output("image").map_err(|e| anyhow!(e))?.to_rgba_f64())
    }

    /// The converged image: `spp` samples of the block-majorant tracer.
    fn converged(&mut self, spp: u32) -> anyhow::Result<Vec<[f64; 4]>> {
        let plan = self.apply("cinematic/path_traced_blocks", &[], Some(REFERENCE_SEED), &[])?;
        for _ in 0..spp {
            self.frame(plan.viewport)?;
        }
        self.image()
    }

    /// A case accumulated to powers of two of samples within `seconds`, RMSE at each against
    /// `reference`. The first frame of a pipeline includes its compilation: a warm-up frame from
    /// another camera is rendered and thrown away (the moved camera restarts the mean).
    fn curve(&mut self, case: &Case, reference: &[[f64; 4]], seconds: f64, most: u32) -> anyhow::Result<Curve> {
        let plan = self.apply(case.graph, case.overrides, None, &[])?;
        let warm = OrbitCamera { azimuth_deg: self.camera.azimuth_deg + 90.0, ..self.camera };
        self.runtime.render(CameraData::from_orbit(&warm, plan.viewport)).map_err(|e| anyhow!(e))?;
        let (mut spent, mut times, mut points, mut estimated) = (0.0, Vec::new(), Vec::new(), Vec::new());
        let mut colour_rmse = Vec::new();
        let mut tracker = ErrorTracker::default();
        let mut next = 1;
        for n in 1..=most {
            let ms = self.frame(plan.viewport)?;
            spent += ms;
            times.push(ms);
            if n == next {
                let image = self.image()?;
                points.push((n, spent / 1e3, rmse(&image, reference)));
                colour_rmse.push(rgb_rmse(&image, reference));
                tracker.offer(0, u64::from(n), image);
                estimated.push(tracker.last(0).filter(|e| e.spp == u64::from(n)).map(|e| e.rmse));
                if spent / 1e3 > seconds {
                    break;
                }
                next *= 2;
            }
        }
        Ok(Curve { name: case.name, ms_per_sample: median(&times), points, colour_rmse, estimated })
    }
}

/// RMSE over premultiplied RGB alone (alpha left out).
fn rgb_rmse(a: &[[f64; 4]], b: &[[f64; 4]]) -> f64 {
    let sum: f64 = a.iter().zip(b).flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).powi(2))).sum();
    (sum / (a.len().max(1) * 3) as f64).sqrt()
}

/// Runs the benchmark, prints the tables and returns the JSON.
pub fn run(args: &CinematicArgs) -> anyhow::Result<serde_json::Value> {
    let loaded = volgraph_accel::data_dir::load_dataset(&args.dataset)
        .with_context(|| format!("dataset \"{}\" (set VOLGRAPH_DATA)", args.dataset))?;
    let volume = loaded.volume;
    let (tf, _) = volgraph_app::inputs::transfer_function(args.tf.as_ref(), None, &volume, false)?;
    let lut = tf.to_lut_for(&volume, volgraph_app::inputs::LUT_SIZE);
    let light = Light::parse(&args.light).map_err(|e| anyhow!("--light {}: {e}", args.light))?;
    let gpu = std::sync::Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let adapter = gpu.adapter_name.clone();
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(volgraph_passes::builtin_shaders()));
    runtime.set_light(light);
    let camera = OrbitCamera { azimuth_deg: 30.0, elevation_deg: 20.0, distance: 3.2, ..OrbitCamera::default() };
    let mut bench =
        Bench { runtime, registry: volgraph_app::program::registry(), volume, lut, size: args.size.clone(), camera };
    let k = args.reference_spp;
    eprintln!("converging the reference: {k} samples per pixel …");
    let reference = bench.converged(k)?;
    let mut curves = Vec::new();
    for case in &CASES {
        eprintln!("{} …", case.name);
        curves.push(bench.curve(case, &reference, args.seconds, (k / 4).max(1))?);
    }
    let target = args.target / 255.0;
    let mut table = format!(
        "# Cinematic light: error against time\n\n{} ({}×{}×{} voxels) at {}, light {}, measured side by side in one \
         run on {adapter}. RMSE over premultiplied linear RGBA against the block-majorant path tracer at {k} samples \
         per pixel (another seed); wall-clock ms per sample after a warm-up frame. \"estimated\" is what the viewer \
         and `render --spp` report with no reference: the RMS difference of the means at n/2 and n samples \
         (volgraph_accel::progressive_error); the measured RMSE² also holds the reference's own noise². \
         \"colour\" is the RMSE over premultiplied RGB alone.\n\n\
         | path tracer | ms/sample | samples | seconds | RMSE (/255) | colour (/255) | estimated (/255) |\n\
         |---|---:|---:|---:|---:|---:|---:|\n",
        args.dataset, bench.volume.dims.x, bench.volume.dims.y, bench.volume.dims.z, args.size, args.light
    );
    let mut json_curves = Vec::new();
    let mut summary = String::from(
        "\n| path tracer | σ of one sample (/255) | samples to reach the target | seconds to reach it |\n|---|---:|---:|---:|\n",
    );
    for c in &curves {
        for (((n, s, e), estimate), colour) in c.points.iter().zip(&c.estimated).zip(&c.colour_rmse) {
            let estimate = estimate.map_or("–".to_string(), |x| format!("{:.2}", x * 255.0));
            table.push_str(&format!(
                "| {} | {:.1} | {n} | {s:.2} | {:.2} | {:.2} | {estimate} |\n",
                c.name,
                c.ms_per_sample,
                e * 255.0,
                colour * 255.0
            ));
        }
        // RMSE² at n samples ≈ σ²/n + σ²/K (the reference's own noise): σ from the first point.
        let sigma = c.points.first().map_or(0.0, |(n, _, e)| {
            let n = f64::from(*n);
            (e * e / (1.0 / n + 1.0 / f64::from(k))).sqrt()
        });
        let needed = (sigma / target).powi(2).ceil().max(1.0);
        let seconds = needed * c.ms_per_sample / 1e3;
        summary.push_str(&format!("| {} | {:.1} | {needed:.0} | {seconds:.1} |\n", c.name, sigma * 255.0));
        json_curves.push(serde_json::json!({
            "case": c.name, "ms_per_sample": c.ms_per_sample,
            "points": c.points.iter().zip(&c.estimated).zip(&c.colour_rmse).map(|(((n, s, e), estimate), colour)| serde_json::json!({"spp": n, "seconds": s, "rmse": e, "colour_rmse": colour, "estimated_rmse": estimate})).collect::<Vec<_>>(),
            "sigma_one_sample": sigma, "spp_to_target": needed, "seconds_to_target": seconds,
        }));
    }
    let floor = curves.first().and_then(|c| c.points.first()).map_or(0.0, |(n, _, e)| {
        let n = f64::from(*n);
        (e * e / (1.0 / n + 1.0 / f64::from(k))).sqrt() / f64::from(k).sqrt()
    });
    table.push_str(&format!(
        "\nThe reference's own noise, σ/√{k} ≈ {:.2}/255, sits under every RMSE above.\n",
        floor * 255.0
    ));
    table.push_str(&format!("\nTo reach an RMSE of {}/255 (σ/√n = target):\n", args.target));
    table.push_str(&summary);
    // The raycasters' light volume beside the path tracer, with the key light alone and with a
    // fill and the headlight added (each light its own shadow channel and Blinn–Phong terms).
    let key = bench.runtime.lights();
    let three =
        Lights::new(&[key.key(), Light::Directional { azimuth_deg: 70.0, elevation_deg: 10.0 }, Light::Headlight])
            .map_err(|e| anyhow!(e))?;
    let shadows = light_volume_shadows(&mut bench, &["shadows"], key)?;
    let shaded = light_volume_shadows(&mut bench, &["shading", "shadows"], key)?;
    let shaded_three = light_volume_shadows(&mut bench, &["shading", "shadows"], three)?;
    bench.runtime.set_lights(key);
    table.push_str(&format!(
        "\nThe raycasters' light-volume `shadows` effect (modern/fastest, one frame, no accumulation; Behrens & \
         Ratering 1998: a scattering-free shadow per light, not the path tracer's light transport), ms/frame after \
         the light volume is built and RMSE against its own f64 reference:\n\n\
         | features | lights | ms/frame | RMSE (/255) |\n|---|---|---:|---:|\n\
         | shadows | {key:?} | {:.1} | {:.2} |\n| shading, shadows | {key:?} | {:.1} | {:.2} |\n\
         | shading, shadows | {three:?} | {:.1} | {:.2} |\n",
        shadows.0,
        shadows.1 * 255.0,
        shaded.0,
        shaded.1 * 255.0,
        shaded_three.0,
        shaded_three.1 * 255.0,
    ));
    println!("{table}");
    let value = serde_json::json!({
        "dataset": args.dataset, "size": args.size, "light": args.light, "adapter": adapter,
        "reference_spp": k, "target_rmse": target, "curves": json_curves,
        "light_volume_shadows": {"graph": "modern/fastest", "ms_per_frame": shadows.0, "rmse_vs_reference": shadows.1},
        "light_volume_shading_shadows": {"graph": "modern/fastest", "ms_per_frame": shaded.0, "rmse_vs_reference": shaded.1},
        "light_volume_shading_shadows_three_lights": {
            "graph": "modern/fastest", "lights": format!("{three:?}"), "ms_per_frame": shaded_three.0, "rmse_vs_reference": shaded_three.1,
        },
    });
    crate::report_files::write_markdown_and_json((args.markdown.as_deref(), &table), (args.json.as_deref(), &value))?;
    if let Some(path) = &args.plot {
        write_plot(path, &curves, target, &adapter)
            .map_err(|e| anyhow!("--plot {}: cannot draw the plot: {e}", path.display()))?;
    }
    Ok(value)
}

/// RMSE (/255) against seconds of accumulation, both on log scales (a path tracer's error is a
/// line of slope −½ there), one line per case, and the target as a dashed level.
fn write_plot(
    path: &std::path::Path,
    curves: &[Curve],
    target: f64,
    adapter: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let points: Vec<(f64, f64)> =
        curves.iter().flat_map(|c| c.points.iter().map(|&(_, s, e)| (s, e * 255.0))).collect();
    let (x_min, x_max) = points.iter().fold((f64::MAX, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    let (y_min, y_max) = points.iter().fold((target * 255.0, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let root = BitMapBackend::new(path, (960, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("path tracer: RMSE against seconds of accumulation, {adapter}"), ("sans-serif", 18))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d((x_min * 0.8..x_max * 1.25).log_scale(), (y_min * 0.8..y_max * 1.25).log_scale())?;
    chart.configure_mesh().x_desc("seconds of accumulation").y_desc("RMSE (1/255)").draw()?;
    for (i, c) in curves.iter().enumerate() {
        let color = crate::graphs::plot::palette(i);
        let line: Vec<(f64, f64)> = c.points.iter().map(|&(_, s, e)| (s, e * 255.0)).collect();
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))?
            .label(c.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2)));
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    let level = target * 255.0;
    chart
        .draw_series(DashedLineSeries::new(vec![(x_min * 0.8, level), (x_max * 1.25, level)], 6, 4, BLACK.into()))?
        .label(format!("target {level:.0}/255"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
    chart.configure_series_labels().background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(())
}

/// `modern/fastest` with `features` (the `shadows` effect among them) and `lights`: median ms of
/// 8 frames after a warm-up (which builds the light volume), and the RMSE of its image against
/// the f64 reference with the same lights and effects.
fn light_volume_shadows(bench: &mut Bench, features: &[&str], lights: Lights) -> anyhow::Result<(f64, f64)> {
    bench.runtime.set_lights(lights);
    let features: Vec<String> = features.iter().map(|f| f.to_string()).collect();
    let plan = bench.apply("modern/fastest", &[], None, &features)?;
    bench.frame(plan.viewport)?;
    let mut times = Vec::new();
    for _ in 0..8 {
        times.push(bench.frame(plan.viewport)?);
    }
    let image = bench.image()?;
    let march = plan.steps.iter().find(|s| s.pass_id == "march").ok_or_else(|| anyhow!("no march step"))?;
    let settings = volgraph_accel::reference::RaycastSettings {
        lights: bench.runtime.lights(),
        ..volgraph_passes::raycast_params::reference_settings(&march.params)
    };
    let (w, h) = plan.viewport;
    let reference =
        volgraph_accel::reference::render_reference(&bench.volume, &bench.lut, &bench.camera, w, h, &settings);
    Ok((median(&times), rmse(&image, &reference.color)))
}
