//! Min/max grid (Krüger & Westermann 2003 §2.3) and transfer-function classification: no
//! visible sample may fall in a block classified empty, and the tables agree with the
//! classifier.

mod accel_support;

use accel_support::{lut_alpha, probe_positions, random_lut, random_volume};
use glam::{DVec3, UVec3};
use proptest::prelude::*;
use volgraph_accel::classify::{ClassifyError, FLAG_SET, OpacityClassifier};
use volgraph_accel::minmax::{GridError, MinMaxGrid};
use volgraph_accel::volume::{Volume, VoxelData};

/// Blocks whose closed texture box contains `u` (clamped into [0,1]: the outer blocks bound
/// samples beyond the faces).
fn blocks_containing(grid: &MinMaxGrid, u: DVec3) -> Vec<UVec3> {
    let u = u.clamp(DVec3::ZERO, DVec3::ONE);
    let d = grid.dims();
    // Only blocks next to floor(u·n/B) can contain u; test those three per axis exactly.
    let guess = (u * grid.volume_dims().as_dvec3() / grid.block_size() as f64).floor();
    let near = |a: usize| {
        let g = guess[a] as i64;
        (g - 1).max(0) as u32..=((g + 1).min(d[a] as i64 - 1)) as u32
    };
    let mut out = Vec::new();
    for z in near(2) {
        for y in near(1) {
            for x in near(0) {
                let b = UVec3::new(x, y, z);
                let (lo, hi) = grid.block_texture_box(b);
                if lo.cmple(u).all() && u.cmple(hi).all() {
                    out.push(b);
                }
            }
        }
    }
    out
}

/// Checks every probe: a visible sample's blocks are all classified visible; returns how many
/// visible probes were checked.
fn check_grid(volume: &Volume, lut: &[[f32; 4]], block_size: u32, seed: u64) -> usize {
    let grid = MinMaxGrid::build(volume, block_size).expect("valid volume and block size");
    let classifier = OpacityClassifier::new(lut).expect("non-empty LUT");
    let flags = classifier.empty_flags(&grid);
    let mut visible = 0;
    for u in probe_positions(volume.dims, seed, 2000) {
        let s = volume.sample_trilinear(u);
        let blocks = blocks_containing(&grid, u);
        assert!(!blocks.is_empty(), "position {u} is in no block");
        for b in blocks {
            let range = grid.range(b);
            assert!(
                range[0] as f64 <= s && s <= range[1] as f64,
                "sample {s} at {u} outside block {b} range {range:?}"
            );
            if lut_alpha(lut, s) > 0.0 {
                assert!(classifier.is_range_visible(range), "visible sample {s} at {u} in empty block {b}");
                assert_eq!(flags[grid.block_index(b)], 0);
            }
        }
        if lut_alpha(lut, s) > 0.0 {
            visible += 1;
        }
    }
    visible
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn no_visible_sample_in_an_empty_block(
        dims in (1u32..=24, 1u32..=24, 1u32..=24),
        float in any::<bool>(),
        block_size in 1u32..=9,
        seed in any::<u64>(),
    ) {
        let volume = random_volume(UVec3::new(dims.0, dims.1, dims.2), float, seed);
        check_grid(&volume, &random_lut(seed), block_size, seed);
    }

    /// The classifier is exact up to the closed supports: a range whose every value (on a fine
    /// grid) is transparent may be visible only if a support end point lies within the margin;
    /// a range containing a visible value is always visible.
    #[test]
    fn classifier_matches_sampled_lut(seed in any::<u64>(), a in 0.0f64..1.0, b in 0.0f64..1.0) {
        let lut = random_lut(seed);
        let classifier = OpacityClassifier::new(&lut).expect("non-empty LUT");
        let (lo, hi) = (a.min(b), a.max(b));
        let any_visible = (0..=2000).any(|k| lut_alpha(&lut, lo + (hi - lo) * k as f64 / 2000.0) > 0.0);
        if any_visible {
            prop_assert!(classifier.is_visible(lo as f32, hi as f32));
        }
        // Widen by one LUT texel: if even that is transparent everywhere, the range is empty.
        let n = lut.len() as f64;
        let wide_visible = (0..=4000).any(|k| {
            let s = (lo - 1.0 / n) + (hi - lo + 2.0 / n) * k as f64 / 4000.0;
            lut_alpha(&lut, s) > 0.0
        });
        if !wide_visible {
            prop_assert!(!classifier.is_visible(lo as f32, hi as f32));
        }
    }

    /// The 8-bit table and the quantized table never call a visible range empty.
    #[test]
    fn tables_are_conservative(seed in any::<u64>(), lo in 0u8..=255, hi in 0u8..=255, bins in 1u32..=300) {
        let lut = random_lut(seed);
        let classifier = OpacityClassifier::new(&lut).expect("non-empty LUT");
        let table = classifier.table_u8();
        let visible = classifier.is_visible(lo as f32 / 255.0, hi as f32 / 255.0);
        prop_assert_eq!(table[lo as usize + 256 * hi as usize] == FLAG_SET, visible);
        let quantized = classifier.quantized_table(bins).expect("bins in range");
        let (a, b) = (lo.min(hi) as f32 / 255.0, lo.max(hi) as f32 / 255.0);
        if classifier.is_visible(a, b) {
            prop_assert!(quantized.is_visible(a, b));
        }
    }
}

fn lut_constant(alpha: f32, n: usize) -> Vec<[f32; 4]> {
    vec![[1.0, 1.0, 1.0, alpha]; n]
}

#[test]
fn one_voxel_volume() {
    let volume = Volume {
        dims: UVec3::ONE,
        spacing: DVec3::ONE,
        data: VoxelData::U8(vec![100]),
        name: "one".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    };
    let grid = MinMaxGrid::build(&volume, 8).expect("valid");
    assert_eq!(grid.dims(), UVec3::ONE);
    // The range is 100/255 rounded outward to f32: it brackets the exact value within an ulp.
    let [lo, hi] = grid.range(UVec3::ZERO);
    assert!(lo as f64 <= 100.0 / 255.0 && 100.0 / 255.0 <= hi as f64 && hi - lo < 1e-7);
    // A LUT visible only around 100/255 keeps the block; one visible only near 1 drops it.
    let mut lut = lut_constant(0.0, 256);
    lut[100][3] = 1.0;
    let classifier = OpacityClassifier::new(&lut).expect("non-empty");
    assert_eq!(classifier.empty_flags(&grid), vec![0]);
    let mut lut = lut_constant(0.0, 256);
    lut[250][3] = 1.0;
    let classifier = OpacityClassifier::new(&lut).expect("non-empty");
    assert_eq!(classifier.empty_flags(&grid), vec![FLAG_SET]);
    assert_eq!(classifier.empty_fraction(&grid), 1.0);
    check_grid(&volume, &lut, 1, 7);
}

#[test]
fn dims_not_a_multiple_of_the_block_size() {
    let volume = random_volume(UVec3::new(19, 8, 13), false, 42);
    let grid = MinMaxGrid::build(&volume, 8).expect("valid");
    assert_eq!(grid.dims(), UVec3::new(3, 1, 2));
    assert_eq!(grid.block_voxel_box(UVec3::new(2, 0, 1)), (UVec3::new(15, 0, 7), UVec3::new(18, 7, 12)));
    assert_eq!(grid.to_rg32float_bytes().len(), (3 * 2) * 8); // 3×1×2 blocks, 8 bytes each
    for seed in 0..20 {
        check_grid(&volume, &random_lut(seed), 8, seed);
    }
}

#[test]
fn apron_makes_a_neighbouring_voxel_count() {
    // One bright voxel at x = 8: block 0 (voxels 0..8) must see it through its apron, because
    // samples between voxel centres 7 and 8 lie in block 0 and interpolate voxel 8.
    let mut data = vec![0u8; 16];
    data[8] = 255;
    let volume = Volume {
        dims: UVec3::new(16, 1, 1),
        spacing: DVec3::ONE,
        data: VoxelData::U8(data),
        name: "spike".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    };
    let grid = MinMaxGrid::build(&volume, 8).expect("valid");
    assert_eq!(grid.range(UVec3::ZERO), [0.0, 1.0]);
    assert_eq!(grid.range(UVec3::X), [0.0, 1.0]);
}

#[test]
fn all_transparent_and_all_opaque_luts() {
    let volume = random_volume(UVec3::new(17, 9, 5), true, 3);
    let grid = MinMaxGrid::build(&volume, 4).expect("valid");
    let transparent = OpacityClassifier::new(&lut_constant(0.0, 64)).expect("non-empty");
    assert!(transparent.all_transparent());
    assert_eq!(transparent.empty_fraction(&grid), 1.0);
    assert!(transparent.table_u8().iter().all(|e| *e == 0));
    assert!(transparent.quantized_table(64).expect("ok").data().iter().all(|e| *e == 0));
    let opaque = OpacityClassifier::new(&lut_constant(1.0, 64)).expect("non-empty");
    assert_eq!(opaque.empty_fraction(&grid), 0.0);
    assert!(opaque.empty_flags(&grid).iter().all(|e| *e == 0));
    assert!(opaque.table_u8().iter().all(|e| *e == FLAG_SET));
}

#[test]
fn bad_input_is_a_typed_error() {
    let volume = random_volume(UVec3::new(4, 4, 4), false, 1);
    assert_eq!(MinMaxGrid::build(&volume, 0), Err(GridError::ZeroSize { what: "block_size" }));
    let mut broken = volume.clone();
    broken.data = VoxelData::U8(vec![0; 5]);
    let err = MinMaxGrid::build(&broken, 8).expect_err("length mismatch");
    assert_eq!(
        err.to_string(),
        "volume \"random-1\" holds 5 voxels but its dims [4, 4, 4] need 64; \
         the loader or generator built an inconsistent volume"
    );
    assert_eq!(OpacityClassifier::new(&[]), Err(ClassifyError::EmptyLut));
    let classifier = OpacityClassifier::new(&lut_constant(1.0, 4)).expect("non-empty");
    assert_eq!(classifier.quantized_table(0), Err(ClassifyError::BinCount { bins: 0, max: 4096 }));
}
