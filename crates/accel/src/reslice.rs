//! Multi-planar reformatting, in f64: the axial, coronal and sagittal slices a clinical viewer
//! shows beside its 3D view, resampled from the volume with the renderer's own trilinear
//! filter ([`Volume::sample_trilinear`]) and mapped to grey through a window (DICOM's
//! WindowCenter/WindowWidth, in data units). The GPU pass `reslice`
//! (`crates/passes/src/reslice.rs`, `shaders/reslice.wgsl`) computes the same image; this is its
//! reference.
//!
//! The panes follow the radiological convention of the clinical tools (3D Slicer, ITK-SNAP):
//! for a volume in the patient frame (the loaders lay its x, y, z along L, P, S) an axial slice
//! is seen from the feet — the patient's right on the pane's left, anterior up; a coronal one
//! from the front — right on the left, superior up; a sagittal one from the patient's left —
//! anterior on the left, superior up. A volume outside the patient frame is shown the same way
//! by its index axes. The slice keeps its physical aspect (voxel spacing) and is centred in the
//! pane, which shows nothing beside it.

use glam::{DVec2, DVec3};

use crate::fusion::{FrameMismatch, TextureMap, in_box};
use crate::labels::sample::{LabelFilter, sample_label};
use crate::volume::Volume;
use crate::volume_meta::Window;

/// Which of the three standard planes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SliceAxis {
    /// Normal to z (superior–inferior in the patient frame).
    Axial,
    /// Normal to y (anterior–posterior).
    Coronal,
    /// Normal to x (left–right).
    Sagittal,
}

impl SliceAxis {
    /// The three, in the order the viewer lays out their panes.
    pub const ALL: [SliceAxis; 3] = [SliceAxis::Axial, SliceAxis::Coronal, SliceAxis::Sagittal];

    /// Its name, as graph files and the viewer write it.
    pub fn name(self) -> &'static str {
        match self {
            SliceAxis::Axial => "axial",
            SliceAxis::Coronal => "coronal",
            SliceAxis::Sagittal => "sagittal",
        }
    }

    /// The volume axis the plane is normal to: z, y or x.
    pub fn normal(self) -> usize {
        match self {
            SliceAxis::Axial => 2,
            SliceAxis::Coronal => 1,
            SliceAxis::Sagittal => 0,
        }
    }

    /// The volume axes along the pane's columns (left to right) and rows (top to bottom), each
    /// with whether it runs backwards: axial (+x, +y), coronal (+x, −z), sagittal (+y, −z).
    pub fn pane_axes(self) -> [(usize, bool); 2] {
        match self {
            SliceAxis::Axial => [(0, false), (1, false)],
            SliceAxis::Coronal => [(0, false), (2, true)],
            SliceAxis::Sagittal => [(1, false), (2, true)],
        }
    }
}

/// Where a slice lies in its pane: the rectangle (pixels, origin top left) the slice fills,
/// the largest of the slice's physical aspect centred in the pane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaneFit {
    /// Top-left corner.
    pub origin: DVec2,
    /// Width and height.
    pub size: DVec2,
}

impl PaneFit {
    /// The fit of `axis`'s slice of a volume of `dims` voxels of `spacing` in a pane of `pane`
    /// pixels.
    pub fn of(axis: SliceAxis, dims: glam::UVec3, spacing: DVec3, pane: (u32, u32)) -> Self {
        let extent = dims.as_dvec3() * spacing;
        let [(c, _), (r, _)] = axis.pane_axes();
        let physical = DVec2::new(extent[c], extent[r]);
        let pane = DVec2::new(pane.0 as f64, pane.1 as f64);
        let scale = (pane.x / physical.x).min(pane.y / physical.y);
        let size = physical * scale;
        Self { origin: (pane - size) * 0.5, size }
    }

    /// The slice's (column, row) fractions in [0, 1]² at pane point `p` (pixels); outside [0, 1]
    /// beside the slice.
    pub fn fractions(&self, p: DVec2) -> DVec2 {
        (p - self.origin) / self.size
    }

    /// The pane point (pixels) of slice fractions `f`.
    pub fn point(&self, f: DVec2) -> DVec2 {
        self.origin + f * self.size
    }
}

/// A slice: its plane and its position along the normal, a texture coordinate (0 at the
/// volume's first face, 1 at its last; voxel centres at `(k + 0.5) / n`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlicePlane {
    /// Which plane.
    pub axis: SliceAxis,
    /// Texture coordinate along `axis.normal()`.
    pub position: f64,
}

impl SlicePlane {
    /// The texture point (`[0, 1]³`) shown at pane point `p` (pixels) under `fit`, `None` beside
    /// the slice.
    pub fn texture_point(&self, fit: &PaneFit, p: DVec2) -> Option<DVec3> {
        let f = fit.fractions(p);
        let inside = (0.0..=1.0).contains(&f.x) && (0.0..=1.0).contains(&f.y);
        inside.then(|| self.extended_point(fit, p))
    }

    /// [`Self::texture_point`] extended past the slice's edges: an affine map of the pane point
    /// (the GPU pass evaluates it from its value at three points).
    pub fn extended_point(&self, fit: &PaneFit, p: DVec2) -> DVec3 {
        let f = fit.fractions(p);
        let [(c, c_back), (r, r_back)] = self.axis.pane_axes();
        let mut u = DVec3::ZERO;
        u[c] = if c_back { 1.0 - f.x } else { f.x };
        u[r] = if r_back { 1.0 - f.y } else { f.y };
        u[self.axis.normal()] = self.position;
        u
    }

    /// The pane point (pixels) where texture point `u` projects onto this slice under `fit`:
    /// where the viewer draws the crosshair of the other two planes.
    pub fn pane_point(&self, fit: &PaneFit, u: DVec3) -> DVec2 {
        let [(c, c_back), (r, r_back)] = self.axis.pane_axes();
        let f = DVec2::new(if c_back { 1.0 - u[c] } else { u[c] }, if r_back { 1.0 - u[r] } else { u[r] });
        fit.point(f)
    }
}

/// A window mapped to the normalized values the renderer samples: grey 0 at `low`, 1 at `high`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalizedWindow {
    /// The normalized value shown black.
    pub low: f64,
    /// The normalized value shown white.
    pub high: f64,
}

impl NormalizedWindow {
    /// `window` (data units) over `volume`'s normalized values ([`Volume::normalized`]); a width
    /// under a millionth of the value range is taken as that (a step, not a division by zero).
    pub fn of(window: Window, volume: &Volume) -> Self {
        let (v0, v1) = volume.value_range;
        let span = if v1 > v0 { v1 - v0 } else { 1.0 };
        let width = window.width.abs().max(span * 1e-6);
        Self { low: (window.center - width / 2.0 - v0) / span, high: (window.center + width / 2.0 - v0) / span }
    }

    /// The grey level of normalized value `s`: 0 below the window, 1 above, linear between.
    pub fn grey(&self, s: f64) -> f64 {
        ((s - self.low) / (self.high - self.low)).clamp(0.0, 1.0)
    }
}

/// The window a slice shows by default: the file's (DICOM WindowCenter/Width, NIfTI
/// cal_min/cal_max), else the whole value range.
pub fn default_window(volume: &Volume) -> Window {
    volume.meta.window.unwrap_or_else(|| {
        let (v0, v1) = volume.value_range;
        Window { center: 0.5 * (v0 + v1), width: (v1 - v0).max(f64::MIN_POSITIVE) }
    })
}

/// The slice `plane` of `volume` in a pane of `pane` pixels through `window`: per pixel (rows
/// from the top) the grey level at its centre, `None` beside the slice.
pub fn reslice(volume: &Volume, plane: SlicePlane, window: Window, pane: (u32, u32)) -> Vec<Option<f64>> {
    let fit = PaneFit::of(plane.axis, volume.dims, volume.spacing, pane);
    let window = NormalizedWindow::of(window, volume);
    let (w, h) = pane;
    (0..h)
        .flat_map(|y| (0..w).map(move |x| DVec2::new(x as f64 + 0.5, y as f64 + 0.5)))
        .map(|p| plane.texture_point(&fit, p).map(|u| window.grey(volume.sample_trilinear(u))))
        .collect()
}

/// A label map over a slice: the map (in the slice volume's patient frame, on any grid of it),
/// its table as a graph's `LabelTable` input holds it (colour and opacity by label value, 0
/// where hidden; `LabelTable::lut`) and how strongly a label's colour covers the grey.
pub struct LabelOverlay<'a> {
    /// The label map.
    pub labels: &'a Volume,
    /// Colour (the table's bytes / 255, display values) and opacity by label value.
    pub table: &'a [[f32; 4]],
    /// The cover of a label of opacity 1.
    pub opacity: f64,
}

impl LabelOverlay<'_> {
    /// The colour at slice volume texture point `u` through `map` (the slice volume's texture
    /// space to the map's): the nearest voxel's label — clinical viewers show a segmentation's
    /// voxels as they are — and its table colour with the cover `opacity × its opacity`;
    /// `None` outside the map or where its label is hidden or beyond the table.
    pub fn colour(&self, map: &TextureMap, u: DVec3) -> Option<([f64; 3], f64)> {
        let v = map.apply(u);
        if !in_box(v) {
            return None;
        }
        let (label, _) = sample_label(self.labels, v, LabelFilter::Nearest);
        let [r, g, b, a] = *self.table.get(label as usize)?;
        let cover = self.opacity * f64::from(a);
        (cover > 0.0).then_some(([f64::from(r), f64::from(g), f64::from(b)], cover))
    }
}

/// [`reslice`] with a label map over it: per pixel the grey (as a colour) with the label's
/// colour blended over it, `None` beside the slice.
pub fn reslice_with_labels(
    volume: &Volume,
    plane: SlicePlane,
    window: Window,
    pane: (u32, u32),
    overlay: &LabelOverlay<'_>,
) -> Result<Vec<Option<[f64; 3]>>, FrameMismatch> {
    let map = TextureMap::between(volume, overlay.labels)?;
    let fit = PaneFit::of(plane.axis, volume.dims, volume.spacing, pane);
    let window = NormalizedWindow::of(window, volume);
    let (w, h) = pane;
    Ok((0..h)
        .flat_map(|y| (0..w).map(move |x| DVec2::new(x as f64 + 0.5, y as f64 + 0.5)))
        .map(|p| {
            let u = plane.texture_point(&fit, p)?;
            let grey = window.grey(volume.sample_trilinear(u));
            Some(match overlay.colour(&map, u) {
                Some((c, a)) => c.map(|c| grey * (1.0 - a) + c * a),
                None => [grey; 3],
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Volume, VoxelData};
    use glam::UVec3;

    /// A volume whose value is its x index + 10·y + 100·z (u16), spacing (1, 2, 3).
    fn ramp() -> Volume {
        let dims = UVec3::new(4, 5, 6);
        let mut data = Vec::new();
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    data.push((x + 10 * y + 100 * z) as u16);
                }
            }
        }
        let mut v = Volume::new("ramp", dims, DVec3::new(1.0, 2.0, 3.0), VoxelData::U16(data));
        v.value_range = (0.0, 1000.0);
        v
    }

    #[test]
    fn a_label_map_colours_its_voxels_over_the_grey() {
        let v = ramp();
        // Labels on the same grid: 2 where x ≥ 2, else 0 (background, hidden).
        let mut labels = v.clone();
        let dims = v.dims;
        labels.data =
            VoxelData::U16((0..dims.x * dims.y * dims.z).map(|i| if i % dims.x >= 2 { 2 } else { 0 }).collect());
        labels.value_range = (0.0, 65535.0);
        let table = [[0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]];
        let overlay = LabelOverlay { labels: &labels, table: &table, opacity: 0.5 };
        let plane = SlicePlane { axis: SliceAxis::Axial, position: 2.5 / 6.0 };
        let window = Window { center: 500.0, width: 1000.0 };
        let plain = reslice(&v, plane, window, (4, 10));
        let with = reslice_with_labels(&v, plane, window, (4, 10), &overlay).expect("one frame");
        for (i, (g, c)) in plain.iter().zip(&with).enumerate() {
            let (g, c) = (g.expect("on the slice"), c.expect("on the slice"));
            if i % 4 >= 2 {
                // Half red over the grey.
                assert!((c[0] - (0.5 * g + 0.5)).abs() < 1e-12 && (c[1] - 0.5 * g).abs() < 1e-12, "{i}: {c:?}");
            } else {
                assert_eq!(c, [g; 3], "{i}: the background is hidden");
            }
        }
    }

    #[test]
    fn a_slice_keeps_its_physical_aspect_centred_in_its_pane() {
        let v = ramp();
        // Axial: 4 mm wide (x), 10 mm tall (y): in a 100×100 pane 40×100, centred.
        let fit = PaneFit::of(SliceAxis::Axial, v.dims, v.spacing, (100, 100));
        assert_eq!(fit.size, DVec2::new(40.0, 100.0));
        assert_eq!(fit.origin, DVec2::new(30.0, 0.0));
        // Sagittal: y (10 mm) across, z (18 mm) down.
        let fit = PaneFit::of(SliceAxis::Sagittal, v.dims, v.spacing, (90, 90));
        assert_eq!(fit.size, DVec2::new(50.0, 90.0));
    }

    #[test]
    fn panes_are_oriented_as_the_clinical_tools_show_them() {
        let fit = PaneFit { origin: DVec2::ZERO, size: DVec2::ONE };
        let top_left = DVec2::new(0.0, 0.0);
        // Axial, seen from the feet: top left is the patient's right (x 0) and anterior (y 0).
        let axial = SlicePlane { axis: SliceAxis::Axial, position: 0.25 };
        assert_eq!(axial.texture_point(&fit, top_left), Some(DVec3::new(0.0, 0.0, 0.25)));
        // Coronal and sagittal: superior (z 1) at the top.
        let coronal = SlicePlane { axis: SliceAxis::Coronal, position: 0.5 };
        assert_eq!(coronal.texture_point(&fit, top_left), Some(DVec3::new(0.0, 0.5, 1.0)));
        let sagittal = SlicePlane { axis: SliceAxis::Sagittal, position: 0.75 };
        // Sagittal: anterior (y 0) on the left.
        assert_eq!(sagittal.texture_point(&fit, top_left), Some(DVec3::new(0.75, 0.0, 1.0)));
        assert_eq!(sagittal.texture_point(&fit, DVec2::new(1.5, 0.5)), None);
        // The crosshair point maps back where it was picked.
        let u = DVec3::new(0.2, 0.3, 0.4);
        for axis in SliceAxis::ALL {
            let plane = SlicePlane { axis, position: u[axis.normal()] };
            let p = plane.pane_point(&fit, u);
            assert!((plane.texture_point(&fit, p).unwrap() - u).length() < 1e-12, "{axis:?}");
        }
    }

    #[test]
    fn a_window_maps_data_units_to_grey() {
        let v = ramp();
        let w = NormalizedWindow::of(Window { center: 300.0, width: 200.0 }, &v);
        assert!((w.low - 0.2).abs() < 1e-12 && (w.high - 0.4).abs() < 1e-12);
        assert_eq!(w.grey(0.1), 0.0);
        assert_eq!(w.grey(0.5), 1.0);
        assert!((w.grey(0.3) - 0.5).abs() < 1e-12);
        // A zero width is a step at the centre, not a division by zero.
        let step = NormalizedWindow::of(Window { center: 300.0, width: 0.0 }, &v);
        assert_eq!((step.grey(0.2999), step.grey(0.3001)), (0.0, 1.0));
    }

    #[test]
    fn a_slice_at_a_voxel_centre_shows_that_voxel_layer() {
        let v = ramp();
        // Axial slice through z = 2 (texture (2 + 0.5) / 6) in a pane the size of the slice in
        // mm (4 × 10, one pixel per mm): pixel (x, 2y') sits at voxel (x, y).
        let plane = SlicePlane { axis: SliceAxis::Axial, position: 2.5 / 6.0 };
        let window = Window { center: 500.0, width: 1000.0 };
        let image = reslice(&v, plane, window, (4, 10));
        for y in 0..5u32 {
            for x in 0..4u32 {
                // Pixel row 2y + 1's centre lies at y + 0.75 voxels: a quarter toward y + 1,
                // clamped at the last row.
                let fy = if y == 4 { 0.0 } else { 0.25 };
                let expected = (x as f64 + 10.0 * (y as f64 + fy) + 200.0) / 1000.0;
                let got = image[((2 * y + 1) * 4 + x) as usize].unwrap();
                assert!((got - expected).abs() < 1e-12, "({x}, {y}): {got} vs {expected}");
            }
        }
    }
}
