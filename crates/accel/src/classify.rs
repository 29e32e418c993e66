//! Transfer-function classification of value ranges: Krüger & Westermann 2003 §2.3's "CT"
//! texture, which says for every (min, max) pair whether any value in between is visible.
//!
//! The transfer function is taken as a LUT of `N` RGBA texels over the normalized value
//! `s ∈ [0,1]`, sampled the way a 1D linear sampler with clamp-to-edge does
//! (`docs/rendering_model.md`): texel `i` is centred at `c_i = (i + 0.5) / N` and the opacity
//! is linear between centres, constant beyond the first and last centre. Opacities are taken as
//! non-negative, so the opacity at `s` is non-zero exactly when some texel with non-zero alpha
//! has a non-zero weight at `s`. Texel `i` has a weight on the closed support
//! `[c_{i-1}, c_{i+1}]` (extended to `-∞` for `i = 0` and `+∞` for `i = N-1`), so `[lo, hi]`
//! may be visible iff some non-zero-alpha texel `i` has `c_{i-1} ≤ hi` and `c_{i+1} ≥ lo`, i.e.
//! `ceil(lo·N − 1.5) ≤ i ≤ floor(hi·N + 0.5)`. The supports are taken closed (a texel whose
//! weight is exactly zero at an end point still counts) and widened by [`VALUE_MARGIN`]: both
//! only ever turn "empty" into "visible", never the other way round.

use rayon::prelude::*;

use crate::minmax::MinMaxGrid;

/// Widening of every queried value range, in normalized units. Covers f32 rounding of the
/// interpolated value on the GPU (about 8 ulps at 1.0); it can only make a range visible.
pub const VALUE_MARGIN: f64 = 1e-6;

/// The largest number of bins per axis of a [`QuantizedTable`] (a 4096² texture, 16 MiB).
pub const MAX_TABLE_BINS: u32 = 4096;

/// Byte stored for "visible" in the tables and for "empty" in the flag arrays: reads as 1.0
/// through an `R8Unorm` texture and as non-zero through `R8Uint`.
pub const FLAG_SET: u8 = 255;

/// Why a classifier or table could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClassifyError {
    /// The LUT has no texels.
    #[error("the transfer-function LUT has no texels; it needs at least one RGBA entry")]
    EmptyLut,
    /// A quantized table was asked for with a bin count out of range.
    #[error("a quantized classification table needs 1..={max} bins per axis, got {bins}")]
    BinCount {
        /// The bins asked for.
        bins: u32,
        /// [`MAX_TABLE_BINS`].
        max: u32,
    },
}

/// O(1) "does any value in `[lo, hi]` map to non-zero opacity" queries over a LUT, with a prefix
/// sum over the LUT's non-zero-opacity texels (Krüger & Westermann 2003 §2.3).
#[derive(Clone, Debug, PartialEq)]
pub struct OpacityClassifier {
    texels: usize,
    /// `prefix[i]` = number of texels `< i` with non-zero alpha; `texels + 1` entries.
    prefix: Vec<u32>,
}

impl OpacityClassifier {
    /// Builds the classifier from an RGBA LUT (straight alpha in `[3]`). A NaN alpha counts as
    /// non-zero (the conservative choice).
    pub fn new(lut: &[[f32; 4]]) -> Result<Self, ClassifyError> {
        if lut.is_empty() {
            return Err(ClassifyError::EmptyLut);
        }
        let mut prefix = Vec::with_capacity(lut.len() + 1);
        let mut count = 0u32;
        prefix.push(0);
        for texel in lut {
            // NaN is not `<= 0`, so it counts as non-zero (conservative).
            if texel[3] > 0.0 || texel[3].is_nan() {
                count += 1;
            }
            prefix.push(count);
        }
        Ok(Self { texels: lut.len(), prefix })
    }

    /// `prefix[i]`: how many texels before `i` have non-zero (or NaN) alpha; `texels + 1`
    /// entries. The GPU classification (`shaders/empty_space.wgsl`) reads this very table.
    pub fn visible_before(&self) -> &[u32] {
        &self.prefix
    }

    /// Number of LUT texels.
    pub fn texels(&self) -> usize {
        self.texels
    }

    /// True when no texel has non-zero opacity (everything is empty).
    pub fn all_transparent(&self) -> bool {
        self.prefix[self.texels] == 0
    }

    /// The range of texels `first..=last` whose interpolation support touches `[lo, hi]`
    /// (widened by [`VALUE_MARGIN`]); the order of `lo` and `hi` does not matter.
    pub fn texel_span(&self, lo: f64, hi: f64) -> (usize, usize) {
        let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        let n = self.texels as f64;
        let last_texel = self.texels - 1;
        let first = ((lo - VALUE_MARGIN) * n - 1.5).ceil();
        let last = ((hi + VALUE_MARGIN) * n + 0.5).floor();
        // `as usize` saturates (negative → 0); NaN is caught first and widens to the whole LUT.
        if first.is_nan() || last.is_nan() {
            return (0, last_texel);
        }
        ((first as usize).min(last_texel), (last as usize).min(last_texel))
    }

    /// Whether some value in `[lo, hi]` (normalized) can map to non-zero opacity under the LUT's
    /// linear sampler. O(1). Conservative: `false` means every value in the range is fully
    /// transparent.
    #[inline]
    pub fn is_visible(&self, lo: f32, hi: f32) -> bool {
        let (first, last) = self.texel_span(lo as f64, hi as f64);
        self.prefix[last + 1] > self.prefix[first]
    }

    /// [`Self::is_visible`] for a `[min, max]` pair as stored by the grids.
    #[inline]
    pub fn is_range_visible(&self, range: [f32; 2]) -> bool {
        self.is_visible(range[0], range[1])
    }

    /// Krüger & Westermann's 2D "CT" texture for 8-bit data: 256 × 256 bytes, entry
    /// `min + 256·max` is [`FLAG_SET`] when some value in `[min/255, max/255]` is visible and
    /// 0 otherwise (raw u8 values; the table is symmetric, so swapped pairs read the same).
    pub fn table_u8(&self) -> Vec<u8> {
        let mut table = vec![0u8; 256 * 256];
        table.par_chunks_mut(256).enumerate().for_each(|(max, row)| {
            for (min, entry) in row.iter_mut().enumerate() {
                let (a, b) = (min.min(max) as f64 / 255.0, min.max(max) as f64 / 255.0);
                let (first, last) = self.texel_span(a, b);
                if self.prefix[last + 1] > self.prefix[first] {
                    *entry = FLAG_SET;
                }
            }
        });
        table
    }

    /// A `bins × bins` table for 16-bit and float data; see [`QuantizedTable`].
    pub fn quantized_table(&self, bins: u32) -> Result<QuantizedTable, ClassifyError> {
        if bins == 0 || bins > MAX_TABLE_BINS {
            return Err(ClassifyError::BinCount { bins, max: MAX_TABLE_BINS });
        }
        let q = bins as usize;
        let mut data = vec![0u8; q * q];
        data.par_chunks_mut(q).enumerate().for_each(|(bmax, row)| {
            for (bmin, entry) in row.iter_mut().enumerate() {
                // Round outward: the table entry stands for every `lo` in bin `bmin` and every
                // `hi` in bin `bmax`, so it classifies the whole span of both bins.
                let lo = bmin.min(bmax) as f64 / q as f64;
                let hi = (bmin.max(bmax) + 1) as f64 / q as f64;
                let (first, last) = self.texel_span(lo, hi);
                if self.prefix[last + 1] > self.prefix[first] {
                    *entry = FLAG_SET;
                }
            }
        });
        Ok(QuantizedTable { bins, data })
    }

    /// Fraction in `[0,1]` of the grid's blocks that are empty under this LUT.
    pub fn empty_fraction(&self, grid: &MinMaxGrid) -> f64 {
        let ranges = grid.ranges();
        let empty = ranges.par_iter().filter(|r| !self.is_range_visible(**r)).count();
        empty as f64 / ranges.len().max(1) as f64
    }

    /// Per-block empty flags, one byte per block in the grid's order (x fastest):
    /// [`FLAG_SET`] = empty (skip it), 0 = may be visible. Ready for an `R8Unorm`/`R8Uint` 3D
    /// texture of size `grid.dims()`.
    pub fn empty_flags(&self, grid: &MinMaxGrid) -> Vec<u8> {
        grid.ranges().par_iter().map(|r| if self.is_range_visible(*r) { 0 } else { FLAG_SET }).collect()
    }
}

/// A quantized (min, max) classification table for 16-bit and float data (Krüger & Westermann
/// 2003 §2.3 "CT", with `bins` classes instead of 256 values). A value `v` falls in bin
/// [`QuantizedTable::bin_of`]` = min(floor(v·bins), bins−1)` (clamped to `[0, bins−1]`), and
/// entry `bmin + bins·bmax` is [`FLAG_SET`] when anything in `[bmin/bins, (bmax+1)/bins]` is
/// visible: min is rounded down and max rounded up, so a look-up never calls a visible range
/// empty.
#[derive(Clone, Debug, PartialEq)]
pub struct QuantizedTable {
    bins: u32,
    data: Vec<u8>,
}

impl QuantizedTable {
    /// Bins per axis.
    pub fn bins(&self) -> u32 {
        self.bins
    }

    /// The table, `bins × bins` bytes, min fastest: the data of an `R8Unorm`/`R8Uint` 2D texture.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// The bin of normalized value `v`: `floor(v·bins)` clamped to `[0, bins−1]` (NaN → 0).
    #[inline]
    pub fn bin_of(&self, v: f32) -> u32 {
        ((v as f64 * self.bins as f64).floor().clamp(0.0, (self.bins - 1) as f64)) as u32
    }

    /// Whether `[lo, hi]` may be visible, via the table. Conservative like the table.
    #[inline]
    pub fn is_visible(&self, lo: f32, hi: f32) -> bool {
        let (a, b) = (self.bin_of(lo), self.bin_of(hi));
        self.data[(a + self.bins * b) as usize] != 0
    }
}
