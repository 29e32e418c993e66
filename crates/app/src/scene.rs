//! Scenes as files (`scenes/*.ron`): what to render — the volume, its transfer function, the
//! camera or a camera path, the viewport, the graph — and the effects the user wants
//! (`shading`, `preintegration`, `jitter`, `tricubic`), the accumulation precision and what the
//! transfer function's opacity is per. `volgraph render --scene FILE` and `volgraph view --scene
//! FILE` read them; flags given as well win over the scene's values. Paths are relative to the
//! scene file. Every problem is an error naming the file and line/column or field and the fix.
//!
//! ```ron
//! Scene(
//!     graph: "../graphs/modern/fastest.ron",
//!     volume: Dataset("hydrogen_atom"),          // or File("path.raw"), Generated("ml64")
//!     transfer_function: File("../graphs/tf/default.ron"),   // or Preset("sparse"), Data("engine_opaque")
//!     camera: Orbit(azimuth: 30, elevation: 20, distance: 3.2),
//!     viewport: (512, 512),
//!     effects: ["shading", "jitter"],
//!     precision: F32,                             // optional: F16 or F32 float targets
//!     opacity_reference: Voxel,                   // or World
//! )
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;
use volgraph_accel::camera::OrbitCamera;
use volgraph_core::Precision;
use volgraph_core::runtime::OpacityReference;

/// The effects a scene may ask for (issue "effects a scene asks for"); graphs read them as
/// `"feature.NAME"`.
pub const EFFECTS: [&str; 4] = ["shading", "preintegration", "jitter", "tricubic"];

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
    /// A RON or ParaView JSON file, relative to the scene file.
    File(String),
    /// `default`, `opaque` or `sparse`, stretched over the volume's values.
    Preset(String),
    /// A file `$VOLGRAPH_DATA/tf/<name>.ron` (the peer benchmark's `engine_opaque`, ...).
    Data(String),
}

/// One keyframe of a camera path.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// The frame it holds at.
    pub frame: u32,
    /// Degrees about +y.
    pub azimuth: f64,
    /// Degrees above the xz plane.
    pub elevation: f64,
    /// Distance from the volume's centre, world units.
    pub distance: f64,
}

/// The camera of a scene.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum CameraSpec {
    /// One orbit camera; with `frames` > 1 it turns 1° about y per frame (as `render --frames`).
    Orbit {
        /// Degrees about +y.
        azimuth: f64,
        /// Degrees above the xz plane.
        elevation: f64,
        /// Distance, world units.
        distance: f64,
    },
    /// Keyframes, interpolated linearly in azimuth, elevation and distance.
    Path {
        /// At least one, in increasing frame order.
        keyframes: Vec<Keyframe>,
    },
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
}

/// Why a scene could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file cannot be read.
    #[error("{}: cannot read the scene: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
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
    /// Reads and checks the scene file `path`.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
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
            && !(1..=100_000).contains(&frames)
        {
            return Err(field("frames", format!("{frames}: expected 1..=100000")));
        }
        if let Some(camera) = &doc.camera {
            check_camera(camera).map_err(|m| field("camera", m))?;
        }
        let volume = match doc.volume {
            VolumeSource::File(p) => VolumeSource::File(resolve(&p).display().to_string()),
            other => other,
        };
        let transfer_function = doc.transfer_function.map(|t| match t {
            TfSource::File(p) => TfSource::File(resolve(&p).display().to_string()),
            other => other,
        });
        Ok(Scene {
            path: path.to_path_buf(),
            graph: doc.graph.as_deref().map(resolve),
            volume,
            transfer_function,
            camera: doc.camera,
            viewport: doc.viewport,
            effects: doc.effects,
            precision: doc.precision,
            opacity_reference: doc.opacity_reference,
            frames: doc.frames,
        })
    }

    /// The frames a render of this scene draws (a path's length, else `frames` or 1).
    pub fn frame_count(&self) -> u32 {
        match (&self.camera, self.frames) {
            (_, Some(f)) => f,
            (Some(CameraSpec::Path { keyframes }), None) => keyframes.last().map_or(1, |k| k.frame + 1),
            _ => 1,
        }
    }
}

fn check_camera(camera: &CameraSpec) -> Result<(), String> {
    let finite = |a: f64, e: f64, d: f64| a.is_finite() && e.is_finite() && d.is_finite() && d > 0.0;
    match camera {
        CameraSpec::Orbit { azimuth, elevation, distance } => {
            if !finite(*azimuth, *elevation, *distance) {
                return Err("azimuth and elevation must be finite degrees and distance a positive length".into());
            }
        }
        CameraSpec::Path { keyframes } => {
            if keyframes.is_empty() {
                return Err("a Path needs at least one keyframe".into());
            }
            for (i, k) in keyframes.iter().enumerate() {
                if !finite(k.azimuth, k.elevation, k.distance) {
                    return Err(format!("keyframe {i}: finite degrees and a positive distance, please"));
                }
                if i > 0 && k.frame <= keyframes[i - 1].frame {
                    return Err(format!(
                        "keyframe {i}: frame {} does not come after {}",
                        k.frame,
                        keyframes[i - 1].frame
                    ));
                }
            }
        }
    }
    Ok(())
}

impl CameraSpec {
    /// The orbit camera of frame `index`: an orbit turns 1° about y per frame (as `render
    /// --frames`); a path interpolates its keyframes linearly and holds the ends.
    pub fn at(&self, index: u32) -> OrbitCamera {
        match self {
            CameraSpec::Orbit { azimuth, elevation, distance } => OrbitCamera {
                azimuth_deg: azimuth + index as f64,
                elevation_deg: *elevation,
                distance: *distance,
                ..OrbitCamera::default()
            },
            CameraSpec::Path { keyframes } => {
                let orbit = |k: &Keyframe| (k.azimuth, k.elevation, k.distance);
                let (a, e, d) = match keyframes.iter().position(|k| k.frame >= index) {
                    None => keyframes.last().map_or((30.0, 20.0, 3.2), orbit),
                    Some(0) => orbit(&keyframes[0]),
                    Some(i) => {
                        let (k0, k1) = (&keyframes[i - 1], &keyframes[i]);
                        let t = (index - k0.frame) as f64 / (k1.frame - k0.frame) as f64;
                        let lerp = |x: f64, y: f64| x + (y - x) * t;
                        (lerp(k0.azimuth, k1.azimuth), lerp(k0.elevation, k1.elevation), lerp(k0.distance, k1.distance))
                    }
                };
                OrbitCamera { azimuth_deg: a, elevation_deg: e, distance: d, ..OrbitCamera::default() }
            }
        }
    }
}

/// A scene's volume, loaded: (volume, whether it is generated, notes for stderr). The error
/// names the scene file and field.
pub fn load_volume(
    scene: &Scene,
    raw: &volgraph_accel::load::RawOptions,
) -> anyhow::Result<(volgraph_accel::volume::Volume, bool, Vec<String>)> {
    let at = |e: anyhow::Error| anyhow::anyhow!("{}: volume: {e:#}", scene.path.display());
    match &scene.volume {
        VolumeSource::File(p) => {
            let (v, notes) = crate::inputs::volume(Some(&PathBuf::from(p)), raw).map_err(at)?;
            Ok((v, false, notes))
        }
        VolumeSource::Dataset(name) => {
            let loaded = volgraph_accel::data_dir::load_dataset(name).map_err(|e| at(anyhow::anyhow!("{e}")))?;
            Ok((loaded.volume, false, Vec::new()))
        }
        VolumeSource::Generated(name) => {
            let v = crate::bench_graphs::dataset::load_generated(name).map_err(at)?;
            Ok((v, true, Vec::new()))
        }
    }
}

/// A scene's transfer function for `volume`: a file (also returned, so a viewer can watch it),
/// a preset, or the default fitted to the data; with notes for stderr.
pub fn load_transfer_function(
    scene: &Scene,
    tf_map: Option<&str>,
    volume: &volgraph_accel::volume::Volume,
    generated: bool,
) -> anyhow::Result<(volgraph_accel::transfer_function::TransferFunction, Option<PathBuf>, Vec<String>)> {
    use volgraph_accel::transfer_function::{Preset, TransferFunction};
    match &scene.transfer_function {
        Some(source @ (TfSource::File(_) | TfSource::Data(_))) => {
            let path = match source {
                TfSource::Data(name) => volgraph_accel::data_dir::data_dir().join("tf").join(format!("{name}.ron")),
                TfSource::File(p) | TfSource::Preset(p) => PathBuf::from(p),
            };
            let (tf, notes) = crate::inputs::transfer_function(Some(&path), tf_map, volume, generated)
                .map_err(|e| anyhow::anyhow!("{}: transfer_function: {e:#}", scene.path.display()))?;
            Ok((tf, Some(path), notes))
        }
        Some(TfSource::Preset(name)) => {
            let preset = Preset::from_name(name).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: transfer_function: Preset(\"{name}\") is not a preset; use default, opaque or sparse, or File(\"path.ron\")",
                    scene.path.display()
                )
            })?;
            let (lo, hi) = volume.value_range;
            Ok((TransferFunction::preset(preset, (lo, if hi > lo { hi } else { lo + 1.0 })), None, Vec::new()))
        }
        None => {
            let (tf, notes) = crate::inputs::transfer_function(None, tf_map, volume, generated)?;
            Ok((tf, None, notes))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        Scene::from_str(text, Path::new("scenes/test.ron"))
    }

    #[test]
    fn a_full_scene_resolves_paths_against_its_folder() {
        let s = parse(
            r#"Scene(graph: "../graphs/modern/fastest.ron", volume: File("v.raw"),
                transfer_function: File("tf.ron"), camera: Orbit(azimuth: 10, elevation: 5, distance: 2.5),
                viewport: (64, 32), effects: ["shading", "jitter"], precision: F32, opacity_reference: World)"#,
        )
        .expect("parses");
        assert_eq!(s.graph, Some(PathBuf::from("scenes/../graphs/modern/fastest.ron")));
        assert_eq!(s.volume, VolumeSource::File("scenes/v.raw".into()));
        assert_eq!(s.transfer_function, Some(TfSource::File("scenes/tf.ron".into())));
        assert_eq!(
            (s.viewport, s.precision, s.opacity_reference),
            (Some((64, 32)), Some(Precision::F32), OpacityReference::World)
        );
        assert_eq!(s.frame_count(), 1);
    }

    #[test]
    fn a_camera_path_interpolates_and_sets_the_frame_count() {
        let s = parse(
            r#"Scene(volume: Generated("ml32"), camera: Path(keyframes: [
                (frame: 0, azimuth: 0, elevation: 0, distance: 3),
                (frame: 10, azimuth: 90, elevation: 20, distance: 2)]))"#,
        )
        .expect("parses");
        assert_eq!(s.frame_count(), 11);
        let cam = s.camera.as_ref().expect("a camera");
        let mid = cam.at(5);
        assert!((mid.azimuth_deg - 45.0).abs() < 1e-12 && (mid.distance - 2.5).abs() < 1e-12);
        assert_eq!(cam.at(20).azimuth_deg, 90.0);
    }

    #[test]
    fn mistakes_name_the_line_or_field_and_the_fix() {
        let err =
            parse("Scene(volume: Generated(\"ml32\"), effects: [\"shadng\"])").expect_err("bad effect").to_string();
        assert!(err.contains("effects: \"shadng\" is not an effect") && err.contains("shading"), "{err}");
        let err = parse("Scene(\n  volume: Generated(\"ml32\"),\n  colour: 3)").expect_err("unknown field").to_string();
        assert!(err.starts_with("scenes/test.ron:3:"), "{err}");
        let err = parse("Scene(volume: Generated(\"ml32\"), viewport: (0, 5))").expect_err("bad size").to_string();
        assert!(err.contains("viewport: (0, 5)"), "{err}");
        let err =
            parse("Scene(volume: Generated(\"ml32\"), camera: Path(keyframes: []))").expect_err("empty").to_string();
        assert!(err.contains("camera: a Path needs at least one keyframe"), "{err}");
    }
}
