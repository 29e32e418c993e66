//! The histogram of a volume's normalized values, and the background it shows: the low peak
//! that air or a scanner's noise floor makes, at or below the median (a CT's padding outside
//! the field of view, below −1024 HU and apart from every measured value, left out). A default transfer function that
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
    /// The normalized value of the peak (its highest bin).
    pub mode: f64,
    /// The normalized value where the peak's upper flank has fallen to 1% of its height: what
    /// lies below is background.
    pub ceiling: f64,
    /// The normalized value where the peak's share begins: 0, or above a CT's padding.
    pub floor: f64,
    /// The share of all voxels in the peak: from `floor` up to `ceiling` (its own, not what
    /// lies below it).
    pub fraction: f64,
}

/// Values apart from every other at the bottom of the histogram ([`ValueSummary::padding`]):
/// a CT's padding outside the scanner's field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Padding {
    /// The normalized value of its bin.
    pub value: f64,
    /// The share of voxels it holds.
    pub fraction: f64,
    /// The first bin above it that holds a value (where the measured values begin).
    pub next_bin: usize,
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

    /// The background ([`Self::background_from`] bin 0, any mode).
    pub fn background(&self) -> Option<Background> {
        self.background_from(0, |_| true)
    }

    /// The background among the bins from `start` on: the densest window of 5 bins (so noise
    /// spread over neighbouring values counts as one peak) holding at least a tenth of the
    /// voxels, whose highest bin lies in the lower half of the values from `start`, at or below
    /// the median
    /// and where `allowed` (the data's units: a CT's air) says a background may be — a denser
    /// window that is not is tissue, and the search goes on below it — up to where the counts
    /// above that bin fall below 1% of its height. Its share is its own: from `start` (above a
    /// CT's padding) to that ceiling. `None` for a volume without one (no low peak, a flat
    /// histogram, or a peak with nothing above it).
    ///
    /// At or below the median: an MR's noise floor spread over many low values (half the
    /// voxels below 12) is the background even where a narrower tissue peak above it (at 68)
    /// holds more voxels per bin.
    pub fn background_from(&self, start: usize, allowed: impl Fn(f64) -> bool) -> Option<Background> {
        let n = self.counts.len();
        if self.total == 0 || start >= n {
            return None;
        }
        let median = self.percentile(0.5);
        // The lower half of the values above `start` (a CT's padding stretches the range).
        let half = (start as f64 / n as f64 + 1.0) / 2.0;
        let around = |i: usize| i.saturating_sub(2).max(start)..(i + 3).min(n);
        let window = |i: usize| self.counts[around(i)].iter().sum::<u64>();
        let mut limit = n;
        while limit > start {
            let densest = (start..limit).max_by_key(|&i| (window(i), std::cmp::Reverse(i)))?;
            if (window(densest) as f64) < MIN_BACKGROUND_SHARE * self.total as f64 {
                return None;
            }
            let mode = around(densest).max_by_key(|&i| (self.counts[i], std::cmp::Reverse(i)))?;
            let centre = self.bin_centre(mode);
            if centre < half && centre <= median && allowed(centre) {
                let flank = (self.counts[mode] as f64 * FLANK).max(1.0);
                let end = (mode..n).find(|&i| (self.counts[i] as f64) < flank)?;
                let own: u64 = self.counts[start..end].iter().sum();
                let below: u64 = self.counts[..end].iter().sum();
                if below == self.total || own == 0 {
                    return None;
                }
                return Some(Background {
                    mode: centre,
                    ceiling: end as f64 / n as f64,
                    floor: start as f64 / n as f64,
                    fraction: own as f64 / self.total as f64,
                });
            }
            // Tissue, not background: look below its window.
            limit = around(densest).start;
        }
        None
    }

    /// The lowest occupied bin when the n/32 bins above it are empty — values apart from all
    /// others — with the first occupied bin above it.
    pub fn isolated_lowest(&self) -> Option<(usize, usize)> {
        let first = self.counts.iter().position(|&c| c > 0)?;
        let next = (first + 1..self.counts.len()).find(|&i| self.counts[i] > 0)?;
        (next - first > (self.counts.len() / 32).max(2)).then_some((first, next))
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

/// The floor of the Hounsfield scale (dcm2niix and most scanners clamp air there): a value
/// below it is no measurement but padding outside the field of view (−2000, −3024, −32768).
const HU_FLOOR: f64 = -1024.0;

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

    /// Whether the values are Hounsfield units: the file says so (a DICOM CT), or they reach
    /// −1024, the scale's floor, which no MR, microscope or 8/16-bit unsigned file reaches — so
    /// a NIfTI written from a CT series, which names no units, is read as the series is.
    pub fn hounsfield(&self) -> bool {
        self.ct_hu || self.value_range.0 <= HU_FLOOR
    }

    /// A CT's padding in the 256-bin histogram: the lowest values when they lie below −1024
    /// (below air on the Hounsfield scale: no measurement) and apart from every other value
    /// ([`Histogram::isolated_lowest`]). Read from the values alone — a DICOM series and the
    /// NIfTI written from it (which says no units) find the same. `None` for any other volume:
    /// an MR's masked zeros are its background, not padding.
    pub fn padding(&self) -> Option<Padding> {
        let h = self.binned(256);
        let (first, next) = h.isolated_lowest()?;
        // The bin's upper edge: every value in it lies below the floor.
        let top = self.data_value((first + 1) as f64 / 256.0);
        (top < HU_FLOOR && self.value_range.0 < HU_FLOOR).then(|| Padding {
            value: h.bin_centre(first),
            fraction: h.counts[first] as f64 / h.total.max(1) as f64,
            next_bin: next,
        })
    }
}

/// The background of `volume` ([`background_in`] of its summary).
pub fn background_of(volume: &Volume) -> Option<Background> {
    background_in(&ValueSummary::of(volume))
}

/// The background ([`Histogram::background_from`] of the 256-bin histogram, above a CT's
/// padding), where the data's units allow it: in CT (values in HU, said by the file or read
/// from the values: [`ValueSummary::hounsfield`]) only a peak of air counts — a field of view
/// filled with soft tissue has no background, however common its values.
pub fn background_in(values: &ValueSummary) -> Option<Background> {
    let start = values.padding().map_or(0, |p| p.next_bin);
    let hu = values.hounsfield();
    values.binned(256).background_from(start, |mode| !hu || values.data_value(mode) <= CT_AIR_BELOW_HU)
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

    /// A volume of i16 values drawn from `(value, count)` runs, in order.
    fn of_runs(runs: &[(i16, usize)]) -> ValueSummary {
        let values: Vec<i16> = runs.iter().flat_map(|&(v, n)| std::iter::repeat_n(v, n)).collect();
        let n = values.len() as u32;
        let mut v = Volume::new("runs", UVec3::new(n, 1, 1), DVec3::ONE, VoxelData::I16(values));
        v.fit_range_to_data();
        ValueSummary::of(&v)
    }

    /// An MR head: half the voxels a noise floor spread over 0..24, a narrow tissue peak at 68
    /// denser per bin than any part of the floor, a tail to 255. The background is the floor
    /// (at or below the median), not the tissue peak (the issue's "a peak at 68.2 holding
    /// 94.2 % of the voxels" with a median of 12).
    #[test]
    fn an_mr_noise_floor_below_the_median_is_the_background_not_a_denser_tissue_peak() {
        let mut runs: Vec<(i16, usize)> = (0..24).map(|v| (v, 2000)).collect();
        runs.extend([(67, 9000), (68, 12000), (69, 9000)]);
        runs.extend((70..256).map(|v| (v as i16, 40)));
        let values = of_runs(&runs);
        let median = values.data_value(values.histogram.percentile(0.5));
        let b = background_in(&values).expect("a background");
        let (mode, ceiling) = (values.data_value(b.mode), values.data_value(b.ceiling));
        assert!(mode < 24.0 && mode <= median, "mode {mode}, median {median}");
        assert!(ceiling <= 30.0, "the floor ends before the tissue: {ceiling}");
        assert!((b.fraction - 48_000.0 / 85_440.0).abs() < 0.02, "its own share: {b:?}");
    }

    /// A CT with padding outside the field of view (−3024, a fifth of the voxels), air at
    /// −1000, a narrow soft-tissue peak and bone: the padding is apart, the background is air
    /// with its own share, whether the file says HU (DICOM) or not (a NIfTI of it: its values
    /// reach −1024).
    #[test]
    fn a_ct_background_is_air_above_its_padding_with_or_without_units() {
        let mut runs = vec![(-3024, 20_000)];
        runs.extend((-1010..=-990).map(|v| (v, 1_400)));
        runs.extend([(39, 13_000), (40, 14_000), (41, 13_000)]);
        runs.extend((300..1300).step_by(10).map(|v| (v, 100)));
        for ct_hu in [true, false] {
            let mut values = of_runs(&runs);
            values.ct_hu = ct_hu;
            assert!(values.hounsfield());
            let padding = values.padding().expect("padding");
            assert!(
                values.data_value(padding.value) < -3000.0 && (padding.fraction - 20_000.0 / 99_400.0).abs() < 1e-9
            );
            let b = background_in(&values).expect("air");
            let mode = values.data_value(b.mode);
            assert!((-1030.0..=-970.0).contains(&mode), "ct_hu {ct_hu}: mode {mode}");
            assert!((b.fraction - 29_400.0 / 99_400.0).abs() < 0.01, "air's own share: {b:?}");
            assert!(values.data_value(b.ceiling) < 0.0, "the tissue is not background: {b:?}");
        }
        // Masked MR zeros are not padding (0 is no value below the HU floor).
        let mr = of_runs(&[(0, 5000), (400, 3000), (401, 3000), (900, 100)]);
        assert_eq!(mr.padding(), None);
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
