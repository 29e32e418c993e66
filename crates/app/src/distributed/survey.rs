//! The first pass of a sort-last render: the file is read once in total, split in z-slabs
//! between the processes, for what every process must agree on before it knows its box — the
//! value range of float data, the whole volume's histogram (what the default transfer function
//! and the data's automatic values are fitted to, as one process fits them), a subsampled
//! preview, and per-brick histograms (what `need` finds the bricks the view needs in, which the
//! kd-tree balances).

use glam::UVec3;
use volgraph_accel::histogram::{FIT_BINS, Histogram, ValueSummary};
use volgraph_accel::kd_split::{BrickWeights, KdTree, SplitError};
use volgraph_accel::load::VolumeHeader;
use volgraph_accel::volume::{Volume, VoxelData, VoxelType};
use volgraph_composite::{Exchange, agree, all_gather};

/// Histogram bins per brick: one per LUT texel (`inputs::LUT_SIZE`).
pub const BINS: usize = crate::inputs::LUT_SIZE;
/// The brick edges the decomposition may use, in voxels (split planes lie on brick faces),
/// coarsest first: 16 keeps the per-brick histograms small; a small volume split between many
/// ranks takes finer bricks ([`brick_for`]).
const BRICKS: [u32; 5] = [16, 8, 4, 2, 1];
/// The most memory the per-brick histograms may take: a finer brick than this allows is not
/// tried.
const MAX_BIN_BYTES: u64 = 256 << 20;
/// The preview's longest side, in voxels.
const PREVIEW: u32 = 64;

/// What every process knows of the whole volume after the survey.
pub struct Survey {
    /// The range values normalize over (the type range, or the finite min/max of float data).
    pub value_range: (f64, f64),
    /// The volume subsampled every `stride` voxels (its spacing scaled to match).
    pub preview: Volume,
    /// The brick edge of the per-brick histograms ([`brick_for`]).
    pub brick: u32,
    /// Voxels per brick per normalized-value bin, brick-major.
    pub bins: Vec<u64>,
    /// The whole volume's histogram, value range and units: what the default transfer function
    /// and the data's automatic values are fitted to, exactly as one process fits them.
    pub values: ValueSummary,
    /// Voxels this process read.
    pub bytes_read: u64,
}

#[cfg(test)]
impl Survey {
    /// A survey of only per-brick histograms (`bins`, brick-major), for tests of what uses them.
    pub fn for_tests(brick: u32, bins: Vec<u64>) -> Self {
        let preview = Volume::new("test", UVec3::ONE, glam::DVec3::ONE, VoxelData::U8(vec![0]));
        let values = ValueSummary {
            histogram: Histogram { total: 0, counts: vec![0; FIT_BINS] },
            value_range: (0.0, 255.0),
            ct_hu: false,
        };
        Self { value_range: (0.0, 255.0), preview, brick, bins, values, bytes_read: 0 }
    }
}

/// The coarsest brick edge of [`BRICKS`] at which a volume of `dims` splits into the boxes of
/// `factors` (where each level finds enough brick faces), or the error at the finest tried.
pub fn brick_for(dims: UVec3, factors: &[usize]) -> Result<u32, SplitError> {
    let mut last = Err(SplitError::NoParts);
    for brick in BRICKS {
        // Checked before the weights are made: a finer brick than the histograms can afford is
        // not tried (the coarsest always is, as the loaders' checks bound the volume).
        if brick < BRICKS[0] && BrickWeights::count(dims, brick).saturating_mul((BINS * 8) as u64) > MAX_BIN_BYTES {
            break;
        }
        last = KdTree::balanced(&BrickWeights::zeros(dims, brick), factors).map(|_| brick);
        if last.is_ok() {
            break;
        }
    }
    last
}

fn stride_of(dims: UVec3) -> u32 {
    dims.max_element().div_ceil(PREVIEW).max(1)
}

/// This process's z-slab: whole preview slices (multiples of the stride), an equal share.
fn slab(dims: UVec3, stride: u32, rank: usize, size: usize) -> std::ops::Range<u32> {
    let slices = dims.z.div_ceil(stride) as usize;
    let (j0, j1) = (slices * rank / size, slices * (rank + 1) / size);
    (j0 as u32 * stride).min(dims.z)..(j1 as u32 * stride).min(dims.z)
}

/// Surveys `header`'s file with every process of `ex`, with per-brick histograms of bricks of
/// edge `brick` ([`brick_for`]).
pub fn survey<E: Exchange + ?Sized>(ex: &mut E, header: &VolumeHeader, brick: u32) -> Result<Survey, String> {
    let (rank, size) = (ex.rank(), ex.size());
    let dims = header.dims;
    let stride = stride_of(dims);
    let z = slab(dims, stride, rank, size);
    let fail = |e: volgraph_composite::ExchangeError| e.to_string();
    // Float data normalizes over its finite range: agree on it first.
    let value_range = match header.type_range() {
        Some(range) => range,
        None => {
            let read = header.finite_range(z.clone());
            let lo_hi = *read.as_ref().unwrap_or(&(f64::INFINITY, f64::NEG_INFINITY));
            agree(ex, read.map(drop).map_err(|e| e.to_string())).map_err(fail)?;
            let mine = [lo_hi.0, lo_hi.1].iter().flat_map(|v| v.to_le_bytes()).collect();
            let all = all_gather(ex, mine).map_err(fail)?;
            let (lo, hi) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| {
                let v = |i: usize| {
                    m.get(8 * i..8 * i + 8).map_or(f64::NAN, |b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
                };
                (lo.min(v(0)), hi.max(v(1)))
            });
            if lo <= hi { (lo, hi) } else { (0.0, 0.0) }
        }
    };
    let n_bricks = BrickWeights::zeros(dims, brick).weight.len();
    let mut bins = vec![0u64; n_bricks * BINS];
    let preview_dims = UVec3::new(dims.x.div_ceil(stride), dims.y.div_ceil(stride), dims.z.div_ceil(stride));
    let mut preview_part: Vec<f32> = Vec::new();
    let mut fit = vec![0u64; FIT_BINS];
    let weights = BrickWeights::zeros(dims, brick);
    let mut bytes_read = 0u64;
    let read = header.for_each_slab(z.clone(), stride, value_range, |z0, v| {
        bytes_read += v.voxel_count() as u64 * header.dtype.size_bytes() as u64;
        for lz in 0..v.dims.z {
            for y in 0..v.dims.y {
                for x in 0..v.dims.x {
                    let i = v.index(x, y, lz);
                    let s = v.normalized(i);
                    let bin = ((s * BINS as f64) as usize).min(BINS - 1);
                    bins[weights.brick_of(UVec3::new(x, y, z0 + lz)) * BINS + bin] += 1;
                    // As `Histogram::of` bins: non-finite values count in bin 0.
                    fit[if s.is_finite() { ((s * FIT_BINS as f64) as usize).min(FIT_BINS - 1) } else { 0 }] += 1;
                }
            }
        }
        // The preview slice at z0 (a multiple of the stride).
        for y in (0..v.dims.y).step_by(stride as usize) {
            for x in (0..v.dims.x).step_by(stride as usize) {
                preview_part.push(v.raw_value(v.index(x, y, 0)) as f32);
            }
        }
    });
    agree(ex, read.map_err(|e| e.to_string())).map_err(fail)?;
    // Everyone gets the histograms (summed) and the preview slices (in rank order = z order).
    let summed = summed_over_ranks(ex, &bins).map_err(fail)?;
    let fit_summed = summed_over_ranks(ex, &fit).map_err(fail)?;
    let all_preview = all_gather(ex, preview_part.iter().flat_map(|v| v.to_le_bytes()).collect()).map_err(fail)?;
    let values: Vec<f32> = all_preview
        .iter()
        .flat_map(|m| m.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap_or([0; 4]))))
        .collect();
    if values.len() != (preview_dims.x * preview_dims.y * preview_dims.z) as usize {
        return Err(format!("internal: the preview has {} voxels, expected {preview_dims}", values.len()));
    }
    let data = match header.dtype {
        VoxelType::U8 => VoxelData::U8(values.iter().map(|v| *v as u8).collect()),
        VoxelType::U16 => VoxelData::U16(values.iter().map(|v| *v as u16).collect()),
        VoxelType::I16 => VoxelData::I16(values.iter().map(|v| *v as i16).collect()),
        VoxelType::F32 => VoxelData::F32(values),
    };
    let mut preview = Volume::new(header.name.clone(), preview_dims, header.spacing * stride as f64, data);
    preview.value_range = value_range;
    preview.meta = header.meta.clone();
    let values = ValueSummary {
        histogram: Histogram { total: fit_summed.iter().sum(), counts: fit_summed },
        value_range,
        ct_hu: header.meta.is_ct_hu(),
    };
    Ok(Survey { value_range, preview, values, brick, bins: summed, bytes_read })
}

/// Every rank's `counts`, added element by element: the counts of the whole file.
fn summed_over_ranks<E: Exchange + ?Sized>(
    ex: &mut E,
    counts: &[u64],
) -> Result<Vec<u64>, volgraph_composite::ExchangeError> {
    let mut summed = vec![0u64; counts.len()];
    for m in &all_gather(ex, u64_bytes(counts))? {
        for (s, c) in summed.iter_mut().zip(m.chunks_exact(8)) {
            *s += u64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
        }
    }
    Ok(summed)
}

fn u64_bytes(v: &[u64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_cover_the_volume_once() {
        let dims = UVec3::new(10, 10, 130);
        let stride = stride_of(dims);
        for size in 1..6 {
            let mut next = 0;
            for rank in 0..size {
                let z = slab(dims, stride, rank, size);
                assert_eq!(z.start, next);
                assert_eq!(z.start % stride, 0);
                next = z.end;
            }
            assert_eq!(next, dims.z);
        }
    }

    /// `-n 3` and `-n 6` on a 32³ volume: two 16-voxel bricks per axis cannot make three slabs,
    /// 8-voxel bricks can (the split said "no brick face to split at" before).
    #[test]
    fn a_small_volume_split_between_many_ranks_takes_finer_bricks() {
        let dims = UVec3::splat(32);
        assert_eq!(brick_for(dims, &[2]), Ok(16));
        assert_eq!(brick_for(dims, &[3]), Ok(8));
        assert_eq!(brick_for(dims, &[3, 2]), Ok(8));
        assert_eq!(brick_for(dims, &[2, 2, 2, 2, 2, 2]), Ok(8));
        // Only what truly cannot be split is refused: 5 slabs of a 4-voxel axis.
        let err = brick_for(UVec3::new(4, 1, 1), &[5]).expect_err("4 voxels cannot make 5 boxes");
        assert!(err.to_string().contains("cannot be split into 5 boxes"), "{err}");
    }
}
