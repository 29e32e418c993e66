//! Bricks (Ruijters & Vilanova 2006 §5) and per-brick octrees (§7): bricks reassemble to the
//! volume and hold every voxel their samples read; no visible sample falls in an empty brick
//! or outside the drawn octree boxes; with threshold 1 and node size 1 the boxes are exactly
//! the visible cells; boxes come out front to back.

mod accel_support;

use accel_support::{Rng, lut_alpha, probe_positions, random_lut, random_volume};
use glam::{DVec3, UVec3};
use proptest::prelude::*;
use volgraph_accel::bricks::{BrickLayout, BrickSet, ViewPoint, cell_dims};
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::minmax::GridError;
use volgraph_accel::octree::{CHILD_ORDERS, DrawBox, OctreeHierarchy, direction_sign_bits};
use volgraph_accel::volume::{Volume, VoxelData};

fn inside(u: DVec3, (lo, hi): (DVec3, DVec3)) -> bool {
    let u = u.clamp(DVec3::ZERO, DVec3::ONE);
    lo.cmple(u).all() && u.cmple(hi).all()
}

fn check_bricks(volume: &Volume, lut: &[[f32; 4]], brick_cells: u32, overlap: u32, seed: u64) {
    let set = BrickSet::build(volume, brick_cells, overlap).expect("valid input");
    assert_eq!(&set.reassemble(), volume, "bricks do not reassemble to the volume");
    let n = volume.dims;
    for brick in set.bricks() {
        // Each brick on its own holds exactly the volume's voxels at its place.
        for z in 0..brick.dims.z {
            for y in 0..brick.dims.y {
                for x in 0..brick.dims.x {
                    let v = brick.origin + UVec3::new(x, y, z);
                    let local = (x + brick.dims.x * (y + brick.dims.y * z)) as usize;
                    let expect = volume.normalized(volume.index(v.x, v.y, v.z));
                    let got = match &brick.data {
                        VoxelData::U8(d) => d[local] as f64 / 255.0,
                        VoxelData::F32(d) => {
                            let (lo, hi) = volume.value_range;
                            if hi > lo { (d[local] as f64 - lo) / (hi - lo) } else { 0.0 }
                        }
                        _ => unreachable!("tests only build u8 and f32 volumes"),
                    };
                    assert_eq!(got, expect);
                }
            }
        }
    }
    let memory = set.memory();
    assert!(memory.ratio >= 1.0 && memory.brick_bytes >= memory.volume_bytes);
    let classifier = OpacityClassifier::new(lut).expect("non-empty");
    let empty = set.empty_bricks(&classifier);
    let layout = set.layout();
    for u in probe_positions(n, seed, 1500) {
        let s = volume.sample_trilinear(u);
        // Probes on faces come out a few ulps off (e.g. 6.5/23·23 − 0.5); snap them back.
        let p = u * n.as_dvec3() - 0.5;
        let p = DVec3::select((p - p.round()).abs().cmplt(DVec3::splat(1e-9)), p.round(), p);
        let mut holders = 0;
        for (i, brick) in set.bricks().iter().enumerate() {
            if !inside(u, layout.brick_texture_box(brick.coord)) {
                continue;
            }
            holders += 1;
            // 1e-12: a probe on a brick face gives a neighbour voxel a weight of a few ulps
            // (see the snapping above); the classifier's VALUE_MARGIN absorbs that.
            assert!(
                brick.range[0] as f64 - 1e-12 <= s && s <= brick.range[1] as f64 + 1e-12,
                "sample {s} at {u} outside brick {} range {:?}",
                brick.coord,
                brick.range
            );
            if lut_alpha(lut, s) > 0.0 {
                assert!(!empty[i], "visible sample {s} at {u} in empty brick {}", brick.coord);
            }
            // The voxels trilinear interpolation reads (and, with overlap 2, those of the
            // central differences at ±1 voxel) with a non-zero weight are stored in the brick;
            // on a brick face (integer p) the next voxel has weight 0.
            let reach = overlap as f64 - 1.0;
            for a in 0..3 {
                let first = ((p[a] - reach).floor()).clamp(0.0, (n[a] - 1) as f64) as u32;
                let last = (p[a] + reach).ceil().clamp(0.0, (n[a] - 1) as f64) as u32;
                assert!(
                    brick.origin[a] <= first && last < brick.origin[a] + brick.dims[a],
                    "brick {} misses voxels {first}..={last} on axis {a} for {u}",
                    brick.coord
                );
            }
        }
        assert!(holders > 0, "{u} lies in no brick");
    }
}

/// Visible cells computed independently: cell c's corners c..=c+1 (clamped), outward rounding.
fn visible_cells(volume: &Volume, classifier: &OpacityClassifier) -> Vec<bool> {
    let n = volume.dims;
    let m = cell_dims(n);
    let mut out = Vec::new();
    for z in 0..m.z {
        for y in 0..m.y {
            for x in 0..m.x {
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for dz in 0..2 {
                    for dy in 0..2 {
                        for dx in 0..2 {
                            let v = (UVec3::new(x + dx, y + dy, z + dz)).min(n - 1);
                            let s = volume.normalized(volume.index(v.x, v.y, v.z));
                            lo = lo.min(s);
                            hi = hi.max(s);
                        }
                    }
                }
                let lo32 = if (lo as f32 as f64) > lo { (lo as f32).next_down() } else { lo as f32 };
                let hi32 = if ((hi as f32) as f64) < hi { (hi as f32).next_up() } else { hi as f32 };
                out.push(classifier.is_visible(lo32, hi32));
            }
        }
    }
    out
}

/// All boxes of all bricks, bricks in front-to-back order.
fn all_boxes(
    h: &OctreeHierarchy,
    vis: &volgraph_accel::octree::OctreeVisibility,
    t: f32,
    view: ViewPoint,
) -> Vec<DrawBox> {
    let mut boxes = Vec::new();
    for brick in h.layout().front_to_back(view) {
        h.draw_boxes(vis, brick as usize, t, view, &mut boxes);
    }
    boxes
}

/// Along rays through the volume, the boxes met must have non-decreasing positions in `boxes`.
fn check_front_to_back(h: &OctreeHierarchy, boxes: &[DrawBox], view: ViewPoint, seed: u64) {
    let mut rng = Rng::new(seed ^ 0xF00D);
    let tex: Vec<(DVec3, DVec3)> = boxes.iter().map(|b| h.texture_box(b)).collect();
    for _ in 0..40 {
        let target = DVec3::new(rng.unit(), rng.unit(), rng.unit());
        let (origin, dir) = match view {
            ViewPoint::Direction(d) => (target - d.normalize() * 2.0, d.normalize()),
            ViewPoint::Eye(e) => (e, (target - e).normalize()),
        };
        let mut last = 0usize;
        for k in 0..4000 {
            let u = origin + dir * (k as f64 * 0.001);
            // Strictly inside a box (faces are shared, so they say nothing about order).
            let hit = tex.iter().position(|(lo, hi)| (*lo + 1e-9).cmplt(u).all() && u.cmplt(*hi - 1e-9).all());
            if let Some(i) = hit {
                assert!(i >= last, "ray {origin}->{dir} meets box {i} after box {last}");
                last = i;
            }
        }
    }
}

fn random_view(rng: &mut Rng) -> ViewPoint {
    let d = DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5);
    let d = if d.length() < 1e-3 { DVec3::X } else { d };
    if rng.below(2) == 0 {
        ViewPoint::Direction(d)
    } else {
        ViewPoint::Eye(DVec3::splat(0.5) - d.normalize() * (0.2 + 2.0 * rng.unit()))
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn bricks_reassemble_and_keep_visible_samples(
        dims in (1u32..=24, 1u32..=24, 1u32..=24),
        float in any::<bool>(),
        brick_cells in 1u32..=10,
        overlap in 1u32..=2,
        seed in any::<u64>(),
    ) {
        let volume = random_volume(UVec3::new(dims.0, dims.1, dims.2), float, seed);
        check_bricks(&volume, &random_lut(seed), brick_cells, overlap, seed);
    }

    #[test]
    fn octree_boxes_hold_every_visible_sample(
        dims in (1u32..=24, 1u32..=24, 1u32..=24),
        float in any::<bool>(),
        brick_cells in 1u32..=12,
        min_node_cells in 1u32..=5,
        threshold in 0.05f32..=1.0,
        seed in any::<u64>(),
    ) {
        let volume = random_volume(UVec3::new(dims.0, dims.1, dims.2), float, seed);
        let lut = random_lut(seed);
        let layout = BrickLayout::new(volume.dims, brick_cells, 1).expect("valid");
        let h = OctreeHierarchy::build(&volume, &layout, min_node_cells).expect("valid");
        let classifier = OpacityClassifier::new(&lut).expect("non-empty");
        let vis = h.classify(&classifier);
        let view = random_view(&mut Rng::new(seed));
        let boxes = all_boxes(&h, &vis, threshold, view);
        let tex: Vec<_> = boxes.iter().map(|b| h.texture_box(b)).collect();
        for u in probe_positions(volume.dims, seed, 1500) {
            let s = volume.sample_trilinear(u);
            if lut_alpha(&lut, s) > 0.0 {
                prop_assert!(tex.iter().any(|b| inside(u, *b)), "visible sample {} at {} in no box", s, u);
            }
        }
        for b in &boxes {
            prop_assert!(b.ratio > 0.0 && b.ratio <= 1.0);
            let size = b.cells_hi - b.cells_lo;
            prop_assert!(b.ratio >= threshold || size.max_element() <= min_node_cells);
        }
        check_front_to_back(&h, &boxes, view, seed);
    }

    /// With threshold 1 and node size 1 the boxes cover exactly the visible cells, once each.
    #[test]
    fn exact_octree_covers_exactly_the_visible_cells(
        dims in (1u32..=16, 1u32..=16, 1u32..=16),
        float in any::<bool>(),
        brick_cells in 1u32..=9,
        seed in any::<u64>(),
    ) {
        let volume = random_volume(UVec3::new(dims.0, dims.1, dims.2), float, seed);
        let classifier = OpacityClassifier::new(&random_lut(seed)).expect("non-empty");
        let layout = BrickLayout::new(volume.dims, brick_cells, 1).expect("valid");
        let h = OctreeHierarchy::build(&volume, &layout, 1).expect("valid");
        let vis = h.classify(&classifier);
        let boxes = all_boxes(&h, &vis, 1.0, ViewPoint::Direction(DVec3::ONE));
        let m = cell_dims(volume.dims);
        let mut covered = vec![0u32; (m.x * m.y * m.z) as usize];
        for b in &boxes {
            prop_assert_eq!(b.ratio, 1.0);
            for z in b.cells_lo.z..b.cells_hi.z {
                for y in b.cells_lo.y..b.cells_hi.y {
                    for x in b.cells_lo.x..b.cells_hi.x {
                        covered[(x + m.x * (y + m.y * z)) as usize] += 1;
                    }
                }
            }
        }
        let expected: Vec<u32> = visible_cells(&volume, &classifier).iter().map(|v| *v as u32).collect();
        prop_assert_eq!(covered, expected);
    }

    /// Every one of the 8 orders is front to back: along any ray with that direction's signs,
    /// the children of a 2×2×2 node are entered in increasing order position.
    #[test]
    fn child_orders_are_front_to_back(d in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), seed in any::<u64>()) {
        let d = DVec3::new(d.0, d.1, d.2);
        prop_assume!(d.abs().min_element() > 1e-3);
        let order = CHILD_ORDERS[direction_sign_bits(d)];
        let position = |child: usize| order.iter().position(|c| *c as usize == child).expect("a permutation");
        let mut sorted = order;
        sorted.sort_unstable();
        prop_assert_eq!(sorted, [0, 1, 2, 3, 4, 5, 6, 7]);
        let mut rng = Rng::new(seed);
        let dir = d.normalize();
        for _ in 0..50 {
            let start = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 2.0 - dir * 4.0;
            let mut last = 0;
            for k in 0..8000 {
                let p = start + dir * (k as f64 * 0.001);
                if p.cmpgt(DVec3::ZERO).all() && p.cmplt(DVec3::splat(2.0)).all() {
                    let child = (p.x >= 1.0) as usize | ((p.y >= 1.0) as usize) << 1 | ((p.z >= 1.0) as usize) << 2;
                    let pos = position(child);
                    prop_assert!(pos >= last, "direction {} enters child {} after a later one", d, child);
                    last = pos;
                }
            }
        }
    }
}

fn lut_constant(alpha: f32) -> Vec<[f32; 4]> {
    vec![[1.0, 1.0, 1.0, alpha]; 32]
}

#[test]
fn one_voxel_volume() {
    let volume = Volume {
        dims: UVec3::ONE,
        spacing: DVec3::ONE,
        data: VoxelData::F32(vec![3.5]),
        name: "one".into(),
        value_range: (3.5, 3.5),
        meta: Default::default(),
    };
    let set = BrickSet::build(&volume, 64, 2).expect("valid");
    assert_eq!(set.bricks().len(), 1);
    assert_eq!(set.reassemble(), volume);
    assert_eq!(set.memory().ratio, 1.0);
    let layout = BrickLayout::new(volume.dims, 64, 1).expect("valid");
    let h = OctreeHierarchy::build(&volume, &layout, 8).expect("valid");
    assert_eq!((h.node_count(), h.leaf_count()), (1, 1));
    let opaque = OpacityClassifier::new(&lut_constant(1.0)).expect("non-empty");
    let boxes = all_boxes(&h, &h.classify(&opaque), 0.5, ViewPoint::Direction(DVec3::X));
    assert_eq!(boxes.len(), 1);
    assert_eq!(h.texture_box(&boxes[0]), (DVec3::ZERO, DVec3::ONE));
    check_bricks(&volume, &lut_constant(1.0), 1, 1, 3);
}

#[test]
fn dims_not_a_multiple_of_the_brick_size() {
    // 20 voxels → 19 cells → bricks of 8, 8 and 3 cells.
    let volume = random_volume(UVec3::new(20, 9, 5), false, 11);
    let set = BrickSet::build(&volume, 8, 1).expect("valid");
    assert_eq!(set.layout().grid_dims(), UVec3::new(3, 1, 1));
    let last = &set.bricks()[2];
    assert_eq!((last.origin, last.dims), (UVec3::new(16, 0, 0), UVec3::new(4, 9, 5)));
    let with_gradients = BrickSet::build(&volume, 8, 2).expect("valid");
    let middle = &with_gradients.bricks()[1];
    assert_eq!((middle.origin, middle.dims), (UVec3::new(7, 0, 0), UVec3::new(11, 9, 5)));
    assert!(with_gradients.memory().ratio > set.memory().ratio);
    for seed in 0..10 {
        check_bricks(&volume, &random_lut(seed), 8, 1 + (seed % 2) as u32, seed);
    }
}

#[test]
fn all_transparent_and_all_opaque_luts() {
    let volume = random_volume(UVec3::new(23, 17, 9), true, 5);
    let layout = BrickLayout::new(volume.dims, 8, 1).expect("valid");
    let set = BrickSet::build(&volume, 8, 1).expect("valid");
    let h = OctreeHierarchy::build(&volume, &layout, 2).expect("valid");
    let transparent = OpacityClassifier::new(&lut_constant(0.0)).expect("non-empty");
    assert!(set.empty_bricks(&transparent).iter().all(|e| *e));
    let vis = h.classify(&transparent);
    assert!(all_boxes(&h, &vis, 0.5, ViewPoint::Direction(DVec3::ONE)).is_empty());
    let opaque = OpacityClassifier::new(&lut_constant(1.0)).expect("non-empty");
    assert!(set.empty_bricks(&opaque).iter().all(|e| !*e));
    // Everything visible: each brick is drawn as one box (its root), r = 1.
    let mut vis = vis;
    h.classify_into(&opaque, &mut vis);
    let boxes = all_boxes(&h, &vis, 1.0, ViewPoint::Direction(DVec3::ONE));
    assert_eq!(boxes.len(), layout.brick_count());
    for b in &boxes {
        assert_eq!((b.cells_lo, b.cells_hi), layout.brick_cells_box(layout.brick_coord(b.brick as usize)));
        assert_eq!(b.ratio, 1.0);
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let volume = random_volume(UVec3::new(4, 4, 4), false, 1);
    assert_eq!(BrickSet::build(&volume, 0, 1), Err(GridError::ZeroSize { what: "brick_cells" }));
    let err = BrickSet::build(&volume, 8, 3).expect_err("overlap 3");
    assert_eq!(
        err.to_string(),
        "brick overlap must be 1 (trilinear) or 2 (trilinear with on-the-fly gradients), got 3"
    );
    let layout = BrickLayout::new(volume.dims, 8, 1).expect("valid");
    assert_eq!(OctreeHierarchy::build(&volume, &layout, 0), Err(GridError::ZeroSize { what: "min_node_cells" }));
    let other = BrickLayout::new(UVec3::new(5, 4, 4), 8, 1).expect("valid");
    assert_eq!(
        OctreeHierarchy::build(&volume, &other, 8).expect_err("mismatch").to_string(),
        "brick layout was built for a volume of dims [5, 4, 4], but the volume has dims [4, 4, 4]"
    );
}
