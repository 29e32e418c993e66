//! What a scanner file says about its volume besides the voxels: modality, value units, the
//! window it suggests, how the box's axes lie in the patient, and where it came from. The
//! loaders fill it in; `volgraph info`, the CT presets and `iso_value: Auto` read it.

use glam::DVec3;

/// How the axes of a volume's box lie in the world (`docs/rendering_model.md`, "Patient frame").
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum WorldFrame {
    /// The file gave no orientation: x, y and z are the file's index axes.
    #[default]
    IndexAxes,
    /// DICOM's patient frame: +x towards the patient's left, +y posterior, +z superior. NIfTI's
    /// RAS and NRRD's anatomical spaces are converted to it (as ITK does).
    Lps,
    /// A NRRD space that is not anatomical (`scanner-xyz`, `3D-right-handed`, …), kept as named.
    Named(String),
}

impl WorldFrame {
    /// One line for `volgraph info`.
    pub fn describe(&self) -> String {
        match self {
            WorldFrame::IndexAxes => "index axes (the file gives no orientation)".to_string(),
            WorldFrame::Lps => "LPS: +x left, +y posterior, +z superior (patient frame)".to_string(),
            WorldFrame::Named(name) => format!("the file's space \"{name}\""),
        }
    }
}

/// A DICOM-style display window in data units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Centre (DICOM WindowCenter).
    pub center: f64,
    /// Width (DICOM WindowWidth).
    pub width: f64,
}

/// Everything a file says about a volume besides its voxels and spacing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeMeta {
    /// DICOM Modality (`CT`, `MR`, `PT`, …), when known.
    pub modality: Option<String>,
    /// Units of the voxel values after rescaling: `HU` for CT, else what the file says.
    pub units: Option<String>,
    /// The window the file suggests (DICOM WindowCenter/Width, NIfTI cal_min/cal_max).
    pub window: Option<Window>,
    /// How x, y, z lie in the world.
    pub frame: WorldFrame,
    /// Position of the centre of voxel (0, 0, 0) in the frame (mm), when the file gives one.
    pub origin: Option<DVec3>,
    /// Series description (DICOM SeriesDescription, NIfTI descrip).
    pub description: Option<String>,
    /// DICOM FrameOfReferenceUID: series of one patient position share it; two that differ do
    /// not lie in one patient frame even where both are LPS (`volgraph_accel::fusion`).
    pub frame_of_reference: Option<String>,
}

impl VolumeMeta {
    /// True for CT data in Hounsfield units, what the `ct-*` presets are written for.
    pub fn is_ct_hu(&self) -> bool {
        self.units.as_deref() == Some("HU")
    }

    /// The patient point (LPS, mm) of a point in voxel coordinates (voxel centres at integer +
    /// 0.5, as `probe::Probe::voxel`): the loaders lay an LPS volume's axes along L, P and S, so
    /// it is the origin (voxel (0, 0, 0)'s centre) plus the index times the spacing. `None` for
    /// a volume outside the patient frame or without an origin.
    pub fn patient_point(&self, voxel: DVec3, spacing: DVec3) -> Option<DVec3> {
        match (&self.frame, self.origin) {
            (WorldFrame::Lps, Some(origin)) => Some(origin + (voxel - DVec3::splat(0.5)) * spacing),
            _ => None,
        }
    }
}

/// A patient point (LPS, mm) as the clinical tools write it: each axis by the side it lies
/// toward — R/L, A/P, I/S — and its distance from the origin, `R 12.5 · P 40.0 · S 7.0 mm`.
pub fn patient_label(point: DVec3) -> String {
    format!("{} · {} · {} mm", side_label(0, point.x), side_label(1, point.y), side_label(2, point.z))
}

/// The sides of LPS axis `axis` (0, 1, 2): toward negative and positive values.
pub const SIDES: [(char, char); 3] = [('R', 'L'), ('A', 'P'), ('I', 'S')];

/// A coordinate `mm` along LPS axis `axis` by its side: `R 12.5`, `S 7.0`.
pub fn side_label(axis: usize, mm: f64) -> String {
    let (negative, positive) = SIDES[axis.min(2)];
    let v = if mm.abs() < 0.05 { 0.0 } else { mm };
    format!("{} {:.1}", if v < 0.0 { negative } else { positive }, v.abs())
}

impl VolumeMeta {
    /// The patient box of a volume in the patient frame: the LPS position (mm) of its low
    /// corner (voxel (0, 0, 0)'s outer face) and its extent along L, P and S (`dims` ×
    /// `spacing`); `None` outside the patient frame. A volume fraction f along axis a lies at
    /// `corner[a] + f · extent[a]`, which the viewer's crop sliders show.
    pub fn patient_box(&self, dims: DVec3, spacing: DVec3) -> Option<(DVec3, DVec3)> {
        let corner = self.patient_point(DVec3::ZERO, spacing)?;
        Some((corner, dims * spacing))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LPS: +x left, +y posterior, +z superior; a negative coordinate is the opposite side.
    #[test]
    fn patient_points_are_labelled_by_side() {
        let meta =
            VolumeMeta { frame: WorldFrame::Lps, origin: Some(DVec3::new(-100.0, 20.0, -5.0)), ..Default::default() };
        // The centre of voxel (10, 0, 4) with 0.5 × 1 × 2.5 mm voxels.
        let p = meta.patient_point(DVec3::new(10.5, 0.5, 4.5), DVec3::new(0.5, 1.0, 2.5)).expect("in LPS");
        assert_eq!(p, DVec3::new(-95.0, 20.0, 5.0));
        assert_eq!(patient_label(p), "R 95.0 · P 20.0 · S 5.0 mm");
        assert_eq!(patient_label(DVec3::new(12.5, -40.0, -7.0)), "L 12.5 · A 40.0 · I 7.0 mm");
        assert_eq!(VolumeMeta::default().patient_point(DVec3::ZERO, DVec3::ONE), None, "index axes have no patient");
        // The box: voxel (0, 0, 0)'s outer corner and dims × spacing.
        let (corner, extent) =
            meta.patient_box(DVec3::new(10.0, 20.0, 4.0), DVec3::new(0.5, 1.0, 2.5)).expect("in LPS");
        assert_eq!((corner, extent), (DVec3::new(-100.25, 19.5, -6.25), DVec3::new(5.0, 20.0, 10.0)));
    }
}
