//! Built-in transfer functions for scanner data, named on the command line (`--tf ct-bone`):
//! CT presets with control points in Hounsfield units, and an MR preset in percentiles of the
//! volume's foreground (MR values have no physical unit, so fixed values would not carry from
//! one scanner to the next).
//!
//! `ct-bone` is 3D Slicer's "CT-Bone" volume-rendering preset (its `presets.xml`: opacity 0 up
//! to −16.4 HU, 0.72 at 641 HU; colours from dark red through bone white); the others follow
//! the tissue ranges radiology uses — lung parenchyma −950…−500 HU, fat −100, soft tissue and
//! muscle 20…80, contrast-filled vessels 150…500, bone from ~300, cortical bone over 700.

use super::{ControlPoint, TransferFunction};
use crate::histogram::ValueSummary;
use crate::volume::Volume;

/// A built-in scanner preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScannerPreset {
    /// Bone in CT (3D Slicer's CT-Bone).
    CtBone,
    /// Skin, fat, muscle and bone in CT.
    CtSoftTissue,
    /// Lung parenchyma and airways in CT; the chest wall hidden.
    CtLung,
    /// Contrast-enhanced vessels (CT angiography) in red, bone in white.
    CtAngio,
    /// MR: a grey ramp over the foreground's percentiles.
    MrDefault,
}

/// The CT domain: the HU a 12-bit scanner writes.
const CT_DOMAIN: (f64, f64) = (-3024.0, 3071.0);

impl ScannerPreset {
    /// Every preset.
    pub const ALL: [ScannerPreset; 5] = [
        ScannerPreset::CtBone,
        ScannerPreset::CtSoftTissue,
        ScannerPreset::CtLung,
        ScannerPreset::CtAngio,
        ScannerPreset::MrDefault,
    ];

    /// The name given to `--tf`.
    pub fn name(self) -> &'static str {
        match self {
            ScannerPreset::CtBone => "ct-bone",
            ScannerPreset::CtSoftTissue => "ct-soft-tissue",
            ScannerPreset::CtLung => "ct-lung",
            ScannerPreset::CtAngio => "ct-angio",
            ScannerPreset::MrDefault => "mr-default",
        }
    }

    /// The preset called `name`.
    pub fn from_name(name: &str) -> Option<ScannerPreset> {
        ScannerPreset::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The preset `name` most likely means, when it is none exactly: compared without case and
    /// with `_` read as `-`, then by edit distance (`CT-BONE`, `ct_bone`, `ct-bones` → `ct-bone`).
    /// A suggestion for a message only: `--tf` takes the exact name ([`Self::from_name`]).
    pub fn closest(name: &str) -> Option<ScannerPreset> {
        let wanted = name.to_lowercase().replace('_', "-");
        ScannerPreset::ALL
            .into_iter()
            .map(|p| (strsim::normalized_levenshtein(&wanted, p.name()), p))
            .filter(|(score, _)| *score >= 0.6)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, p)| p)
    }

    /// Every preset's name: `ct-bone, ct-soft-tissue, … and mr-default`.
    pub fn names() -> String {
        let names: Vec<&str> = ScannerPreset::ALL.iter().map(|p| p.name()).collect();
        format!("{} and {}", names[..names.len() - 1].join(", "), names[names.len() - 1])
    }

    /// True for the presets written in Hounsfield units.
    pub fn is_ct(self) -> bool {
        self != ScannerPreset::MrDefault
    }

    /// `(value, rgb, alpha)` in HU for the CT presets.
    fn ct_points(self) -> &'static [(f64, [f64; 3], f64)] {
        match self {
            ScannerPreset::CtBone => &[
                (-3024.0, [0.0, 0.0, 0.0], 0.0),
                (-16.4458, [0.729412, 0.254902, 0.301961], 0.0),
                (641.385, [0.905882, 0.815686, 0.552941], 0.715686),
                (3071.0, [1.0, 1.0, 1.0], 0.705882),
            ],
            ScannerPreset::CtSoftTissue => &[
                (-3024.0, [0.0, 0.0, 0.0], 0.0),
                (-300.0, [0.0, 0.0, 0.0], 0.0),
                (-100.0, [0.9, 0.8, 0.5], 0.02),
                (40.0, [0.75, 0.25, 0.2], 0.12),
                (300.0, [0.95, 0.9, 0.8], 0.4),
                (3071.0, [1.0, 1.0, 1.0], 0.7),
            ],
            ScannerPreset::CtLung => &[
                (-3024.0, [0.0, 0.0, 0.0], 0.0),
                (-990.0, [0.0, 0.0, 0.0], 0.0),
                (-900.0, [0.3, 0.5, 0.9], 0.04),
                (-700.0, [0.95, 0.6, 0.6], 0.15),
                (-450.0, [0.9, 0.5, 0.5], 0.0),
                (3071.0, [0.0, 0.0, 0.0], 0.0),
            ],
            ScannerPreset::CtAngio => &[
                (-3024.0, [0.0, 0.0, 0.0], 0.0),
                (120.0, [0.6, 0.0, 0.0], 0.0),
                (180.0, [0.85, 0.1, 0.05], 0.35),
                (450.0, [1.0, 0.45, 0.25], 0.6),
                (700.0, [1.0, 0.95, 0.9], 0.75),
                (3071.0, [1.0, 1.0, 1.0], 0.8),
            ],
            ScannerPreset::MrDefault => &[],
        }
    }

    /// The transfer function for `volume`: HU control points for CT; for MR, the grey ramp from
    /// the 5th to the 99.5th percentile of the voxels above the background, in the volume's
    /// values.
    pub fn for_volume(self, volume: &Volume) -> TransferFunction {
        self.fitted(&ValueSummary::of(volume))
    }

    /// [`Self::for_volume`] from what it reads of a volume (its summary).
    pub fn fitted(self, values: &ValueSummary) -> TransferFunction {
        let point = |(value, color, alpha): (f64, [f64; 3], f64)| ControlPoint { value, color, alpha };
        if self.is_ct() {
            return TransferFunction {
                domain: CT_DOMAIN,
                points: self.ct_points().iter().copied().map(point).collect(),
            };
        }
        let (lo, hi) = values.value_range;
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let h = values.binned(1024);
        let floor = h.background().map_or(0.0, |b| b.ceiling);
        let at = |p: f64| lo + h.percentile_above(floor, p) * (hi - lo);
        let mut values = [at(0.05), at(0.5), at(0.95), at(0.995)];
        for i in 1..values.len() {
            values[i] = values[i].max(values[i - 1]);
        }
        let shape =
            [([0.0, 0.0, 0.0], 0.0), ([0.45, 0.45, 0.5], 0.05), ([0.9, 0.88, 0.85], 0.35), ([1.0, 1.0, 1.0], 0.7)];
        let mut points = vec![point((lo, [0.0; 3], 0.0))];
        points.extend(values.iter().zip(shape).map(|(&v, (c, a))| point((v.clamp(lo, hi), c, a))));
        points.push(point((hi, [1.0; 3], 0.7)));
        TransferFunction { domain: (lo, hi), points }
    }
}
