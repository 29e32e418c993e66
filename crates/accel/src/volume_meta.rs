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

/// A clip plane of the volume's fractions — it keeps the points `f` with `n · f ≥ d` — as the
/// patient frame sees it, for a volume whose patient box has its low corner at `corner` and its
/// extent `extent` (mm, [`VolumeMeta::patient_box`]): the plane's unit normal in LPS, pointing
/// to the side it keeps, and its signed distance (mm) from the patient origin along that normal.
/// `None` for a zero normal. (With `f = (p − corner) / extent` the plane is `m · p = d + Σ nₐcₐ/eₐ`,
/// `m = n / extent`.)
pub fn patient_plane(normal: DVec3, offset: f64, corner: DVec3, extent: DVec3) -> Option<(DVec3, f64)> {
    let m = normal / extent;
    let length = m.length();
    (length > 0.0 && length.is_finite())
        .then(|| (m / length, (offset + (normal * corner / extent).element_sum()) / length))
}

/// A direction by the sides it points to, its largest components first: `L 0.71 · S 0.71`;
/// components under 0.005 are left out, a direction along one axis is its side alone (`S`).
pub fn direction_label(direction: DVec3) -> String {
    let mut parts: Vec<(f64, String)> = (0..3)
        .filter(|&a| direction[a].abs() >= 0.005)
        .map(|a| {
            let side = side_label(a, direction[a]);
            let letter = side.split(' ').next().unwrap_or_default().to_string();
            (direction[a].abs(), format!("{letter} {:.2}", direction[a].abs()))
        })
        .collect();
    parts.sort_by(|a, b| b.0.total_cmp(&a.0));
    match parts.as_slice() {
        [(_, one)] => one.split(' ').next().unwrap_or_default().to_string(),
        _ => parts.into_iter().map(|(_, p)| p).collect::<Vec<_>>().join(" · "),
    }
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

    #[test]
    fn a_clip_plane_of_fractions_is_a_patient_plane_in_mm() {
        // A box from R 100 · A 50 · I 20 mm, 200 × 100 × 40 mm.
        let (corner, extent) = (DVec3::new(-100.0, -50.0, -20.0), DVec3::new(200.0, 100.0, 40.0));
        // Keep x fraction ≥ 0.6: toward L of x = −100 + 0.6 · 200 = L 20 mm.
        let (n, d) = patient_plane(DVec3::X, 0.6, corner, extent).expect("a plane");
        assert!((n - DVec3::X).length() < 1e-12 && (d - 20.0).abs() < 1e-9, "{n} {d}");
        assert_eq!(direction_label(n), "L");
        // Keep −z ≥ −0.25, z fraction ≤ 0.25: toward I of z = −20 + 10 = I 10 mm; the distance
        // along the inferior normal is +10.
        let (n, d) = patient_plane(-DVec3::Z, -0.25, corner, extent).expect("a plane");
        assert!((n + DVec3::Z).length() < 1e-12 && (d - 10.0).abs() < 1e-9, "{n} {d}");
        assert_eq!(direction_label(n), "I");
        // An oblique plane of fractions is oblique in mm too, turned by the box's aspect; every
        // point of it satisfies both forms.
        let (n, d) = patient_plane(DVec3::new(1.0, 0.0, 1.0), 1.0, corner, extent).expect("a plane");
        let f = DVec3::new(0.3, 0.5, 0.7); // on the fraction plane: 0.3 + 0.7 = 1
        assert!((n.dot(corner + f * extent) - d).abs() < 1e-9);
        assert_eq!(direction_label(n), "S 0.98 · L 0.20");
        assert_eq!(patient_plane(DVec3::ZERO, 0.5, corner, extent), None);
    }

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
