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
}
