//! Per-brick octrees after Ruijters & Vilanova 2006 §7: every node knows the ratio `r` of
//! visible cells in its box, and a traversal emits the boxes worth drawing, front to back.
//!
//! The work is split as the paper wants it ("this calculation only needs to be performed when
//! the transfer function has changed"):
//! - once per volume, [`OctreeHierarchy::build`] stores for every brick the conservative value
//!   range of each *leaf* (a node of `min_node_cells³` cells, the octree limit of §7) and the
//!   cell count of every node; this reads every voxel and does not depend on the TF;
//! - per TF, [`OctreeHierarchy::classify_into`] classifies each leaf in O(1)
//!   ([`OpacityClassifier`]) and sums visible-cell counts from the leaves up. It touches one
//!   value range per leaf and one counter per node, never a voxel.
//!
//! Cells are those of [`crate::bricks`] (the box between voxel centres, border cells extended
//! to the volume faces). A leaf is visible when its range (the min/max of all its cells' corner
//! voxels) is, and then all its cells count as visible: `r` is the exact ratio of visible cells
//! of §7 when `min_node_cells = 1`, and an upper bound of it otherwise (nodes below the limit
//! are never traversed, so nothing finer is needed to draw).
//!
//! Nodes that do not fit in a brick whose cell count is not `min_node_cells · 2^k` are clipped
//! to the brick; a clipped node has fewer than eight children.

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use crate::bricks::{BrickLayout, ViewPoint, cells_corner_voxels, cells_texture_box};
use crate::classify::OpacityClassifier;
use crate::minmax::{GridError, check_volume, voxel_box_range};
use crate::volume::Volume;

/// The 8 front-to-back child orders of Ruijters & Vilanova 2006 §7. Children are numbered by
/// their position bits (`x = 1, y = 2, z = 4`, bit set = upper half); the order is indexed by
/// the sign bits of the view direction (bit set = the view goes towards −axis, so the upper
/// child is nearer). `CHILD_ORDERS[s][k] = k ^ s`: a child that occludes another is nearer on
/// every axis where they differ, so its rank `child ^ s` is a bit subset of the other's and
/// comes first.
pub const CHILD_ORDERS: [[u8; 8]; 8] = {
    let mut orders = [[0u8; 8]; 8];
    let mut s = 0;
    while s < 8 {
        let mut k = 0;
        while k < 8 {
            orders[s][k] = (k ^ s) as u8;
            k += 1;
        }
        s += 1;
    }
    orders
};

/// Sign bits of a direction for [`CHILD_ORDERS`]: bit `a` set when `dir[a] < 0`.
pub fn direction_sign_bits(dir: DVec3) -> usize {
    (dir.x < 0.0) as usize | ((dir.y < 0.0) as usize) << 1 | ((dir.z < 0.0) as usize) << 2
}

/// One level of a brick's octree, stored dense (x fastest) inside the brick's node arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Level {
    /// Nodes per axis.
    dims: UVec3,
    /// Index of the level's first node in the node arrays.
    offset: usize,
}

/// The TF-independent part of one brick's octree.
#[derive(Clone, Debug, PartialEq)]
struct BrickTree {
    cells_lo: UVec3,
    cells_hi: UVec3,
    /// Level 0 is the leaves; the last level is the root (one node).
    levels: Vec<Level>,
    /// Per leaf: `[min, max]` normalized over its cells' corner voxels, rounded outward.
    leaf_ranges: Vec<[f32; 2]>,
    /// Per node (all levels): number of cells in its (clipped) box.
    node_cells: Vec<u32>,
}

/// Per-brick octrees' TF-independent data (Ruijters & Vilanova 2006 §7), built once per volume.
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeHierarchy {
    layout: BrickLayout,
    min_node_cells: u32,
    trees: Vec<BrickTree>,
}

/// The TF-dependent part: visible-cell counts of every node of every brick, from
/// [`OctreeHierarchy::classify`]. Reuse it with [`OctreeHierarchy::classify_into`] to rebuild
/// after a TF change without allocating.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OctreeVisibility {
    visible_cells: Vec<Vec<u32>>,
}

impl OctreeVisibility {
    /// Visible cells of the whole brick `brick` (its root node).
    pub fn brick_visible_cells(&self, brick: usize) -> u32 {
        self.visible_cells[brick].last().copied().unwrap_or(0)
    }
}

/// A box to draw, from [`OctreeHierarchy::draw_boxes`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawBox {
    /// Brick index in the layout.
    pub brick: u32,
    /// First cell of the box (volume cell coordinates).
    pub cells_lo: UVec3,
    /// One past the last cell.
    pub cells_hi: UVec3,
    /// Ratio of visible cells in the box, in `(0, 1]`.
    pub ratio: f32,
}

impl OctreeHierarchy {
    /// Builds every brick's leaf ranges and node cell counts, in parallel over bricks. Leaves
    /// are `min_node_cells³` cells (the paper's octree limit, e.g. 8).
    pub fn build(volume: &Volume, layout: &BrickLayout, min_node_cells: u32) -> Result<Self, GridError> {
        Self::build_with_apron(volume, layout, min_node_cells, 0)
    }

    /// [`Self::build`] with each leaf's value range taken over its cells' corner voxels and
    /// `apron` more voxels on every side (clamped to the volume): what a reconstruction wider
    /// than trilinear reads for a sample in the leaf (the tricubic B-spline: 1), so a leaf is
    /// empty only where nothing it shows can be visible.
    pub fn build_with_apron(
        volume: &Volume,
        layout: &BrickLayout,
        min_node_cells: u32,
        apron: u32,
    ) -> Result<Self, GridError> {
        if min_node_cells == 0 {
            return Err(GridError::ZeroSize { what: "min_node_cells" });
        }
        check_volume(volume)?;
        if layout.volume_dims() != volume.dims {
            return Err(GridError::MismatchedVolume {
                what: "brick layout",
                expected: layout.volume_dims(),
                found: volume.dims,
            });
        }
        let trees = (0..layout.brick_count())
            .into_par_iter()
            .map(|i| {
                let (lo, hi) = layout.brick_cells_box(layout.brick_coord(i));
                build_tree(volume, lo, hi, min_node_cells, apron)
            })
            .collect();
        Ok(Self { layout: *layout, min_node_cells, trees })
    }

    /// The brick layout.
    pub fn layout(&self) -> &BrickLayout {
        &self.layout
    }

    /// Leaf edge length in cells.
    pub fn min_node_cells(&self) -> u32 {
        self.min_node_cells
    }

    /// Total number of octree nodes over all bricks.
    pub fn node_count(&self) -> usize {
        self.trees.iter().map(|t| t.node_cells.len()).sum()
    }

    /// Number of leaves over all bricks.
    pub fn leaf_count(&self) -> usize {
        self.trees.iter().map(|t| t.leaf_ranges.len()).sum()
    }

    /// Visible-cell counts of every node under `classifier`.
    pub fn classify(&self, classifier: &OpacityClassifier) -> OctreeVisibility {
        let mut visibility = OctreeVisibility::default();
        self.classify_into(classifier, &mut visibility);
        visibility
    }

    /// Recomputes `visibility` for a new TF: one O(1) classification per leaf, then sums up the
    /// levels (§7: a node's ratio is the average of its children's, weighted by cells). Work is
    /// proportional to the number of nodes; in parallel over bricks.
    pub fn classify_into(&self, classifier: &OpacityClassifier, visibility: &mut OctreeVisibility) {
        visibility.visible_cells.resize_with(self.trees.len(), Vec::new);
        self.trees.par_iter().zip(visibility.visible_cells.par_iter_mut()).for_each(|(tree, counts)| {
            counts.resize(tree.node_cells.len(), 0);
            let leaves = tree.leaf_ranges.len();
            for ((count, range), cells) in counts[..leaves].iter_mut().zip(&tree.leaf_ranges).zip(&tree.node_cells) {
                *count = if classifier.is_range_visible(*range) { *cells } else { 0 };
            }
            for pair in tree.levels.windows(2) {
                let (child, parent) = (pair[0], pair[1]);
                let (below, above) = counts.split_at_mut(parent.offset);
                let children = &below[child.offset..];
                let parents = &mut above[..parent.dims.element_product() as usize];
                parents.fill(0);
                sum_into_parents(children, child.dims, parents, parent.dims);
            }
        });
    }

    /// Appends to `out` the boxes of brick `brick` to draw, front to back for `view`
    /// (Ruijters & Vilanova 2006 §7): nodes with `r = 0` are skipped, nodes with
    /// `r ≥ threshold` and non-empty leaves are drawn whole, others are split. With
    /// `threshold = 1` and `min_node_cells = 1` the boxes are exactly the visible cells.
    /// `brick` must be below the layout's brick count (indexing panics otherwise, like a slice).
    pub fn draw_boxes(
        &self,
        visibility: &OctreeVisibility,
        brick: usize,
        threshold: f32,
        view: ViewPoint,
        out: &mut Vec<DrawBox>,
    ) {
        let tree = &self.trees[brick];
        let counts = &visibility.visible_cells[brick];
        let root = tree.levels.len() - 1;
        self.visit(tree, counts, brick, root, UVec3::ZERO, threshold, view, out);
    }

    /// Texture-space box of a [`DrawBox`].
    pub fn texture_box(&self, b: &DrawBox) -> (DVec3, DVec3) {
        cells_texture_box(self.layout.volume_dims(), b.cells_lo, b.cells_hi)
    }

    /// Cell box `lo..hi` of node `coord` at `level` of `tree`.
    fn node_cells_box(&self, tree: &BrickTree, level: usize, coord: UVec3) -> (UVec3, UVec3) {
        let span = self.min_node_cells << level;
        let lo = tree.cells_lo + coord * span;
        let hi = lo.saturating_add(UVec3::splat(span)).min(tree.cells_hi);
        (lo, hi)
    }

    #[allow(clippy::too_many_arguments, reason = "private recursion carrying its context")]
    fn visit(
        &self,
        tree: &BrickTree,
        counts: &[u32],
        brick: usize,
        level: usize,
        coord: UVec3,
        threshold: f32,
        view: ViewPoint,
        out: &mut Vec<DrawBox>,
    ) {
        let l = tree.levels[level];
        let index = l.offset + (coord.x + l.dims.x * (coord.y + l.dims.y * coord.z)) as usize;
        let (visible, total) = (counts[index], tree.node_cells[index]);
        if visible == 0 || total == 0 {
            return;
        }
        let ratio = visible as f32 / total as f32;
        if ratio >= threshold || level == 0 {
            let (cells_lo, cells_hi) = self.node_cells_box(tree, level, coord);
            out.push(DrawBox { brick: brick as u32, cells_lo, cells_hi, ratio });
            return;
        }
        let signs = match view {
            ViewPoint::Direction(d) => direction_sign_bits(d),
            ViewPoint::Eye(eye) => {
                // The children split at the node's middle cell boundary; cell boundary c lies
                // at the centre of voxel c, u = (c + 0.5) / n.
                let (lo, _) = self.node_cells_box(tree, level, coord);
                let split = lo + (self.min_node_cells << (level - 1));
                let split_u = (split.as_dvec3() + 0.5) / self.layout.volume_dims().as_dvec3();
                direction_sign_bits(split_u - eye)
            }
        };
        let child_dims = tree.levels[level - 1].dims;
        for &child in &CHILD_ORDERS[signs] {
            let offset = UVec3::new(child as u32 & 1, (child as u32 >> 1) & 1, child as u32 >> 2);
            let c = coord * 2 + offset;
            if c.cmplt(child_dims).all() {
                self.visit(tree, counts, brick, level - 1, c, threshold, view, out);
            }
        }
    }
}

fn sum_into_parents(children: &[u32], cd: UVec3, parents: &mut [u32], pd: UVec3) {
    let (cx, cy) = (cd.x as usize, cd.y as usize);
    let (px, py) = (pd.x as usize, pd.y as usize);
    for z in 0..cd.z as usize {
        for y in 0..cy {
            let row = &children[cx * (y + cy * z)..][..cx];
            let prow = &mut parents[px * (y / 2 + py * (z / 2))..][..px];
            for (x, c) in row.iter().enumerate() {
                prow[x / 2] += c;
            }
        }
    }
}

fn build_tree(volume: &Volume, cells_lo: UVec3, cells_hi: UVec3, min_node_cells: u32, apron: u32) -> BrickTree {
    let extent = cells_hi - cells_lo;
    let leaf_dims = (extent - 1) / min_node_cells + 1;
    let mut levels = Vec::new();
    let mut dims = leaf_dims;
    let mut offset = 0;
    loop {
        levels.push(Level { dims, offset });
        offset += dims.element_product() as usize;
        if dims == UVec3::ONE {
            break;
        }
        dims = (dims + 1) / 2;
    }
    let mut leaf_ranges = Vec::with_capacity(leaf_dims.element_product() as usize);
    let mut node_cells = vec![0u32; offset];
    for z in 0..leaf_dims.z {
        for y in 0..leaf_dims.y {
            for x in 0..leaf_dims.x {
                let lo = cells_lo + UVec3::new(x, y, z) * min_node_cells;
                let hi = lo.saturating_add(UVec3::splat(min_node_cells)).min(cells_hi);
                let (vlo, vhi) = cells_corner_voxels(volume.dims, lo, hi);
                let (vlo, vhi) = (vlo.saturating_sub(UVec3::splat(apron)), (vhi + apron).min(volume.dims - 1));
                node_cells[leaf_ranges.len()] = (hi - lo).element_product();
                leaf_ranges.push(voxel_box_range(volume, vlo, vhi));
            }
        }
    }
    for pair in levels.windows(2) {
        let (child, parent) = (pair[0], pair[1]);
        let (below, above) = node_cells.split_at_mut(parent.offset);
        sum_into_parents(&below[child.offset..], child.dims, above, parent.dims);
    }
    BrickTree { cells_lo, cells_hi, levels, leaf_ranges, node_cells }
}
