//! Several volumes in one march (issue "several volumes", items 2 and 3): how a sample of the
//! frame's volume finds the same point in a second volume on another grid of the patient frame,
//! and how the two are classified and combined at that sample — the f64 model the GPU's
//! `shaders/common/fusion.wgsl` follows (`docs/rendering_model.md`, "Several volumes").
//!
//! Rays are marched in the frame volume's texture space (an affine image of the patient frame:
//! axes along LPS, voxel `i`'s centre at `origin + i · spacing`), so a second volume's texture
//! point is `u · scale + offset` per axis ([`TextureMap`]): a PET at 4 mm over a CT at 0.7 mm,
//! shifted by half a voxel, is sampled where it lies. Outside its box a second volume adds
//! nothing (a label map reads background 0).
//!
//! [`Combine`] says what one sample is:
//! - `Labels`: the frame volume is a label map; each sample is its label's colour and opacity
//!   (the label table), sampled without mixing label numbers ([`crate::labels::sample`]).
//! - `Tint`: the scan by its TF, its colour replaced by the label's where a visible label lies
//!   (the label's opacity is how strongly: 1 replaces it).
//! - `Inside`: the scan by its TF, only where a visible label lies ("this organ and its vessels").
//! - `Fuse`: two scalar volumes, each classified by its own TF, combined per sample as two
//!   media in one place: `α = 1 − (1 − α₁)(1 − α₂)`, colour the opacity-weighted mean.
//! - `Add`: channels (napari's and Fiji's additive blending): colours add (no clamp: where
//!   channels overlap the image may exceed 1, as a display saturates it), `α` as in `Fuse`.
//!
//! `Fuse` and `Add` take up to four scalar volumes (a microscope's channels), each by its TF.
//!
//! A third volume, a label map, may lie over a fused pair ([`Overlay`]: PET/CT and the organs
//! segmented on the CT): the pair's sample tinted by the visible label, or kept only inside
//! visible labels, as `Tint` and `Inside` do to one scan.
//!
//! Every opacity is corrected for the step in the frame volume's voxels, as one volume's is.

use glam::DVec3;

use crate::labels::sample::{LabelFilter, sample_label};
use crate::reference::{corrected_alpha, lut_sample, preintegrate};
use crate::volume::Volume;

/// Where the frame volume's texture point `u` lies in another volume's texture space:
/// `u · scale + offset` per axis (both grids' axes lie along the patient frame's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureMap {
    /// Per-axis scale.
    pub scale: DVec3,
    /// Per-axis offset.
    pub offset: DVec3,
}

/// Two volumes that cannot be placed in one frame.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "{first} lies in {first_frame} and {second} in {second_frame}: where one lies in the other is unknown; give \
     files in one frame (a scan and its segmentation from one series)"
)]
pub struct FrameMismatch {
    /// The frame volume's name.
    pub first: String,
    /// Its frame, described.
    pub first_frame: String,
    /// The other volume's name.
    pub second: String,
    /// Its frame, described.
    pub second_frame: String,
}

/// Two DICOM series whose FrameOfReferenceUIDs differ: both say LPS, but of two patient
/// positions (two scans, a patient who moved), so one does not lie where the other says.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "{first} and {second} lie in different DICOM frames of reference ({first_uid} and {second_uid}): their \
     positions do not line up unless registered; register them, or pass --allow-frame-mismatch to show them as \
     their files place them"
)]
pub struct FrameOfReferenceMismatch {
    /// The frame volume's name.
    pub first: String,
    /// Its FrameOfReferenceUID.
    pub first_uid: String,
    /// The other volume's name.
    pub second: String,
    /// Its FrameOfReferenceUID.
    pub second_uid: String,
}

/// Whether `a` and `b` lie in one DICOM frame of reference: an error where both name one and
/// the two differ (a volume without one — NIfTI, NRRD — is taken at its word).
pub fn same_frame_of_reference(a: &Volume, b: &Volume) -> Result<(), FrameOfReferenceMismatch> {
    match (&a.meta.frame_of_reference, &b.meta.frame_of_reference) {
        (Some(x), Some(y)) if x != y => Err(FrameOfReferenceMismatch {
            first: a.name.clone(),
            first_uid: x.clone(),
            second: b.name.clone(),
            second_uid: y.clone(),
        }),
        _ => Ok(()),
    }
}

impl TextureMap {
    /// The identity (one grid).
    pub const IDENTITY: Self = Self { scale: DVec3::ONE, offset: DVec3::ZERO };

    /// The map from `from`'s texture space to `to`'s: the texture point `u` of `from` is the
    /// patient point `origin + (u · n − ½) · spacing`, which is `to`'s texture point
    /// `(p − origin' ) / spacing' + ½) / n'`. Files without an origin sit at 0 (voxel 0's centre).
    pub fn between(from: &Volume, to: &Volume) -> Result<Self, FrameMismatch> {
        if from.meta.frame != to.meta.frame {
            return Err(FrameMismatch {
                first: from.name.clone(),
                first_frame: from.meta.frame.describe(),
                second: to.name.clone(),
                second_frame: to.meta.frame.describe(),
            });
        }
        let corner = |v: &Volume| v.meta.origin.unwrap_or(DVec3::ZERO) - 0.5 * v.spacing;
        let size = |v: &Volume| v.dims.as_dvec3() * v.spacing;
        let scale = size(from) / size(to);
        let offset = (corner(from) - corner(to)) / size(to);
        Ok(Self { scale, offset })
    }

    /// `u` in the other volume's texture space.
    pub fn apply(&self, u: DVec3) -> DVec3 {
        u * self.scale + self.offset
    }
}

/// What a sample composites with pre-integration ([`Fusion::classify_scan`]): the scan's segment
/// ending at it (premultiplied, corrected) and the frame volume's texture point of the sample
/// before it, where every other medium's segment starts.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    /// The scan's pre-integrated segment.
    pub scan: [f64; 4],
    /// The sample before's texture point.
    pub front: DVec3,
}

/// Whether texture point `u` lies in the box (voxel centres ± half a voxel).
pub fn in_box(u: DVec3) -> bool {
    u.cmpge(DVec3::ZERO).all() && u.cmple(DVec3::ONE).all()
}

/// What one sample of several volumes is (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Combine {
    /// The frame volume is a label map, coloured by its table.
    #[default]
    Labels,
    /// The scan by its TF, coloured by a visible label.
    Tint,
    /// The scan by its TF, only inside visible labels.
    Inside,
    /// Two scalar volumes, each by its TF, as two media in one place.
    Fuse,
    /// Two scalar volumes (channels), colours added.
    Add,
}

impl Combine {
    /// Whether the second volume is a label map (read through a label table).
    pub fn second_is_labels(self) -> bool {
        matches!(self, Combine::Tint | Combine::Inside)
    }

    /// Whether a sample's opacity is at most the frame volume's through its TF, so that the
    /// frame volume's empty space is empty for the combination too (its leap is lossless).
    pub fn bounded_by_first(self) -> bool {
        matches!(self, Combine::Tint | Combine::Inside)
    }
}

/// A label map over a fused pair (`Fuse`, `Add`): what it does to the pair's sample (`Tint` or
/// `Inside`, as to one scan), the map, and where a frame-volume texture point lies in it. Its
/// labels are coloured by the fusion's `label_lut` and sampled with its `filter`.
#[derive(Clone, Copy, Debug)]
pub struct Overlay<'a> {
    /// `Tint` or `Inside`.
    pub combine: Combine,
    /// The label map.
    pub labels: &'a Volume,
    /// The frame volume's texture space into the map's.
    pub map: TextureMap,
}

/// A second volume and how samples combine, for the reference ([`crate::reference`]).
#[derive(Clone, Copy, Debug)]
pub struct Fusion<'a> {
    /// What a sample is.
    pub combine: Combine,
    /// The label table as a LUT by label value ([`crate::labels::LabelTable::lut`]); for `Labels`,
    /// `Tint` and `Inside`.
    pub label_lut: &'a [[f32; 4]],
    /// How label maps are sampled.
    pub filter: LabelFilter,
    /// The second volume and its TF (`Tint`, `Inside`: its label map; `Fuse`, `Add`: the second
    /// scalar volume and its TF), with the map into its texture space.
    pub second: Option<(&'a Volume, &'a [[f32; 4]], TextureMap)>,
    /// More scalar volumes with their TFs and maps (`Fuse`, `Add`: a third and fourth channel),
    /// combined with the first two as more media in one place.
    pub more: &'a [(&'a Volume, &'a [[f32; 4]], TextureMap)],
    /// A label map over the fused pair (`Fuse`, `Add` only).
    pub overlay: Option<Overlay<'a>>,
}

/// The texture-space box (of the frame volume's texture space) rays cross: the frame volume's
/// `[0,1]³`, grown to hold every scalar volume fused with it (`Fuse`, `Add`: a PET reaching past
/// its CT is drawn where it lies); a label map (`Tint`, `Inside`, an overlay) shows only where
/// the scan does, so it grows nothing. The box reaches at most [`MARCH_BOX_REACH`] frame-volume
/// sizes past each face (what the camera, framed on the frame volume, can show): a header placing
/// a volume 10³⁹ mm away grows the box no further, and it stays finite in the GPU's f32.
pub fn march_box(combine: Combine, scalar_maps: impl IntoIterator<Item = TextureMap>) -> (DVec3, DVec3) {
    let (mut lo, mut hi) = (DVec3::ZERO, DVec3::ONE);
    if matches!(combine, Combine::Fuse | Combine::Add) {
        for m in scalar_maps {
            // u₂ = u · scale + offset is the partner's [0,1] at u = −offset/scale … (1 − offset)/scale.
            let (a, b) = (-m.offset / m.scale, (DVec3::ONE - m.offset) / m.scale);
            if a.is_finite() && b.is_finite() {
                (lo, hi) = (lo.min(a.min(b)), hi.max(a.max(b)));
            }
        }
    }
    (lo.max(DVec3::splat(-MARCH_BOX_REACH)), hi.min(DVec3::splat(1.0 + MARCH_BOX_REACH)))
}

/// How far, in frame-volume sizes, the box rays cross may reach past the frame volume's faces.
pub const MARCH_BOX_REACH: f64 = 4.0;

/// The label table's entry at `label` (zero past its end: hidden).
pub fn label_entry(label_lut: &[[f32; 4]], label: u32) -> [f64; 4] {
    label_lut.get(label as usize).map_or([0.0; 4], |e| e.map(f64::from))
}

impl Fusion<'_> {
    /// The table's entry of the label map `labels` at its texture point `at` (hidden — zero —
    /// outside its box, where it reads background 0).
    fn label_entry_at(&self, labels: &Volume, at: DVec3) -> [f64; 4] {
        let label = if in_box(at) { sample_label(labels, at, self.filter).0 } else { 0 };
        label_entry(self.label_lut, label)
    }

    /// Scalar volume `volume` through its TF `lut` at the frame volume's texture point `u`
    /// (`map` into its texture space): straight colour and the TF's opacity, zero outside its box.
    fn medium_at(volume: &Volume, lut: &[[f32; 4]], map: &TextureMap, u: DVec3) -> [f64; 4] {
        let at = map.apply(u);
        if in_box(at) { lut_sample(lut, volume.sample_trilinear(at)) } else { [0.0; 4] }
    }

    /// The box rays cross ([`march_box`]).
    pub fn march_box(&self) -> (DVec3, DVec3) {
        let maps = self.second.iter().map(|(_, _, m)| *m).chain(self.more.iter().map(|(_, _, m)| *m));
        march_box(self.combine, maps)
    }

    /// The premultiplied, opacity-corrected colour of the sample at the frame volume's texture
    /// point `u`, where the frame volume's field is `s` and its TF `lut`; `exponent` is the
    /// correction's (step over opacity unit). Shading, when on, is applied by the caller.
    pub fn classify(&self, first: &Volume, lut: &[[f32; 4]], u: DVec3, s: f64, exponent: f64) -> [f64; 4] {
        self.classify_scan(first, lut, u, s, exponent, None)
    }

    /// [`Self::classify`] with pre-integration (Engel et al. 2001) where `segment` is given: the
    /// scan's own sample is its pre-integrated segment ending at this sample instead of its TF at
    /// `s` — `tint` and `inside` colour or mask it (their opacity is the scan's) — and every other
    /// scalar medium (`fuse`, `add`) is its own TF's segment from its field at the sample before
    /// to its field here, so media in one place combine segments as they combine samples.
    pub fn classify_scan(
        &self,
        first: &Volume,
        lut: &[[f32; 4]],
        u: DVec3,
        s: f64,
        exponent: f64,
        segment: Option<Segment>,
    ) -> [f64; 4] {
        let premultiplied = |c: [f64; 3], a: f64| [c[0] * a, c[1] * a, c[2] * a, a];
        let through = |lut: &[[f32; 4]], s: f64| match segment.map(|g| g.scan) {
            Some(p) if p[3] > 0.0 => ([p[0] / p[3], p[1] / p[3], p[2] / p[3]], p[3]),
            Some(_) => ([0.0; 3], 0.0),
            None => {
                let c = lut_sample(lut, s);
                ([c[0], c[1], c[2]], corrected_alpha(c[3], exponent))
            }
        };
        if self.combine == Combine::Labels {
            let (label, _) = sample_label(first, u, self.filter);
            let e = label_entry(self.label_lut, label);
            return premultiplied([e[0], e[1], e[2]], corrected_alpha(e[3], exponent));
        }
        let (c1, a1) = through(lut, s);
        let Some((second, second_lut, map)) = self.second else { return premultiplied(c1, a1) };
        match self.combine {
            Combine::Labels => unreachable!("handled above"),
            Combine::Tint | Combine::Inside => {
                let e = self.label_entry_at(second, map.apply(u));
                let visible = e[3] > 0.0;
                match self.combine {
                    Combine::Inside => premultiplied(c1, if visible { a1 } else { 0.0 }),
                    _ if visible => {
                        let w = e[3].min(1.0);
                        premultiplied(std::array::from_fn(|i| c1[i] + (e[i] - c1[i]) * w), a1)
                    }
                    _ => premultiplied(c1, a1),
                }
            }
            Combine::Fuse | Combine::Add => {
                let medium = |volume: &Volume, lut: &[[f32; 4]], map: &TextureMap| match segment {
                    // Nothing outside its box; its front is its field at the sample before
                    // (clamped to its edge, as the GPU's sampler reads it).
                    Some(g) if in_box(map.apply(u)) => preintegrate(
                        lut,
                        volume.sample_trilinear(map.apply(g.front)),
                        volume.sample_trilinear(map.apply(u)),
                        exponent,
                    ),
                    Some(_) => [0.0; 4],
                    None => {
                        let c = Self::medium_at(volume, lut, map, u);
                        premultiplied([c[0], c[1], c[2]], corrected_alpha(c[3], exponent))
                    }
                };
                // Past the frame volume's box (rays cross every scalar volume's) it adds nothing.
                let first = if in_box(u) { premultiplied(c1, a1) } else { [0.0; 4] };
                let mut media = vec![first, medium(second, second_lut, &map)];
                media.extend(self.more.iter().map(|(v, lut, map)| medium(v, lut, map)));
                let fused = fuse_media(self.combine, &media);
                match &self.overlay {
                    Some(overlay) => self.overlaid(overlay, fused, u),
                    None => fused,
                }
            }
        }
    }

    /// The opacity of the sample at the frame volume's texture point `u` (its field `s`, its TF
    /// `lut`) before the step's correction: what the light grid of the `shadows` and
    /// `ambient_occlusion` effects attenuates by ([`crate::light::LightGrid::compute`]). The
    /// combination's opacity as [`Self::classify`] makes it — the correction of several media's
    /// `1 − Π(1 − αᵢ)` is the product of each one's.
    pub fn alpha(&self, first: &Volume, lut: &[[f32; 4]], u: DVec3, s: f64) -> f64 {
        let visible = |labels: &Volume, at: DVec3| self.label_entry_at(labels, at)[3] > 0.0;
        if self.combine == Combine::Labels {
            return label_entry(self.label_lut, sample_label(first, u, self.filter).0)[3].clamp(0.0, 1.0);
        }
        let a1 = lut_sample(lut, s)[3].clamp(0.0, 1.0);
        let Some((second, second_lut, map)) = self.second else { return a1 };
        match self.combine {
            Combine::Labels | Combine::Tint => a1,
            Combine::Inside => {
                if visible(second, map.apply(u)) {
                    a1
                } else {
                    0.0
                }
            }
            Combine::Fuse | Combine::Add => {
                let medium = |volume: &Volume, lut: &[[f32; 4]], map: &TextureMap| {
                    Self::medium_at(volume, lut, map, u)[3].clamp(0.0, 1.0)
                };
                let mut clear = 1.0 - if in_box(u) { a1 } else { 0.0 };
                clear *= 1.0 - medium(second, second_lut, &map);
                for (v, lut, map) in self.more {
                    clear *= 1.0 - medium(v, lut, map);
                }
                match &self.overlay {
                    Some(o) if o.combine == Combine::Inside && !visible(o.labels, o.map.apply(u)) => 0.0,
                    _ => 1.0 - clear,
                }
            }
        }
    }

    /// The premultiplied sample `fused` under the label map `overlay` at the frame volume's
    /// texture point `u`: where no visible label lies, nothing (`Inside`) or itself (`Tint`);
    /// where one does, itself (`Inside`) or its colour moved towards the label's by the label's
    /// opacity, its own opacity kept (`Tint`).
    fn overlaid(&self, overlay: &Overlay<'_>, fused: [f64; 4], u: DVec3) -> [f64; 4] {
        let a = fused[3];
        if !(a > 0.0) {
            return [0.0; 4];
        }
        let e = self.label_entry_at(overlay.labels, overlay.map.apply(u));
        let visible = e[3] > 0.0;
        match overlay.combine {
            Combine::Inside if !visible => [0.0; 4],
            Combine::Tint if visible => {
                let w = e[3].min(1.0);
                let rgb: [f64; 3] = std::array::from_fn(|i| {
                    let straight = fused[i] / a;
                    (straight + (e[i] - straight) * w) * a
                });
                [rgb[0], rgb[1], rgb[2], a]
            }
            _ => fused,
        }
    }
}

/// The largest opacity a combination `combine` can give a sample, from the largest of each
/// input's table (`maxima`: the frame volume's TF — or label table for `Labels` — first, then each
/// scalar partner's TF): media in one place `1 − Π(1 − maxᵢ)` (`Fuse`, `Add`), the scan's
/// (`Tint`, `Inside`: a label never adds opacity), the table's (`Labels`). A path tracer's
/// majorant is the extinction of it.
pub fn max_alpha(combine: Combine, maxima: &[f64]) -> f64 {
    let clamp = |a: f64| if a.is_nan() { 1.0 } else { a.clamp(0.0, 1.0) };
    match combine {
        Combine::Fuse | Combine::Add => 1.0 - maxima.iter().map(|&a| 1.0 - clamp(a)).product::<f64>(),
        Combine::Labels | Combine::Tint | Combine::Inside => maxima.first().map_or(0.0, |&a| clamp(a)),
    }
}

/// Premultiplied samples of several media in one place: opacity `1 − Π(1 − αᵢ)`; colour the
/// opacity-weighted mean (`Fuse`) or the sum (`Add`: each channel's light adds, so an image may
/// exceed 1 where channels overlap, as additive blending saturates on display).
pub fn fuse_media(combine: Combine, media: &[[f64; 4]]) -> [f64; 4] {
    let a = 1.0 - media.iter().map(|p| 1.0 - p[3]).product::<f64>();
    let sum: [f64; 4] = std::array::from_fn(|i| media.iter().map(|p| p[i]).sum());
    if combine == Combine::Add {
        return [sum[0], sum[1], sum[2], a];
    }
    if sum[3] <= 0.0 {
        return [0.0; 4];
    }
    let k = a / sum[3];
    [sum[0] * k, sum[1] * k, sum[2] * k, a]
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;
    use crate::volume::VoxelData;
    use crate::volume_meta::WorldFrame;

    fn grid(n: u32, spacing: f64, origin: DVec3) -> Volume {
        let mut v =
            Volume::new("v", UVec3::splat(n), DVec3::splat(spacing), VoxelData::U8(vec![0; (n * n * n) as usize]));
        v.meta.frame = WorldFrame::Lps;
        v.meta.origin = Some(origin);
        v
    }

    #[test]
    fn a_voxel_centre_maps_to_the_same_patient_point() {
        // CT: 64 voxels of 0.7 mm from (10, 20, 30); PET: 12 of 4 mm, shifted by half a PET voxel.
        let ct = grid(64, 0.7, DVec3::new(10.0, 20.0, 30.0));
        let pet = grid(12, 4.0, DVec3::new(10.0 - 2.0, 20.0 + 2.0, 30.0));
        let map = TextureMap::between(&ct, &pet).expect("one frame");
        let patient =
            |v: &Volume, u: DVec3| v.meta.origin.expect("an origin") + (u * v.dims.as_dvec3() - 0.5) * v.spacing;
        for i in [0.0, 17.0, 63.0] {
            let u = (DVec3::new(i, 5.0, 40.0) + 0.5) / 64.0;
            let a = patient(&ct, u);
            let b = patient(&pet, map.apply(u));
            assert!((a - b).length() < 1e-9, "{a} vs {b}");
        }
        assert_eq!(TextureMap::between(&ct, &ct).expect("same"), TextureMap::IDENTITY);
        let mut elsewhere = pet.clone();
        elsewhere.meta.frame = WorldFrame::IndexAxes;
        assert!(TextureMap::between(&ct, &elsewhere).expect_err("frames").to_string().contains("index axes"));
    }

    #[test]
    fn two_media_in_one_place() {
        let red = [0.5, 0.0, 0.0, 0.5];
        let blue = [0.0, 0.0, 0.25, 0.25];
        let f = fuse_media(Combine::Fuse, &[red, blue]);
        assert!((f[3] - (1.0 - 0.5 * 0.75)).abs() < 1e-12);
        // Straight colours: red's weight 0.5, blue's 0.25 of 0.75.
        assert!((f[0] / f[3] - 2.0 / 3.0).abs() < 1e-12 && (f[2] / f[3] - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(fuse_media(Combine::Fuse, &[red, [0.0; 4]]), red);
        assert_eq!(fuse_media(Combine::Fuse, &[[0.0; 4], [0.0; 4]]), [0.0; 4]);
        let added = fuse_media(Combine::Add, &[red, blue]);
        assert_eq!([added[0], added[2]], [0.5, 0.25]);
    }

    /// Four channels: opacity `1 − Π(1 − αᵢ)`, colours added; the order of the media does not
    /// matter (no channel is "in front" within one sample).
    #[test]
    fn four_media_in_one_place() {
        let media = [[0.2, 0.0, 0.0, 0.2], [0.0, 0.3, 0.0, 0.3], [0.0, 0.0, 0.1, 0.1], [0.05, 0.05, 0.0, 0.1]];
        let added = fuse_media(Combine::Add, &media);
        let a = 1.0 - 0.8 * 0.7 * 0.9 * 0.9;
        assert!((added[3] - a).abs() < 1e-12 && (added[0] - 0.25).abs() < 1e-12 && (added[1] - 0.35).abs() < 1e-12);
        let mut reversed = media;
        reversed.reverse();
        let fused = fuse_media(Combine::Fuse, &media);
        let again = fuse_media(Combine::Fuse, &reversed);
        assert!((0..4).all(|i| (fused[i] - again[i]).abs() < 1e-12), "{fused:?} {again:?}");
    }

    /// Rays cross the union of the scalar volumes' boxes, a label map grows nothing, and a
    /// partner placed absurdly far (a header's 10³⁹ mm) is cut at the reach, finite in f32.
    #[test]
    fn the_march_box_is_the_union_within_its_reach() {
        // A partner twice the frame volume's size, centred on it: [−0.5, 1.5] in its texture space.
        let wide = TextureMap { scale: DVec3::splat(0.5), offset: DVec3::splat(0.25) };
        assert_eq!(march_box(Combine::Fuse, [wide]), (DVec3::splat(-0.5), DVec3::splat(1.5)));
        assert_eq!(march_box(Combine::Tint, [wide]), (DVec3::ZERO, DVec3::ONE));
        let far = TextureMap { scale: DVec3::ONE, offset: DVec3::splat(-1e39) };
        let (lo, hi) = march_box(Combine::Add, [far]);
        assert_eq!((lo, hi), (DVec3::ZERO, DVec3::splat(1.0 + MARCH_BOX_REACH)));
        assert!(hi.as_vec3().is_finite());
    }
}
