//! The inputs `volgraph render` and `volgraph view` share, declared once for both command lines:
//! the graph, a scene file, the volume, the transfer function, the viewport, the camera, the
//! scene's effects, a shader folder and the GPU memory budget.

use std::path::PathBuf;

use anyhow::anyhow;

use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};

use crate::cli::RawArgs;
use crate::inputs;
use crate::scene::{CameraSpec, Scene};

/// What to draw and how to look at it (flags given as well as a scene win over it).
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// The graph file (RON); default: the scene's graph.
    pub graph: Option<PathBuf>,
    /// A scene file (scenes/*.ron): volume, transfer function, camera or camera path,
    /// viewport, graph, effects, precision; flags given as well win over it.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// The volume: a file (.raw named NAME_XxYxZ_TYPE.raw, .nrrd, .nhdr, .mhd, .mha, .nii,
    /// .nii.gz), a folder of DICOM slices, DICOM slice files (`--volume dir/*.dcm`), or a name: a
    /// dataset of the data folder (`lobster`) or a generated volume (`ml64`, `vessels128`);
    /// default: a generated Marschner–Lobb 64³. `--volume NAME=PATH` (repeat for each) binds
    /// the graph's volume input NAME (render; volumes on one grid).
    #[arg(long, num_args = 1..)]
    pub volume: Vec<PathBuf>,
    /// How to read a headerless raw volume.
    #[command(flatten)]
    pub raw: RawArgs,
    /// Transfer function (RON, or ParaView color-map .json; the viewer watches it for edits), or
    /// a built-in preset for scanner data: ct-bone, ct-soft-tissue, ct-lung, ct-angio (in HU),
    /// mr-default (percentiles), or a transfer function of the data folder's tf/ by name
    /// (`engine_opaque`, as a scene's Data("…")); default: for a generated 8-bit Marschner–Lobb volume (the
    /// default volume, `ml64`, `ml32`) the band that shows its rings (graphs/tf/marschner_lobb.ron),
    /// else one fitted to the data (transparent up to its background of air or noise; see
    /// `volgraph info`). `--tf NAME=FILE|PRESET` (repeat for each) binds the graph's
    /// transfer-function input NAME (render).
    #[arg(long, action = clap::ArgAction::Append)]
    pub tf: Vec<PathBuf>,
    /// The colour map to use from a ParaView .json holding several (its "Name"); default: the first.
    #[arg(long = "tf-map")]
    pub tf_map: Option<String>,
    /// Viewport (the viewer's window), WIDTHxHEIGHT [default: the scene's, else 512x512 for
    /// render and 800x600 for view].
    #[arg(long)]
    pub size: Option<String>,
    /// Orbit camera AZIMUTH,ELEVATION,DISTANCE (degrees, degrees, world units) [default: the
    /// scene's first camera, else 30,20,3.2].
    #[arg(long)]
    pub camera: Option<String>,
    /// A standard view of a volume in the patient frame (DICOM, NIfTI, an anatomical NRRD):
    /// anterior, posterior, left, right, superior or inferior — superior up, as the clinical
    /// tools show them (from above or below: anterior up). The viewer's keys 1–6 give the same.
    #[arg(long, conflicts_with = "camera")]
    pub view: Option<String>,
    /// Scene features (effects) that are on, comma separated: shading, preintegration,
    /// jitter, tricubic (added to the scene's; the viewer's panel toggles them).
    #[arg(long, value_delimiter = ',')]
    pub features: Vec<String>,
    /// A shader folder to read (and, in the viewer, watch) instead of the built-in shaders
    /// (default: a `shaders/` folder beside the graph's workspace, if there is one).
    #[arg(long)]
    pub shaders: Option<PathBuf>,
    /// GPU memory, in MiB, passes that stream data may hold (the brick pool of
    /// graphs/ruijters_vilanova_2006); a volume that does not fit streams through it
    /// [default: 2048, bounded by the adapter's 3D texture limit].
    #[arg(long = "gpu-memory-mb", value_parser = clap::value_parser!(u64).range(1..=1 << 24))]
    pub gpu_memory_mb: Option<u64>,
    /// Host memory, in MiB, a volume streamed from an OME-Zarr store may hold in decoded chunks
    /// (graphs/streaming/ray_guided.ron reads it brick by brick) [default: 512].
    #[arg(long = "memory-mb", value_parser = clap::value_parser!(u64).range(16..=1 << 24))]
    pub memory_mb: Option<u64>,
    /// Crop box X0,Y0,Z0,X1,Y1,Z1 in fractions of the volume (0..1 per axis): only what lies
    /// inside is drawn [default: the scene's crop, else none].
    #[arg(long, value_parser = CropBox::parse, allow_hyphen_values = true)]
    pub crop: Option<CropBox>,
    /// A clip plane NX,NY,NZ,D in volume fractions, keeping the side its normal points to
    /// (n·f >= D): 1,0,0,0.5 keeps x >= 0.5. Repeat for more (at most 6) [default: the scene's
    /// planes].
    #[arg(long, value_parser = ClipPlane::parse, allow_hyphen_values = true)]
    pub clip: Vec<ClipPlane>,
    /// A light: AZ,EL in degrees (a directional light where an orbit camera at those angles
    /// would stand; elevation -90..90), point:X,Y,Z (a point light in world units: the volume's
    /// box is centred on the origin, its longest side 2), or headlight. Repeat for up to 3
    /// lights (key, fill, back), which then replace the scene's [default: the scene's lights,
    /// else the headlight].
    #[arg(long, value_parser = volgraph_accel::light::Light::parse, allow_hyphen_values = true)]
    pub light: Vec<volgraph_accel::light::Light>,
    /// An environment map (OpenEXR, equirectangular linear radiance) that a path tracer's paths
    /// see when they leave the volume [default: the scene's, else the path tracer's own sky].
    #[arg(long)]
    pub environment: Option<PathBuf>,
}

/// What the command line and the scene say together: flags win over the scene.
pub struct Resolved {
    /// The scene file, read and checked.
    pub scene: Option<Scene>,
    /// The graph file.
    pub graph: PathBuf,
    /// The viewport, WIDTHxHEIGHT.
    pub size: String,
    /// The camera (an orbit, or the scene's path).
    pub camera: CameraSpec,
    /// True when nothing chose the camera (no `--camera`, `--view` or scene camera): a volume in
    /// the patient frame is then seen from the front, superior up ([`Resolved::camera_for`]).
    pub camera_is_default: bool,
    /// The crop box and clip planes: `--crop` and `--clip` win over the scene's.
    pub cuts: Cuts,
    /// The lights: `--light` wins over the scene's.
    pub lights: volgraph_accel::light::Lights,
    /// The environment map's file: `--environment` wins over the scene's.
    pub environment: Option<PathBuf>,
}

impl SceneArgs {
    /// The one transfer function of a command that binds one volume and one transfer function
    /// (`view`, `--distributed`): named inputs are refused there with what to use instead.
    pub fn single_tf(&self, command: &str) -> anyhow::Result<Option<PathBuf>> {
        let (plain, named) = crate::named_inputs::split_tfs(&self.tf)?;
        let named_volume = crate::named_inputs::named_volumes(&self.volume)?;
        if let Some(name) = named.first().map(|(n, _)| n).or(named_volume.first().map(|(n, _)| n)) {
            return Err(anyhow!(
                "{command} binds one volume and one transfer function; \"{name}=…\" names a graph input, which \
                 `volgraph render` binds (or give plain --volume PATH / --tf FILE)"
            ));
        }
        Ok(plain)
    }

    /// Reads the scene and picks the graph, viewport and camera: a flag, else the
    /// scene's, else `default_size` and the 30,20,3.2 orbit. `usage` is the command line that
    /// names a graph, for the error when neither says one.
    pub fn resolve(&self, usage: &str, default_size: &str) -> anyhow::Result<Resolved> {
        if let Some(dir) = &self.shaders
            && !dir.is_dir()
        {
            let what = if dir.exists() { "is not a folder" } else { "does not exist" };
            return Err(anyhow!(
                "--shaders {}: {what}; give the folder that holds the .wgsl files (e.g. --shaders shaders), or leave \
                 the flag out to use the built-in shaders",
                dir.display()
            ));
        }
        let scene = self.scene.as_deref().map(Scene::load_named).transpose().map_err(|e| anyhow!(e))?;
        let graph = match (&self.graph, scene.as_ref().and_then(|s| s.graph.clone())) {
            (Some(g), _) => g.clone(),
            (None, Some(g)) => g,
            (None, None) => {
                return Err(anyhow!(
                    "no graph: give a graph file ({usage}), or a --scene whose file names one \
                     (graph: \"modern/fastest.ron\")"
                ));
            }
        };
        let size = self
            .size
            .clone()
            .or_else(|| scene.as_ref().and_then(|s| s.viewport).map(|(w, h)| format!("{w}x{h}")))
            .unwrap_or_else(|| default_size.to_string());
        let camera_is_default =
            self.view.is_none() && self.camera.is_none() && scene.as_ref().is_none_or(|s| s.camera.is_none());
        let camera = match (&self.camera, scene.as_ref().and_then(|s| s.camera.clone())) {
            _ if self.view.is_some() => patient_view(self.view.as_deref().unwrap_or_default())?,
            (Some(text), _) => orbit(text)?,
            (None, Some(spec)) => spec,
            (None, None) => orbit("30,20,3.2")?,
        };
        let scene_cuts = scene.as_ref().map_or(Cuts::NONE, |s| s.cuts);
        let crop = self.crop.or(scene_cuts.crop());
        let planes: Vec<ClipPlane> =
            if self.clip.is_empty() { scene_cuts.planes().copied().collect() } else { self.clip.clone() };
        let cuts = Cuts::new(crop, &planes).map_err(|e| anyhow!("--clip: {e}"))?;
        let lights = if self.light.is_empty() {
            scene.as_ref().map(|s| s.lights).unwrap_or_default()
        } else {
            volgraph_accel::light::Lights::new(&self.light).map_err(|e| anyhow!("--light: {e}"))?
        };
        let environment = self.environment.clone().or_else(|| scene.as_ref().and_then(|s| s.environment.clone()));
        Ok(Resolved { scene, graph, size, camera, camera_is_default, cuts, lights, environment })
    }
}

impl Resolved {
    /// The camera for `volume`: the one chosen, else — for a volume in the patient frame — the
    /// anterior view, superior up, as the clinical tools open a scan (the generated and raw
    /// volumes, in index axes, keep the 30°, 20° orbit).
    pub fn camera_for(
        camera: CameraSpec,
        camera_is_default: bool,
        volume: &volgraph_accel::volume::Volume,
    ) -> CameraSpec {
        if camera_is_default && volume.meta.frame == volgraph_accel::volume_meta::WorldFrame::Lps {
            patient_view("anterior").unwrap_or(camera)
        } else {
            camera
        }
    }
}

/// The camera of `--view NAME`, 3.2 away: superior up.
fn patient_view(name: &str) -> anyhow::Result<CameraSpec> {
    use volgraph_accel::camera::PatientView;
    let view = PatientView::from_name(name).ok_or_else(|| {
        anyhow!("--view {name}: not a view; the views are {} (a volume in the patient frame)", PatientView::names())
    })?;
    let c = view.camera(3.2);
    Ok(CameraSpec::Orbit {
        azimuth: c.azimuth_deg,
        elevation: c.elevation_deg,
        distance: c.distance,
        target: None,
        up: c.up,
    })
}

/// `--view` needs a volume whose axes lie in the patient (LPS): named views of index axes would
/// name sides the file never gave.
pub fn check_view_frame(view: Option<&str>, volume: &volgraph_accel::volume::Volume) -> anyhow::Result<()> {
    match view {
        Some(name) if volume.meta.frame != volgraph_accel::volume_meta::WorldFrame::Lps => Err(anyhow!(
            "--view {name}: {} lies in {}; the patient views need a volume in the patient frame (DICOM, NIfTI, an \
             anatomical NRRD); use --camera AZIMUTH,ELEVATION,DISTANCE",
            volume.name,
            volume.meta.frame.describe()
        )),
        _ => Ok(()),
    }
}

/// The orbit camera of `AZIMUTH,ELEVATION,DISTANCE`.
fn orbit(text: &str) -> anyhow::Result<CameraSpec> {
    let c = inputs::parse_camera(text)?;
    Ok(CameraSpec::Orbit {
        azimuth: c.azimuth_deg,
        elevation: c.elevation_deg,
        distance: c.distance,
        target: None,
        up: volgraph_accel::camera::CameraUp::Y,
    })
}
