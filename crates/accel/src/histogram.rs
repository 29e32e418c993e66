//! The histogram of a volume's normalized values, and the background it shows: the peak that
//! air, or a scanner's noise floor, makes at the low end. A default transfer function that
//! starts above it shows the object instead of a box of noise (3D Slicer's and ParaView's
//! presets do the same by starting their ramps above air), and `volgraph info` reports it.

use crate::volume::Volume;

/// Counts of normalized values in `bins` equal bins over \[0,1\].
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Voxels per bin.
    pub counts: Vec<u64>,
    /// All voxels counted.
    pub total: u64,
}

/// The background peak of a histogram ([`Histogram::background`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Background {
    /// The normalized value of the peak (the histogram's mode).
    pub mode: f64,
    /// The normalized value where the peak's upper flank has fallen to 1% of its height: what
    /// lies below is background.
    pub ceiling: f64,
    /// The share of voxels at or below the ceiling.
    pub fraction: f64,
}

/// A mode holding less than this share of the voxels is not a background.
const MIN_BACKGROUND_SHARE: f64 = 0.1;
/// The peak ends where the counts fall below this share of its height.
const FLANK: f64 = 0.01;

impl Histogram {
    /// The histogram of `volume`'s normalized values (what the GPU samples) in `bins` bins.
    pub fn of(volume: &Volume, bins: usize) -> Histogram {
        let bins = bins.max(1);
        let mut counts = vec![0u64; bins];
        for i in 0..volume.voxel_count() {
            let v = volume.normalized(i);
            let b = if v.is_finite() { ((v * bins as f64) as usize).min(bins - 1) } else { 0 };
            counts[b] += 1;
        }
        Histogram { total: counts.iter().sum(), counts }
    }

    /// The normalized value at the centre of bin `i`.
    pub fn bin_centre(&self, i: usize) -> f64 {
        (i as f64 + 0.5) / self.counts.len() as f64
    }

    /// The normalized value below which a share `p` (0..=1) of the voxels lie (bin resolution).
    pub fn percentile(&self, p: f64) -> f64 {
        let want = (p.clamp(0.0, 1.0) * self.total as f64).ceil() as u64;
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= want.max(1) {
                return (i + 1) as f64 / self.counts.len() as f64;
            }
        }
        1.0
    }

    /// The background: the histogram's mode — the densest window of 5 bins, so noise spread
    /// over neighbouring values counts as one peak — when it lies in the lower half of the
    /// values and holds at least a tenth of the voxels, up to where the counts fall below 1%
    /// of the peak's highest bin. `None` for a volume without one (a peak in the upper half, a
    /// flat histogram, or a peak with nothing above it).
    pub fn background(&self) -> Option<Background> {
        let n = self.counts.len();
        let around = |i: usize| i.saturating_sub(2)..(i + 3).min(n);
        let window = |i: usize| self.counts[around(i)].iter().sum::<u64>();
        let densest = (0..n).max_by_key(|&i| (window(i), std::cmp::Reverse(i)))?;
        if self.total == 0 || (window(densest) as f64) < MIN_BACKGROUND_SHARE * self.total as f64 {
            return None;
        }
        // The peak is the window's highest bin; the background ends where the counts above it
        // fall below 1% of its height.
        let mode = around(densest).max_by_key(|&i| (self.counts[i], std::cmp::Reverse(i)))?;
        if self.bin_centre(mode) >= 0.5 {
            return None;
        }
        let floor = (self.counts[mode] as f64 * FLANK).max(1.0);
        let end = (mode..n).find(|&i| (self.counts[i] as f64) < floor)?;
        let below: u64 = self.counts[..end].iter().sum();
        if below == self.total || below == 0 {
            return None;
        }
        Some(Background {
            mode: self.bin_centre(mode),
            ceiling: end as f64 / n as f64,
            fraction: below as f64 / self.total as f64,
        })
    }
}

impl Histogram {
    /// Like [`Histogram::percentile`] over only the voxels at or above normalized value `cut`
    /// (the foreground above a background ceiling).
    pub fn percentile_above(&self, cut: f64, p: f64) -> f64 {
        let n = self.counts.len();
        let first = ((cut.clamp(0.0, 1.0) * n as f64) as usize).min(n - 1);
        let total: u64 = self.counts[first..].iter().sum();
        let want = (p.clamp(0.0, 1.0) * total as f64).ceil() as u64;
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate().skip(first) {
            seen += c;
            if seen >= want.max(1) {
                return (i + 1) as f64 / n as f64;
            }
        }
        1.0
    }

    /// Otsu's threshold (Otsu 1979): the normalized value that splits the histogram into the two
    /// classes of least within-class variance — for a scan, background from object. `None` for
    /// an empty or constant histogram.
    pub fn otsu(&self) -> Option<f64> {
        let n = self.counts.len();
        let total = self.total as f64;
        let sum: f64 = self.counts.iter().enumerate().map(|(i, &c)| i as f64 * c as f64).sum();
        let (mut below, mut below_sum, mut best) = (0.0, 0.0, None::<(f64, usize)>);
        for (i, &c) in self.counts.iter().enumerate().take(n.saturating_sub(1)) {
            below += c as f64;
            below_sum += i as f64 * c as f64;
            let above = total - below;
            if below == 0.0 || above == 0.0 {
                continue;
            }
            let (m0, m1) = (below_sum / below, (sum - below_sum) / above);
            let between = below * above * (m0 - m1) * (m0 - m1);
            if best.is_none_or(|(b, _)| between > b) {
                best = Some((between, i));
            }
        }
        best.map(|(_, i)| (i + 1) as f64 / n as f64)
    }
}

/// Air lies below this in HU (−1000 HU, a scanner's air with noise and partial volume up to
/// about −700); a CT peak above it is tissue, not background.
const CT_AIR_BELOW_HU: f64 = -500.0;

/// Bins of [`ValueSummary::histogram`]: the finest any fitted default reads (the MR preset's
/// percentiles); coarser histograms are exact sums of its bins.
pub const FIT_BINS: usize = 1024;

/// What the fitted defaults — the default transfer function, the MR preset's percentiles, the
/// automatic iso value — read of a volume: the histogram of its normalized values in
/// [`FIT_BINS`] bins, its value range and whether its values are Hounsfield units. One process
/// takes it from the volume ([`ValueSummary::of`]); a sort-last render sums every rank's share
/// of the file into the same counts, so every rank fits what one process would.
#[derive(Clone, Debug, PartialEq)]
pub struct ValueSummary {
    /// Voxels per normalized-value bin, [`FIT_BINS`] bins over \[0,1\].
    pub histogram: Histogram,
    /// The range the values normalize over.
    pub value_range: (f64, f64),
    /// True for CT data in HU ([`crate::volume_meta::VolumeMeta::is_ct_hu`]).
    pub ct_hu: bool,
}

impl ValueSummary {
    /// The summary of `volume`.
    pub fn of(volume: &Volume) -> ValueSummary {
        ValueSummary {
            histogram: Histogram::of(volume, FIT_BINS),
            value_range: volume.value_range,
            ct_hu: volume.meta.is_ct_hu(),
        }
    }

    /// The histogram in `bins` bins, which must divide [`FIT_BINS`] (the callers ask for 256
    /// and 1024): exactly [`Histogram::of`]`(volume, bins)` (a bin of `v·bins` is the bin of
    /// `v·FIT_BINS` divided by `FIT_BINS / bins`, both products exact in binary floating point).
    pub fn binned(&self, bins: usize) -> Histogram {
        debug_assert!(bins > 0 && FIT_BINS.is_multiple_of(bins), "{bins} bins do not divide {FIT_BINS}");
        let group = (FIT_BINS / bins.clamp(1, FIT_BINS)).max(1);
        let counts: Vec<u64> = self.histogram.counts.chunks(group).map(|c| c.iter().sum()).collect();
        Histogram { total: counts.iter().sum(), counts }
    }

    /// The data value of normalized value `s`.
    pub fn data_value(&self, s: f64) -> f64 {
        let (lo, hi) = self.value_range;
        lo + s * (hi - lo)
    }
}

/// The background of `volume` ([`background_in`] of its summary).
pub fn background_of(volume: &Volume) -> Option<Background> {
    background_in(&ValueSummary::of(volume))
}

/// The background ([`Histogram::background`] of the 256-bin histogram), where the data's units
/// allow it: in CT (values in HU) only a peak of air counts — a field of view filled with soft
/// tissue has no background, however common its values.
pub fn background_in(values: &ValueSummary) -> Option<Background> {
    let b = values.binned(256).background()?;
    if values.ct_hu && values.data_value(b.mode) > CT_AIR_BELOW_HU {
        return None;
    }
    Some(b)
}

/// The iso value a graph gets for `Data(Auto)` ([`auto_iso_in`] of `volume`'s summary).
pub fn auto_iso(volume: &Volume) -> f64 {
    auto_iso_in(&ValueSummary::of(volume))
}

/// The iso value a graph gets for `Data(Auto)` (normalized): halfway between the background
/// peak (air, the noise floor) and the median of what lies above it — the half-maximum of a
/// blurred step, where an edge between background and object is; for CT, between air and soft
/// tissue, the skin. Never below the top of the background peak, so the surface is the
/// object's and not the box of noise. A volume without a background gets Otsu's threshold
/// (0.5 without contrast).
pub fn auto_iso_in(values: &ValueSummary) -> f64 {
    let h = values.binned(256);
    match background_in(values) {
        Some(b) => {
            let foreground = h.percentile_above(b.ceiling, 0.5);
            (0.5 * (b.mode + foreground)).max(b.ceiling)
        }
        None => h.otsu().unwrap_or(0.5),
    }
}

/// The data range and automatic iso value of `volume` as `(low, high, auto_iso)`: what a
/// graph's `Data(...)` inputs are resolved with (the compiler's `DATA_LOW`, `DATA_HIGH`,
/// `DATA_AUTO_ISO` scene values).
pub fn data_scale(volume: &Volume) -> (f64, f64, f64) {
    data_scale_in(&ValueSummary::of(volume))
}

/// [`data_scale`] from a summary.
pub fn data_scale_in(values: &ValueSummary) -> (f64, f64, f64) {
    (values.value_range.0, values.value_range.1, auto_iso_in(values))
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};

    use super::*;
    use crate::volume::VoxelData;

    #[test]
    fn the_noise_floor_is_the_background() {
        let h = Histogram::of(&crate::generate::scanned_sphere(32), 256);
        let b = h.background().expect("a background");
        assert!((70.0 / 255.0..=81.0 / 255.0).contains(&b.mode), "{b:?}");
        assert!((80.0 / 255.0..=90.0 / 255.0).contains(&b.ceiling), "the floor ends after 80: {b:?}");
        assert!(b.fraction > 0.8 && b.fraction < 1.0, "{b:?}");
        assert!(h.percentile(0.5) < b.ceiling && h.percentile(1.0) > 0.78, "{}", h.percentile(1.0));
    }

    #[test]
    fn the_auto_iso_value_lies_between_the_noise_floor_and_the_object() {
        // scanned_sphere: noise floor near 75/255, the object at 200/255: halfway, ~137.
        let iso = auto_iso(&crate::generate::scanned_sphere(32));
        assert!((120.0 / 255.0..160.0 / 255.0).contains(&iso), "{}", iso * 255.0);
    }

    #[test]
    fn a_volume_without_a_low_peak_has_no_background() {
        // A ramp: every value equally common.
        let ramp: Vec<u8> = (0..4096u32).map(|i| (i % 256) as u8).collect();
        let v = Volume::new("ramp", UVec3::new(16, 16, 16), DVec3::ONE, VoxelData::U8(ramp));
        assert_eq!(Histogram::of(&v, 256).background(), None);
        // A constant volume: nothing above the peak.
        let flat = Volume::new("flat", UVec3::splat(4), DVec3::ONE, VoxelData::U8(vec![30; 64]));
        assert_eq!(Histogram::of(&flat, 256).background(), None);
    }

    #[test]
    fn a_summary_rebins_to_exactly_the_histogram_of_the_volume() {
        let v = crate::generate::scanned_sphere(32);
        let summary = ValueSummary::of(&v);
        for bins in [1, 4, 256, 1024] {
            assert_eq!(summary.binned(bins), Histogram::of(&v, bins), "{bins} bins");
        }
    }
}
