//! The command-line flags of `volgraph bench graphs` and their resolution, together with a
//! preset, into one [`BenchConfig`]. Every bad value is an error naming its flag and the fix.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail};
use clap::Args;
use volgraph_accel::camera::OrbitCamera;

use super::preset::{self, BenchPreset};
use super::tf_choice::TfChoice;
use volgraph_app::inputs;

/// Flags of `volgraph bench graphs`. A `--preset` fills in graphs, datasets, sizes, transfer
/// functions, baseline and frames; any flag given as well replaces the preset's value.
#[derive(Args, Debug, Clone, Default)]
pub struct GraphsArgs {
    /// A named preset: basic, kw2003-table1, thesis-tables, peer, effects-off, klein2005.
    #[arg(long)]
    pub preset: Option<String>,
    /// Graph files, comma separated (graphs that do not exist are skipped with a note).
    #[arg(long, value_delimiter = ',')]
    pub graphs: Vec<PathBuf>,
    /// Datasets, comma separated: names in $VOLGRAPH_DATA/volumes (hydrogen_atom, neghip, ...) or
    /// generated volumes (ml64 = Marschner–Lobb 64³, mlf64 = its f32 twin, sphere64, noise64, tooth256 = a molar CT).
    #[arg(long, value_delimiter = ',')]
    pub datasets: Vec<String>,
    /// Viewports WIDTHxHEIGHT, comma separated (default 512x512).
    #[arg(long, value_delimiter = ',')]
    pub size: Vec<String>,
    /// Shrinks every viewport by this factor (e.g. 0.25 for lavapipe).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Timed frames per case, after one warm-up frame (default 36).
    #[arg(long)]
    pub frames: Option<u32>,
    /// Degrees the volume turns about y per frame (default 1; see --full-turn).
    #[arg(long)]
    pub rotate: Option<f64>,
    /// Turn 360/FRAMES degrees per frame instead, so the frames cover a whole turn.
    #[arg(long)]
    pub full_turn: bool,
    /// Orbit camera of the first frame, AZIMUTH,ELEVATION,DISTANCE (default 30,20,3.2).
    #[arg(long)]
    pub camera: Option<String>,
    /// The baseline graph (its file stem) speed-ups are measured against; default:
    /// the preset's, else the first graph.
    #[arg(long)]
    pub baseline: Option<String>,
    /// Transfer functions, comma separated: presets stretched over each volume's values (default,
    /// opaque, sparse), `fitted` (transparent up to the volume's background, as `volgraph render`
    /// picks), .ron/.json files, or names of files in $VOLGRAPH_DATA/tf (engine_opaque, hydrogen, ...).
    #[arg(long, value_delimiter = ',')]
    pub tf: Vec<String>,
    /// A shader folder to read before the built-in shaders (default: the `shaders/` folder of the
    /// workspace holding the first graph, if there is one).
    #[arg(long)]
    pub shaders: Option<PathBuf>,
    /// Do not run the preset's peer program (the `peer` preset's VTK CPU raycaster).
    #[arg(long)]
    pub no_peer: bool,
    /// Do not count the samples graphs take on the GPU (passes with a `count_samples`
    /// parameter); by default one extra frame per case counts them.
    #[arg(long)]
    pub no_gpu_count: bool,
    /// GPU memory, in MiB, a brick pool may hold (graphs/ruijters_vilanova_2006); volumes that do
    /// not fit stream through it [default: 2048, bounded by the adapter's 3D texture limit].
    #[arg(long = "gpu-memory-mb", value_parser = clap::value_parser!(u64).range(1..=1 << 24))]
    pub gpu_memory_mb: Option<u64>,
    /// Accuracy sweep PASS.PARAM=V1,V2,... (e.g. march.step_voxels=0.25,0.5,1,2), input.NAME=...
    /// for a Scalar graph input shared by several passes, feature.NAME=off,on for a scene effect,
    /// scene.precision=f16,f32; adds error against a converged CPU reference (of the same
    /// effects) to every row.
    #[arg(long)]
    pub sweep: Option<String>,
    /// A fixed value for every case, KEY=NUMBER (repeat the flag): PASS.PARAM or input.NAME, as
    /// --sweep takes keys; added to the preset's own values, and it wins over them (e.g.
    /// --set input.iso_value=0.2 with --sweep input.reproject_below=16,48).
    #[arg(long = "set")]
    pub set: Vec<String>,
    /// Compute error against the converged CPU reference even without --sweep.
    #[arg(long)]
    pub accuracy: bool,
    /// Longest side of the images compared with the CPU reference (error columns).
    #[arg(long, default_value_t = 128)]
    pub accuracy_size: u32,
    /// Step of the converged CPU reference, in voxels.
    #[arg(long, default_value_t = 0.1)]
    pub reference_step: f64,
    /// The scene's light for every case: AZ,EL in degrees (a directional light fixed in the
    /// world while the camera turns), point:X,Y,Z, or headlight [default: the headlight].
    #[arg(long, value_parser = volgraph_accel::light::Light::parse, allow_hyphen_values = true)]
    pub light: Option<volgraph_accel::light::Light>,
    /// Longest side of the CPU reference image whose sample count gives samples/pixel
    /// (0: do not count samples).
    #[arg(long, default_value_t = 128)]
    pub spp_size: u32,
    /// Write the report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write a PNG plot here (ms/frame bars; error vs time when sweeping).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Also write the markdown table here (it is always printed to stdout).
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// One `--sweep`: a pass parameter and the values it takes.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// `pass.param`, the key of `CompileOptions::param_overrides`.
    pub key: String,
    /// The values as written (for tables) and as RON values (for the compiler).
    pub values: Vec<(String, ron::Value)>,
}

/// Everything one run measures, resolved from a preset and flags.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// The preset used, if any.
    pub preset: Option<&'static BenchPreset>,
    /// Graph files.
    pub graphs: Vec<PathBuf>,
    /// The baseline graph's label.
    pub baseline: String,
    /// Dataset names, each once, in the order they are measured.
    pub datasets: Vec<String>,
    /// `(dataset, transfer function)` pairs, grouped by dataset.
    pub cases: Vec<(String, TfChoice)>,
    /// Viewports after `--scale`.
    pub viewports: Vec<(u32, u32)>,
    /// The scale applied.
    pub scale: f64,
    /// Fixed parameter overrides (from the preset).
    pub params: Vec<(String, f64)>,
    /// Timed frames per case.
    pub frames: u32,
    /// Degrees about y per frame.
    pub degrees_per_frame: f64,
    /// Camera of the first timed frame.
    pub camera: OrbitCamera,
    /// The sweep, if any.
    pub sweep: Option<Sweep>,
    /// Whether to measure error against the converged reference.
    pub accuracy: bool,
    /// Longest side of the accuracy images.
    pub accuracy_size: u32,
    /// Step of the converged reference, voxels.
    pub reference_step: f64,
    /// Longest side of the samples/pixel reference image (0 = off).
    pub spp_size: u32,
    /// Count samples on the GPU where a pass can.
    pub gpu_count: bool,
    /// The brick pool's budget in bytes (`--gpu-memory-mb`).
    pub gpu_memory_budget: Option<u64>,
    /// The scene's light (`--light`), on the GPU and in the reference.
    pub light: volgraph_accel::light::Light,
    /// Run the preset's peer.
    pub peer: bool,
    /// A shader folder read before the built-in shaders.
    pub shaders: Option<PathBuf>,
    /// JSON output.
    pub json: Option<PathBuf>,
    /// Plot output.
    pub plot: Option<PathBuf>,
    /// Markdown output (besides stdout).
    pub markdown: Option<PathBuf>,
    /// Hide the progress bar.
    pub quiet: bool,
    /// `(graph, baseline)` pairs measured against their own baseline (the preset's, when its
    /// graphs and baseline are used).
    pub baselines: Vec<(String, String)>,
    /// `(dataset, knob, value)` overrides for one dataset's cases (the preset's).
    pub dataset_params: Vec<(String, String, f64)>,
    /// The preset's antialiasing study and its viewport after `--scale` (when the preset's
    /// graphs are measured).
    pub antialias: Option<(super::antialias_study::AntialiasStudy, (u32, u32))>,
    /// Graphs whose transient memory the report states, at a viewport (the preset's).
    pub memory: Vec<(PathBuf, (u32, u32))>,
}

/// The label of a graph file in tables: its file stem.
pub fn graph_label(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| path.display().to_string())
}

/// Parses one `--set KEY=NUMBER`.
pub fn parse_set(text: &str) -> anyhow::Result<(String, f64)> {
    let fail = |why: &str| {
        anyhow!("--set \"{text}\": {why}; expected PASS.PARAM=NUMBER or input.NAME=NUMBER, e.g. input.iso_value=0.2")
    };
    let (key, value) = text.split_once('=').ok_or_else(|| fail("no '='"))?;
    let key = key.trim();
    if !key.split_once('.').is_some_and(|(a, b)| !a.is_empty() && !b.is_empty()) {
        return Err(fail("the key must be PASS.PARAM or input.NAME"));
    }
    let value: f64 = value.trim().parse().map_err(|_| fail("the value is not a number"))?;
    if !value.is_finite() {
        return Err(fail("the value is not finite"));
    }
    Ok((key.to_string(), value))
}

/// Parses `--sweep PASS.PARAM=V1,V2,...`.
pub fn parse_sweep(text: &str) -> anyhow::Result<Sweep> {
    let fail = |why: &str| {
        anyhow!("--sweep \"{text}\": {why}; expected PASS.PARAM=V1,V2,..., e.g. march.step_voxels=0.25,0.5,1,2")
    };
    let (key, values) = text.split_once('=').ok_or_else(|| fail("no '='"))?;
    let key = key.trim();
    let Some((pass, param)) = key.split_once('.') else {
        return Err(fail("the key must be PASS.PARAM"));
    };
    if pass.is_empty() || param.is_empty() {
        return Err(fail("the key must be PASS.PARAM"));
    }
    let values: Vec<(String, ron::Value)> = values
        .split(',')
        .map(str::trim)
        .filter(|v| !v.is_empty())
        .map(|v| {
            let value = match v {
                "true" => ron::Value::Bool(true),
                "false" => ron::Value::Bool(false),
                _ => match v.parse::<f64>() {
                    Ok(x) if x.is_finite() => ron::Value::from(x),
                    Ok(_) => return Err(fail(&format!("\"{v}\" is not finite"))),
                    Err(_) => ron::Value::String(v.to_string()),
                },
            };
            Ok((v.to_string(), value))
        })
        .collect::<anyhow::Result<_>>()?;
    if values.is_empty() {
        return Err(fail("no values"));
    }
    if pass == "feature" {
        for (text, _) in &values {
            if !matches!(text.as_str(), "on" | "off") {
                return Err(fail(&format!("a feature is \"on\" or \"off\", not \"{text}\"")));
            }
        }
    }
    if pass == "scene" {
        if param != "precision" {
            return Err(fail("the scene knob is scene.precision"));
        }
        for (text, _) in &values {
            if volgraph_core::Precision::from_name(text).is_none() {
                return Err(fail(&format!("precision is f16 or f32, not \"{text}\"")));
            }
        }
    }
    Ok(Sweep { key: key.to_string(), values })
}

/// Scales a viewport, keeping each side at least 1 pixel.
pub fn scale_viewport((w, h): (u32, u32), scale: f64) -> (u32, u32) {
    let s = |v: u32| ((v as f64 * scale).round() as u32).max(1);
    (s(w), s(h))
}

/// A viewport with the same aspect whose longest side is at most `longest`.
pub fn reduced_viewport((w, h): (u32, u32), longest: u32) -> (u32, u32) {
    let m = w.max(h);
    if m <= longest {
        return (w, h);
    }
    scale_viewport((w, h), longest as f64 / m as f64)
}

impl GraphsArgs {
    /// The `(dataset, TF)` pairs: `--datasets` × `--tf` where either is given (the other from the
    /// preset's lists, else `ml64` / `default`), else the preset's pairs, else its datasets × tfs.
    fn cases(&self, preset: Option<&BenchPreset>) -> anyhow::Result<Vec<(String, TfChoice)>> {
        let explicit = !self.datasets.is_empty() || !self.tf.is_empty();
        if let Some(p) = preset.filter(|p| !explicit && !p.cases.is_empty()) {
            return p.cases.iter().map(|&(d, t)| Ok((d.to_string(), TfChoice::parse(t)?))).collect();
        }
        let or_preset = |given: &[String], from: fn(&BenchPreset) -> &'static [&'static str], fallback: &str| {
            if !given.is_empty() {
                return given.to_vec();
            }
            match preset.map(from).filter(|l| !l.is_empty()) {
                Some(list) => list.iter().map(|s| s.to_string()).collect(),
                None => vec![fallback.to_string()],
            }
        };
        let datasets = or_preset(&self.datasets, |p| p.datasets, "ml64");
        let tfs: Vec<TfChoice> = or_preset(&self.tf, |p| p.tfs, "default")
            .iter()
            .map(|t| TfChoice::parse(t))
            .collect::<anyhow::Result<_>>()?;
        Ok(datasets.iter().flat_map(|d| tfs.iter().map(move |t| (d.clone(), t.clone()))).collect())
    }

    /// Merges the flags with the preset into a checked configuration.
    pub fn resolve(&self) -> anyhow::Result<BenchConfig> {
        let preset =
            match &self.preset {
                None => None,
                Some(name) => Some(preset::find(name).ok_or_else(|| {
                    anyhow!("--preset \"{name}\": no such preset; choose one of: {}", preset::names())
                })?),
            };
        let graphs: Vec<PathBuf> = if !self.graphs.is_empty() {
            self.graphs.clone()
        } else if let Some(p) = preset {
            p.graphs.iter().map(PathBuf::from).collect()
        } else {
            bail!("no graphs: give --graphs a.ron,b.ron or a --preset ({})", preset::names());
        };
        let mut labels: Vec<String> = graphs.iter().map(|g| graph_label(g)).collect();
        if let Some(peer) = preset.and_then(|p| p.peer).filter(|_| !self.no_peer) {
            labels.push(peer.label.to_string());
        }
        // A preset whose baseline is its peer program (`peer`: VTK) measures against its first
        // graph when `--no-peer` leaves the peer out (on a machine without VTK, say).
        let peer_left_out = |b: &str| self.no_peer && preset.and_then(|p| p.peer).is_some_and(|peer| peer.label == b);
        let baseline = match (&self.baseline, preset) {
            (Some(b), _) => b.clone(),
            (None, Some(p)) if self.graphs.is_empty() && !peer_left_out(p.baseline) => p.baseline.to_string(),
            _ => labels[0].clone(),
        };
        if !labels.contains(&baseline) {
            bail!(
                "--baseline \"{baseline}\": not one of the graphs ({}); name a graph by its file stem",
                labels.join(", ")
            );
        }
        if !(self.scale.is_finite() && self.scale > 0.0 && self.scale <= 8.0) {
            bail!("--scale {}: expected a factor in (0, 8], e.g. 0.25 to render a quarter of each side", self.scale);
        }
        let base_sizes: Vec<(u32, u32)> = if !self.size.is_empty() {
            self.size.iter().map(|s| inputs::parse_size(s)).collect::<anyhow::Result<_>>()?
        } else {
            preset.map_or_else(|| vec![(512, 512)], |p| p.viewports.to_vec())
        };
        let viewports = base_sizes.into_iter().map(|v| scale_viewport(v, self.scale)).collect();
        let cases = self.cases(preset)?;
        let mut datasets: Vec<String> = Vec::new();
        for (d, _) in &cases {
            if !datasets.contains(d) {
                datasets.push(d.clone());
            }
        }
        let frames = self.frames.or(preset.map(|p| p.frames)).unwrap_or(36);
        if frames == 0 {
            bail!("--frames 0: at least one timed frame is needed");
        }
        let degrees_per_frame = match (self.full_turn, self.rotate) {
            (true, Some(_)) => bail!("--rotate and --full-turn both given; use one"),
            (true, None) => 360.0 / frames as f64,
            (false, Some(d)) if d.is_finite() => d,
            (false, Some(d)) => bail!("--rotate {d}: expected a finite number of degrees"),
            (false, None) if preset.is_some_and(|p| p.full_turn) => 360.0 / frames as f64,
            (false, None) => 1.0,
        };
        let camera = match (&self.camera, preset.and_then(|p| p.camera)) {
            (Some(c), _) => inputs::parse_camera(c)?,
            (None, Some([azimuth_deg, elevation_deg, distance])) => {
                OrbitCamera { azimuth_deg, elevation_deg, distance, ..OrbitCamera::default() }
            }
            (None, None) => OrbitCamera::default(),
        };
        let sweep = self.sweep.as_deref().map(parse_sweep).transpose()?;
        if !(self.reference_step.is_finite() && self.reference_step > 0.0) {
            bail!("--reference-step {}: expected a positive step in voxels, e.g. 0.1", self.reference_step);
        }
        if self.accuracy_size == 0 || self.accuracy_size > 4096 {
            bail!("--accuracy-size {}: expected 1..=4096 pixels", self.accuracy_size);
        }
        if self.spp_size > 4096 {
            bail!("--spp-size {}: expected 0 (off) ..=4096 pixels", self.spp_size);
        }
        let mut params: Vec<(String, f64)> =
            preset.map(|p| p.params.iter().map(|(k, v)| (k.to_string(), *v)).collect()).unwrap_or_default();
        for text in &self.set {
            params.push(parse_set(text)?);
        }
        // The preset's own comparison: its pairs of graphs, its studies.
        let own = preset.filter(|_| self.graphs.is_empty());
        let baselines = own
            .filter(|_| self.baseline.is_none())
            .map(|p| p.baselines.iter().map(|(g, b)| (g.to_string(), b.to_string())).collect())
            .unwrap_or_default();
        let dataset_params = preset
            .map(|p| p.dataset_params.iter().map(|(d, k, v)| (d.to_string(), k.to_string(), *v)).collect())
            .unwrap_or_default();
        let antialias = own.and_then(|p| p.antialias).map(|study| (study, scale_viewport(study.size, self.scale)));
        let memory =
            own.map(|p| p.memory.iter().map(|(g, size)| (PathBuf::from(g), *size)).collect()).unwrap_or_default();
        Ok(BenchConfig {
            preset,
            graphs,
            baseline,
            datasets,
            cases,
            viewports,
            scale: self.scale,
            params,
            frames,
            degrees_per_frame,
            camera,
            accuracy: self.accuracy || sweep.is_some(),
            sweep,
            accuracy_size: self.accuracy_size,
            reference_step: self.reference_step,
            spp_size: self.spp_size,
            gpu_count: !self.no_gpu_count,
            gpu_memory_budget: self.gpu_memory_mb.map(|mb| mb << 20),
            light: self.light.unwrap_or_default(),
            peer: !self.no_peer && preset.is_some_and(|p| p.peer.is_some()),
            shaders: self.shaders.clone(),
            json: self.json.clone(),
            plot: self.plot.clone(),
            markdown: self.markdown.clone(),
            quiet: self.quiet,
            baselines,
            dataset_params,
            antialias,
            memory,
        })
    }
}
