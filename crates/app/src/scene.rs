//! Scenes as files (`scenes/*.ron`): what to render — the volume, its transfer function, the
//! camera or a camera path, the viewport, the graph — and the effects the user wants
//! (`shading`, `preintegration`, `jitter`, `tricubic`), the accumulation precision and what the
//! transfer function's opacity is per. `volgraph render --scene FILE` and `volgraph view --scene
//! FILE` read them; flags given as well win over the scene's values. Paths are relative to the
//! scene file. Every problem is an error naming the file and line/column or field and the fix.
//!
//! ```ron
//! Scene(
//!     graph: "modern/fastest.ron",
//!     volume: Dataset("hydrogen_atom"),          // or File("path.raw"), Generated("ml64")
//!     transfer_function: File("tf/default.ron"),   // or Preset("sparse"), Data("engine_opaque")
//!     camera: Orbit(azimuth: 30, elevation: 20, distance: 3.2),
//!     viewport: (512, 512),
//!     effects: ["shading", "jitter"],
//!     precision: F32,                             // optional: F16 or F32 float targets
//!     opacity_reference: Voxel,                   // or World
//!     crop: (0, 0, 0, 0.5, 1, 1),                 // optional: X0,Y0,Z0,X1,Y1,Z1 in volume fractions
//!     clip: [(0, 1, 1, 0.8)],                     // optional: planes NX,NY,NZ,D keeping n·f >= D
//!     volume_options: (series: "2", spacing: (0.5, 0.5, 1.2)),  // optional: how to read the volume
//! )
//! ```
//!
//! A relative `graph` or `File(...)` transfer function names the file beside the scene when
//! there is one; where there is none, a built-in graph's name (`klein_2005/leap_iso`) or a TF
//! preset's (`ct-bone`, `graphs/tf/vessels.ron`) is resolved as the command line resolves it.

use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;
use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};
use volgraph_core::Precision;
use volgraph_core::runtime::OpacityReference;

mod camera;
mod load;
mod saved_view;

#[cfg(test)]
mod tests;

use camera::check_camera;
pub use camera::{CameraSpec, Keyframe, MAX_DISTANCE, MIN_DISTANCE};
pub use load::{ShownVolume, load_shown_volume, load_transfer_function, marschner_lobb_tf, tf_file_beside};
pub use saved_view::SavedView;

/// The most frames a scene renders, from `frames:` or a camera path's last keyframe (as
/// `render --frames` is capped): a keyframe at frame 10⁹ is an error, not a day of rendering.
pub const MAX_FRAMES: u32 = 100_000;

/// The effects a scene may ask for: those the built-in raycasters declare
/// (`volgraph_passes::effects::SCENE_EFFECTS`, `PassDecl::scene_effects`); graphs read them as
/// `"feature.NAME"`.
pub const EFFECTS: [&str; 6] = volgraph_passes::effects::SCENE_EFFECTS;

/// Where a scene's volume comes from.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum VolumeSource {
    /// A volume file, relative to the scene file.
    File(String),
    /// A dataset in `$VOLGRAPH_DATA/volumes` by name (`hydrogen_atom`).
    Dataset(String),
    /// A generated volume: `ml64` (Marschner–Lobb 64³), `mlf64`, `sphere64`, `noise64`.
    Generated(String),
}

/// Where a scene's transfer function comes from.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum TfSource {
    /// A RON or ParaView JSON file, relative to the scene file (or, where no such file is
    /// beside the scene, a built-in TF's or a scanner preset's name, as `--tf` takes it).
    File(String),
    /// `default`, `opaque` or `sparse`, stretched over the volume's values; or a scanner preset
    /// as `--tf` names it (`ct-bone`, `ct-soft-tissue`, `ct-lung`, `ct-angio`, `mr-default`).
    Preset(String),
    /// A file `$VOLGRAPH_DATA/tf/<name>.ron` (the peer benchmark's `engine_opaque`, ...).
    Data(String),
    /// A built-in TF by its stem (`vessels` for `graphs/tf/vessels.ron`): what a scene's
    /// `File("graphs/tf/vessels.ron")` becomes where no such file is beside the scene, read from
    /// the program's own copy (never a file of that name in the current folder). Not written in
    /// scene files.
    #[serde(skip_deserializing)]
    BuiltIn(String),
}

/// How to read the scene's volume: what the command line's `--series`, `--frame`, `--dims`,
/// `--dtype`, `--big-endian` and `--spacing` say (flags given as well win, field by field).
/// A named volume (`Dataset`, `Generated`) takes only `spacing`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VolumeOptions {
    /// The DICOM series of a folder holding several: its number, UID or description.
    #[serde(default)]
    pub series: Option<String>,
    /// The volume of a 4D NIfTI file (0-based).
    #[serde(default)]
    pub frame: Option<u64>,
    /// A headerless raw file's voxels per axis.
    #[serde(default)]
    pub dims: Option<(u32, u32, u32)>,
    /// A headerless raw file's voxel type: uint8, uint16, int16 or float32.
    #[serde(default)]
    pub dtype: Option<String>,
    /// A raw file's 16/32-bit voxels are big-endian.
    #[serde(default)]
    pub big_endian: bool,
    /// The voxel spacing X, Y, Z (over the file's header or the dataset's).
    #[serde(default)]
    pub spacing: Option<(f64, f64, f64)>,
}

impl VolumeOptions {
    /// The options a volume was read with, as a scene writes them.
    pub fn of(options: &volgraph_accel::load::LoadOptions<'_>) -> VolumeOptions {
        let raw = &options.raw;
        VolumeOptions {
            series: options.series.clone(),
            frame: options.frame,
            dims: raw.dims.map(|d| (d.x, d.y, d.z)),
            dtype: raw.dtype.map(|t| t.name().to_string()),
            big_endian: matches!(raw.endianness, volgraph_accel::load::Endianness::Big),
            spacing: raw.spacing.map(|s| (s.x, s.y, s.z)),
        }
    }

    /// The loader's options, checked as the command line checks its flags (the message names
    /// the flag the field stands for).
    pub fn load_options(&self) -> anyhow::Result<volgraph_accel::load::LoadOptions<'static>> {
        let raw = crate::cli::RawArgs {
            series: self.series.clone(),
            frame: self.frame,
            dims: self.dims.map(|(x, y, z)| format!("{x}x{y}x{z}")),
            dtype: self.dtype.clone(),
            // `Display` writes the shortest text that parses back to the same f64.
            spacing: self.spacing.map(|(x, y, z)| format!("{x},{y},{z}")),
            big_endian: self.big_endian,
        };
        crate::inputs::raw_options(&raw)
    }

    /// True when no option is set.
    pub fn is_empty(&self) -> bool {
        *self == VolumeOptions::default()
    }
}

/// A scene file as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, rename = "Scene")]
struct SceneDoc {
    #[serde(default)]
    graph: Option<String>,
    volume: VolumeSource,
    #[serde(default)]
    transfer_function: Option<TfSource>,
    #[serde(default)]
    camera: Option<CameraSpec>,
    #[serde(default)]
    viewport: Option<(u32, u32)>,
    #[serde(default)]
    effects: Vec<String>,
    #[serde(default)]
    precision: Option<Precision>,
    #[serde(default)]
    opacity_reference: OpacityReference,
    #[serde(default)]
    frames: Option<u32>,
    #[serde(default)]
    crop: Option<(f64, f64, f64, f64, f64, f64)>,
    #[serde(default)]
    clip: Vec<(f64, f64, f64, f64)>,
    #[serde(default)]
    volume_options: VolumeOptions,
    #[serde(default)]
    volumes: std::collections::BTreeMap<String, String>,
    #[serde(default)]
    tfs: std::collections::BTreeMap<String, String>,
    #[serde(default)]
    lights: Vec<SceneLight>,
    #[serde(default)]
    environment: Option<String>,
}

/// An entry of a scene's `lights:`: the light (`Headlight`, `Directional(…)`, `Point(…)`), or
/// what the path tracer's paths see when they leave the volume (`Environment(File("sky.exr"))`,
/// `Environment(Sky)` for its generated sky; the same as `environment:`).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
enum SceneLight {
    Headlight,
    Directional { azimuth_deg: f64, elevation_deg: f64 },
    Point { x: f64, y: f64, z: f64 },
    Environment(EnvironmentSource),
}

/// Where an `Environment(…)` light comes from.
#[derive(Clone, Debug, Deserialize, PartialEq)]
enum EnvironmentSource {
    /// An OpenEXR map beside the scene (or an absolute path).
    File(String),
    /// The path tracer's generated sky.
    Sky,
}

/// A scene read and checked, its paths resolved against the scene file's folder.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// The graph, if the scene names one.
    pub graph: Option<PathBuf>,
    /// The volume (file paths resolved).
    pub volume: VolumeSource,
    /// The transfer function (file paths resolved); `None`: fitted to the data.
    pub transfer_function: Option<TfSource>,
    /// The camera; `None`: the command's default.
    pub camera: Option<CameraSpec>,
    /// The viewport; `None`: the command's default.
    pub viewport: Option<(u32, u32)>,
    /// Effects that are on.
    pub effects: Vec<String>,
    /// Float target precision; `None`: the graph's formats.
    pub precision: Option<Precision>,
    /// What the TF's opacity is per.
    pub opacity_reference: OpacityReference,
    /// Frames of a camera path (default: the last keyframe's frame + 1, or 1).
    pub frames: Option<u32>,
    /// The crop box and clip planes (volume fractions).
    pub cuts: Cuts,
    /// How to read the volume (checked).
    pub volume_options: VolumeOptions,
    /// More volume inputs by name (`volumes: {"mask": "seg.nii.gz"}`): a path beside the scene
    /// or a volume's name, as `--volume NAME=PATH` takes it; `volume:` is then the input
    /// `volume`.
    pub volumes: Vec<(String, PathBuf)>,
    /// Transfer-function inputs by name (`tfs: {"mask_tf": "mask.ron"}`): a file beside the
    /// scene, a preset's or a built-in TF's name, as `--tf NAME=…` takes it.
    pub tfs: Vec<(String, PathBuf)>,
    /// The lights, up to three (`lights: [Directional(azimuth_deg: 35, elevation_deg: 25),
    /// Point(x: 0, y: 2, z: 1)]`; none: the headlight).
    pub lights: volgraph_accel::light::Lights,
    /// The environment map a path tracer's paths see (`environment: "sky.exr"`, beside the
    /// scene); none: the path tracer's own sky.
    pub environment: Option<PathBuf>,
}

/// Why a scene could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file cannot be read (missing, not a regular file, too large, not text).
    #[error(transparent)]
    Read(#[from] volgraph_accel::input_file::InputFileError),
    /// No file at the path, and no built-in scene of that name.
    #[error("{}: no such scene file, nor a built-in scene of that name (`volgraph scenes` lists them: {builtin})", .path.display())]
    Missing {
        /// The path given.
        path: PathBuf,
        /// The built-in scenes' names.
        builtin: String,
    },
    /// The RON does not parse into a scene.
    #[error("{}:{line}:{col}: {message}; see scenes/README.md (or crates/app/src/scene.rs) for the format", .path.display())]
    Ron {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// ron's message.
        message: String,
    },
    /// A field holds a value that cannot work.
    #[error("{}: {field}: {message}", .path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// The field.
        field: &'static str,
        /// What is wrong and how to fix it.
        message: String,
    },
}

impl Scene {
    /// The scene a `--scene` argument names: the file at `argument` (a dangling link too: the
    /// user's), else a shipped scene of that name (`engine_cut_open`; `crate::builtin_scenes`).
    pub fn load_named(argument: &Path) -> Result<Scene, SceneError> {
        match crate::builtin_scenes::find(argument) {
            Some((name, text)) => Scene::from_str(text, &crate::builtin_scenes::virtual_path(name)),
            None if argument.symlink_metadata().is_err() => Err(SceneError::Missing {
                path: argument.to_path_buf(),
                builtin: crate::builtin_graphs::EMBEDDED_SCENES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
            }),
            None => Scene::load(argument),
        }
    }

    /// Reads and checks the scene file `path`.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = volgraph_accel::input_file::read_text(path, "scene file")?;
        Scene::from_str(&text, path)
    }

    /// Parses and checks scene text; `path` names it in messages and anchors relative paths.
    pub fn from_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let doc: SceneDoc = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| SceneError::Ron {
                path: path.to_path_buf(),
                line: e.span.start.line,
                col: e.span.start.col,
                message: e.code.to_string(),
            })?;
        let field =
            |field: &'static str, message: String| SceneError::Field { path: path.to_path_buf(), field, message };
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let resolve = |p: &str| if Path::new(p).is_absolute() { PathBuf::from(p) } else { dir.join(p) };
        for effect in &doc.effects {
            if !EFFECTS.contains(&effect.as_str()) {
                let help = volgraph_core::suggest::guess_then(
                    effect,
                    EFFECTS.iter().copied(),
                    "",
                    format!("the effects are: {}", volgraph_core::suggest::comma_list(&EFFECTS)),
                );
                return Err(field("effects", format!("\"{effect}\" is not an effect; {help}")));
            }
        }
        if let Some((w, h)) = doc.viewport
            && (!(1..=16384).contains(&w) || !(1..=16384).contains(&h))
        {
            return Err(field("viewport", format!("({w}, {h}): each side must be 1..=16384 pixels")));
        }
        if let Some(frames) = doc.frames
            && !(1..=MAX_FRAMES).contains(&frames)
        {
            return Err(field("frames", format!("{frames}: expected 1..={MAX_FRAMES}")));
        }
        if let Some(camera) = &doc.camera {
            check_camera(camera).map_err(|m| field("camera", m))?;
        }
        if doc.graph.as_deref().is_some_and(|g| g.trim().is_empty()) {
            return Err(field("graph", "is empty; name the graph file, e.g. graph: \"modern/fastest.ron\"".into()));
        }
        for (name, path) in [
            (
                "volume",
                match &doc.volume {
                    VolumeSource::File(p) => Some(p),
                    _ => None,
                },
            ),
            (
                "transfer_function",
                match &doc.transfer_function {
                    Some(TfSource::File(p)) => Some(p),
                    _ => None,
                },
            ),
        ] {
            if path.is_some_and(|p| p.trim().is_empty()) {
                return Err(field(name, "File(\"\") names no file; give its path relative to the scene file".into()));
            }
        }
        let crop = doc
            .crop
            .map(|(x0, y0, z0, x1, y1, z1)| CropBox::new(DVec3::new(x0, y0, z0), DVec3::new(x1, y1, z1)))
            .transpose()
            .map_err(|e| field("crop", format!("{e} (write crop: (X0, Y0, Z0, X1, Y1, Z1))")))?;
        let planes = doc
            .clip
            .iter()
            .enumerate()
            .map(|(i, &(x, y, z, d))| {
                ClipPlane::new(DVec3::new(x, y, z), d)
                    .map_err(|e| field("clip", format!("plane {}: {e} (write clip: [(NX, NY, NZ, D)])", i + 1)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let cuts = Cuts::new(crop, &planes).map_err(|e| field("clip", e.to_string()))?;
        use volgraph_accel::light::Light;
        let (mut lights, mut environments) = (Vec::new(), Vec::new());
        for entry in &doc.lights {
            match entry {
                SceneLight::Headlight => lights.push(Light::Headlight),
                &SceneLight::Directional { azimuth_deg, elevation_deg } => {
                    lights.push(Light::Directional { azimuth_deg, elevation_deg })
                }
                &SceneLight::Point { x, y, z } => lights.push(Light::Point { x, y, z }),
                SceneLight::Environment(source) => environments.push(source),
            }
        }
        let lights = if lights.is_empty() {
            volgraph_accel::light::Lights::default()
        } else {
            volgraph_accel::light::Lights::new(&lights).map_err(|e| {
                let more = lights.len() > volgraph_accel::light::MAX_LIGHTS;
                field(
                    "lights",
                    if more {
                        format!("{e}, besides an Environment(…); keep at most {}", volgraph_accel::light::MAX_LIGHTS)
                    } else {
                        e
                    },
                )
            })?
        };
        let environment = match (environments.as_slice(), &doc.environment) {
            ([], None) | ([EnvironmentSource::Sky], None) => None,
            ([], Some(file)) | ([EnvironmentSource::File(file)], None) => Some(resolve(file)),
            _ => {
                return Err(field(
                    "lights",
                    "a scene has one environment: one Environment(File(\"sky.exr\")) in lights:, or environment: \
                     \"sky.exr\", not both or two"
                        .to_string(),
                ));
            }
        };
        if let Some(TfSource::Data(name)) = &doc.transfer_function {
            check_data_name(name).map_err(|m| field("transfer_function", m))?;
        }
        if let Some(TfSource::Preset(name)) = &doc.transfer_function
            && tf_preset(name).is_none()
        {
            return Err(field("transfer_function", format!("Preset(\"{name}\") is not a preset; {PRESETS}")));
        }
        doc.volume_options.load_options().map_err(|e| {
            field("volume_options", format!("{e:#} (the field volume_options says what that flag says)"))
        })?;
        let input_name = |field: &'static str, name: &str| {
            let mut chars = name.chars();
            let ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !ok {
                return Err(SceneError::Field {
                    path: path.to_path_buf(),
                    field,
                    message: format!("\"{name}\" is no input name (a letter or _, then letters, digits, _)"),
                });
            }
            Ok(())
        };
        let mut volumes = Vec::new();
        for (name, written) in &doc.volumes {
            input_name("volumes", name)?;
            if name == volgraph_core::runtime::inputs::PRIMARY_VOLUME {
                return Err(field("volumes", "\"volume\" is the scene's `volume:`; give the other inputs here".into()));
            }
            if written.trim().is_empty() {
                return Err(field("volumes", format!("\"{name}\": \"\" names no volume")));
            }
            volumes.push((name.clone(), beside_or_name(written, &dir, |p| crate::inputs::volume_name(p).is_some())));
        }
        let mut tfs = Vec::new();
        for (name, written) in &doc.tfs {
            input_name("tfs", name)?;
            if written.trim().is_empty() {
                return Err(field("tfs", format!("\"{name}\": \"\" names no transfer function")));
            }
            tfs.push((name.clone(), beside_or_name(written, &dir, is_tf_name)));
        }
        let volume = match doc.volume {
            VolumeSource::File(p) => VolumeSource::File(resolve(&p).display().to_string()),
            other => other,
        };
        let transfer_function = doc.transfer_function.map(|t| match t {
            TfSource::File(p) => tf_file_or_builtin(&p, &dir),
            other => other,
        });
        Ok(Scene {
            path: path.to_path_buf(),
            graph: doc.graph.as_deref().map(|g| beside_or_name(g, &dir, |p| crate::builtin_graphs::find(p).is_some())),
            volume,
            transfer_function,
            camera: doc.camera,
            viewport: doc.viewport,
            effects: doc.effects,
            precision: doc.precision,
            opacity_reference: doc.opacity_reference,
            frames: doc.frames,
            cuts,
            volume_options: doc.volume_options,
            volumes,
            tfs,
            lights,
            environment,
        })
    }

    /// The frames a render of this scene draws (a path's length, else `frames` or 1).
    pub fn frame_count(&self) -> u32 {
        match (&self.camera, self.frames) {
            (_, Some(f)) => f,
            (Some(CameraSpec::Path { keyframes }), None) => {
                keyframes.last().map_or(1, |k| k.frame.saturating_add(1).min(MAX_FRAMES))
            }
            _ => 1,
        }
    }
}

/// A relative path written in a scene: the file beside the scene when there is one (a dangling
/// link too: it is the user's file), else — where `names_builtin` says so — the name as written,
/// which the command line's rules resolve (a built-in graph, a TF preset), else the path beside
/// the scene (whose error then names it).
fn beside_or_name(written: &str, dir: &Path, names_builtin: impl Fn(&Path) -> bool) -> PathBuf {
    let path = Path::new(written);
    if path.is_absolute() {
        return path.to_path_buf();
    }
    let beside = dir.join(path);
    if beside.symlink_metadata().is_err() && names_builtin(path) { path.to_path_buf() } else { beside }
}

/// A scene's `File("…")` transfer function: the file beside the scene when there is one (a
/// dangling link too), else a scanner preset's name as that preset, else a built-in TF's name as
/// the built-in; else the path beside the scene (whose error then names it). Never a path
/// relative to the current folder, so a scene renders the same from any folder.
fn tf_file_or_builtin(written: &str, dir: &Path) -> TfSource {
    let path = Path::new(written);
    if path.is_absolute() {
        return TfSource::File(written.to_string());
    }
    let beside = dir.join(path);
    if beside.symlink_metadata().is_err() {
        if let Some(preset) = volgraph_accel::transfer_function::ScannerPreset::from_name(written) {
            return TfSource::Preset(preset.name().to_string());
        }
        if let Some((name, _)) = crate::builtin_graphs::builtin_tf(path) {
            return TfSource::BuiltIn(name.to_string());
        }
    }
    TfSource::File(beside.display().to_string())
}

/// Whether `--tf PATH` would read `path` as a built-in: a scanner preset's name or a built-in TF
/// (`graphs/tf/vessels.ron`).
fn is_tf_name(path: &Path) -> bool {
    path.to_str().and_then(volgraph_accel::transfer_function::ScannerPreset::from_name).is_some()
        || crate::builtin_graphs::find_tf(path).is_some()
}

/// A preset a scene's `Preset("…")` names: a general one (stretched over the volume's values) or
/// a scanner preset.
enum NamedPreset {
    General(volgraph_accel::transfer_function::Preset),
    Scanner(volgraph_accel::transfer_function::ScannerPreset),
}

fn tf_preset(name: &str) -> Option<NamedPreset> {
    use volgraph_accel::transfer_function::{Preset, ScannerPreset};
    Preset::from_name(name)
        .map(NamedPreset::General)
        .or_else(|| ScannerPreset::from_name(name).map(NamedPreset::Scanner))
}

/// The presets a scene's `Preset("…")` may name, for messages.
const PRESETS: &str = "use default, opaque or sparse, a scanner preset (ct-bone, ct-soft-tissue, ct-lung, ct-angio, \
                       mr-default), or File(\"path.ron\")";

/// A `Data("name")` transfer function names a file of `$VOLGRAPH_DATA/tf` by its stem: no
/// folders, no `..`, so a scene cannot read a file outside that folder.
fn check_data_name(name: &str) -> Result<(), String> {
    let plain = !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\'])
        && !name.chars().any(volgraph_core::terminal::is_unsafe);
    if plain {
        return Ok(());
    }
    Err(format!(
        "Data(\"{name}\") must name a file of $VOLGRAPH_DATA/tf by its stem (e.g. Data(\"engine_opaque\")), \
         without folders or \"..\"; for a file elsewhere write File(\"path.ron\")"
    ))
}
