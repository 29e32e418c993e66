//! The viewer's "save view": the view on screen written as a scene file.

use std::path::{Path, PathBuf};

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::Cuts;
use volgraph_core::Precision;
use volgraph_core::runtime::OpacityReference;

use super::{Scene, TfSource, VolumeOptions, VolumeSource};

/// What the viewer's "save view" keeps: everything `render --scene` needs to draw the view on
/// screen again, pixel for pixel.
#[derive(Clone, Debug)]
pub struct SavedView {
    /// The graph file, or a built-in graph's name.
    pub graph: PathBuf,
    /// The volume.
    pub volume: VolumeSource,
    /// How the volume was read (`--series`, `--frame`, `--dims`, `--spacing`, ...).
    pub volume_options: VolumeOptions,
    /// The transfer function: a file (or a built-in TF's name), a preset, a data-folder TF;
    /// `None`: fitted to the data (as it was).
    pub transfer_function: Option<TfSource>,
    /// The camera on screen.
    pub camera: OrbitCamera,
    /// The viewport.
    pub viewport: (u32, u32),
    /// Effects that are on.
    pub effects: Vec<String>,
    /// Float target precision.
    pub precision: Option<Precision>,
    /// What the TF's opacity is per.
    pub opacity_reference: OpacityReference,
    /// The crop box and clip planes.
    pub cuts: Cuts,
    /// The lights.
    pub lights: volgraph_accel::light::Lights,
    /// The environment map's file.
    pub environment: Option<PathBuf>,
}

impl SavedView {
    /// The scene file's text. Paths of files are written absolute, so the file may be moved; a
    /// built-in graph's or TF's name stays a name (a scene resolves it as the command line does).
    pub fn to_ron(&self) -> String {
        let quote = |p: &Path| {
            let p = std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
            format!("{:?}", p.display().to_string())
        };
        let mut out = String::from(
            "// Saved by volgraph view (\"save view\"): `volgraph render --scene FILE` draws this view.\nScene(\n",
        );
        out += &format!("    graph: {},\n", quote(&self.graph));
        out += &format!(
            "    volume: {},\n",
            match &self.volume {
                VolumeSource::File(p) => format!("File({})", quote(Path::new(p))),
                VolumeSource::Dataset(n) => format!("Dataset({n:?})"),
                VolumeSource::Generated(n) => format!("Generated({n:?})"),
            }
        );
        let o = &self.volume_options;
        if !o.is_empty() {
            let mut fields = Vec::new();
            if let Some(series) = &o.series {
                fields.push(format!("series: {series:?}"));
            }
            if let Some(frame) = o.frame {
                fields.push(format!("frame: {frame}"));
            }
            if let Some((x, y, z)) = o.dims {
                fields.push(format!("dims: ({x}, {y}, {z})"));
            }
            if let Some(dtype) = &o.dtype {
                fields.push(format!("dtype: {dtype:?}"));
            }
            if o.big_endian {
                fields.push("big_endian: true".to_string());
            }
            if let Some((x, y, z)) = o.spacing {
                fields.push(format!("spacing: ({x:?}, {y:?}, {z:?})"));
            }
            out += &format!("    volume_options: ({}),\n", fields.join(", "));
        }
        match &self.transfer_function {
            Some(TfSource::File(p)) => out += &format!("    transfer_function: File({}),\n", quote(Path::new(p))),
            Some(TfSource::Preset(n)) => out += &format!("    transfer_function: Preset({n:?}),\n"),
            Some(TfSource::Data(n)) => out += &format!("    transfer_function: Data({n:?}),\n"),
            Some(TfSource::BuiltIn(n)) => {
                out += &format!("    transfer_function: File({:?}),\n", format!("graphs/tf/{n}.ron"));
            }
            None => {}
        }
        let c = &self.camera;
        // Rust's shortest round-trip formatting: the file reads back the same f64.
        let up = match c.up {
            volgraph_accel::camera::CameraUp::Y => "",
            volgraph_accel::camera::CameraUp::Patient => ", up: Patient",
        };
        out += &format!(
            "    camera: Orbit(azimuth: {:?}, elevation: {:?}, distance: {:?}, target: ({:?}, {:?}, {:?}){up}),\n",
            c.azimuth_deg, c.elevation_deg, c.distance, c.target[0], c.target[1], c.target[2]
        );
        out += &format!("    viewport: ({}, {}),\n", self.viewport.0, self.viewport.1);
        out += &format!("    effects: {:?},\n", self.effects);
        if let Some(p) = self.precision {
            out += &format!("    precision: {p:?},\n");
        }
        out += &format!("    opacity_reference: {:?},\n", self.opacity_reference);
        if let Some(b) = self.cuts.crop() {
            out += &format!(
                "    crop: ({:?}, {:?}, {:?}, {:?}, {:?}, {:?}),\n",
                b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z
            );
        }
        let planes: Vec<String> = self
            .cuts
            .planes()
            .map(|p| format!("({:?}, {:?}, {:?}, {:?})", p.normal.x, p.normal.y, p.normal.z, p.offset))
            .collect();
        if !planes.is_empty() {
            out += &format!("    clip: [{}],\n", planes.join(", "));
        }
        let lights: Vec<String> = self
            .lights
            .as_slice()
            .iter()
            .map(|light| match *light {
                volgraph_accel::light::Light::Directional { azimuth_deg, elevation_deg } => {
                    format!("Directional(azimuth_deg: {azimuth_deg:?}, elevation_deg: {elevation_deg:?})")
                }
                volgraph_accel::light::Light::Point { x, y, z } => format!("Point(x: {x:?}, y: {y:?}, z: {z:?})"),
                volgraph_accel::light::Light::Headlight => "Headlight".to_string(),
            })
            .collect();
        // The headlight alone is what no `lights:` means.
        if self.lights != volgraph_accel::light::Lights::default() {
            out += &format!("    lights: [{}],\n", lights.join(", "));
        }
        if let Some(path) = &self.environment {
            out += &format!("    environment: {},\n", quote(path));
        }
        out += ")\n";
        out
    }

    /// Writes the scene to `path` (through a temporary file and a rename, so a reader never
    /// sees half a file) and reads it back as a check.
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        crate::atomic_write::write_atomically(path, &self.to_ron())?;
        Scene::load(path).map_err(|e| anyhow::anyhow!("the saved scene does not read back: {e}"))?;
        Ok(())
    }
}

#[cfg(test)]
mod saved_view_tests {
    use super::*;
    use glam::DVec3;
    use volgraph_accel::cuts::{ClipPlane, CropBox};

    /// "Save view" writes a scene that reads back to the same camera, cuts, light, environment
    /// map and effects,
    /// to the last bit of every f64.
    #[test]
    fn a_saved_view_reads_back_exactly() {
        let cuts = Cuts::new(
            Some(CropBox::new(DVec3::new(0.1, 0.0, 1.0 / 3.0), DVec3::new(0.9, 0.5, 1.0)).expect("box")),
            &[ClipPlane::new(DVec3::new(-1.0, 0.25, 0.0), -0.3).expect("plane")],
        )
        .expect("cuts");
        let camera = OrbitCamera {
            azimuth_deg: 37.123456789,
            elevation_deg: -12.5,
            distance: 2.0 / 3.0,
            target: [0.1, -0.2, 0.3],
            ..OrbitCamera::default()
        };
        let view = SavedView {
            graph: PathBuf::from("/nonexistent/graph.ron"),
            volume: VolumeSource::Generated("ml64".into()),
            volume_options: VolumeOptions { spacing: Some((1.0, 0.1, 1.0 / 3.0)), ..Default::default() },
            transfer_function: None,
            camera,
            viewport: (320, 200),
            effects: vec!["shading".into()],
            precision: Some(Precision::F16),
            opacity_reference: OpacityReference::World,
            cuts,
            lights: volgraph_accel::light::Light::Directional { azimuth_deg: -33.3, elevation_deg: 1.0 / 7.0 }.into(),
            environment: Some(PathBuf::from("/nonexistent/sky.exr")),
        };
        let scene = Scene::from_str(&view.to_ron(), Path::new("/tmp/x.scene.ron")).expect("reads back");
        assert_eq!(scene.cuts, cuts);
        assert_eq!(scene.lights, view.lights);
        assert_eq!(scene.environment, view.environment);
        // A point light beside a directional one and the headlight is written back as they are.
        use volgraph_accel::light::{Light, Lights};
        let three =
            Lights::new(&[Light::Point { x: 0.25, y: 1.0 / 3.0, z: -2.0 }, view.lights.key(), Light::Headlight])
                .expect("three lights");
        let point = SavedView { lights: three, ..view.clone() };
        let scene = Scene::from_str(&point.to_ron(), Path::new("/tmp/x.scene.ron")).expect("reads back");
        assert_eq!(scene.lights, three);
        assert_eq!(scene.volume_options.spacing, Some((1.0, 0.1, 1.0 / 3.0)));
        assert_eq!(scene.viewport, Some((320, 200)));
        assert_eq!(scene.effects, vec!["shading".to_string()]);
        assert_eq!(scene.precision, Some(Precision::F16));
        assert_eq!(scene.opacity_reference, OpacityReference::World);
        let back = scene.camera.expect("a camera").at(0);
        assert_eq!(
            (back.azimuth_deg, back.elevation_deg, back.distance, back.target),
            (37.123456789, -12.5, 2.0 / 3.0, [0.1, -0.2, 0.3])
        );
        assert_eq!(back.up, volgraph_accel::camera::CameraUp::Y);
        // A patient view (superior up) is written back as one.
        let patient = SavedView {
            camera: OrbitCamera { up: volgraph_accel::camera::CameraUp::Patient, ..camera },
            ..view.clone()
        };
        let text = patient.to_ron();
        assert!(text.contains("up: Patient"), "{text}");
        let scene = Scene::from_str(&text, Path::new("/tmp/x.scene.ron")).expect("reads back");
        assert_eq!(scene.camera.expect("a camera").at(0), patient.camera);
    }
}
