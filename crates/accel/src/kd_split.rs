//! Sort-last decomposition (`docs/scaling.md`): a kd-tree over the brick grid splits a volume
//! into one box per process, balanced by the voxels visible under the transfer function (at the
//! last level, by the bounding boxes of those a process holds), and gives, for any eye position,
//! an order of the boxes in which every ray from the eye meets them front to back — the order
//! their images composite in with the *over* operator.
//!
//! The tree is k-ary where radix-k compositing (Peterka et al. 2009) wants it: a node splits
//! into `factors[level]` slabs along one axis, so each compositing round combines the images of
//! one node's children, which are contiguous in every visibility order.

use glam::{DVec3, UVec3};

/// A half-open box of voxels `[lo, hi)` of the whole volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct VoxelBox {
    /// First voxel per axis.
    pub lo: UVec3,
    /// One past the last voxel per axis.
    pub hi: UVec3,
}

impl VoxelBox {
    /// The box `[lo, hi)`.
    pub fn new(lo: UVec3, hi: UVec3) -> Self {
        Self { lo, hi }
    }

    /// The voxels per axis.
    pub fn size(&self) -> UVec3 {
        self.hi.saturating_sub(self.lo)
    }

    /// The number of voxels.
    pub fn voxels(&self) -> u64 {
        let s = self.size();
        s.x as u64 * s.y as u64 * s.z as u64
    }

    /// The box grown by `apron` voxels on every side, within a volume of `dims`: what a process
    /// must hold for its filters (trilinear, gradients, tricubic) to see the same values at its
    /// box's faces as the whole volume gives.
    pub fn with_apron(&self, apron: u32, dims: UVec3) -> Self {
        Self { lo: self.lo.saturating_sub(UVec3::splat(apron)), hi: (self.hi + UVec3::splat(apron)).min(dims) }
    }
}

/// The weight of each brick of a volume: what the split balances.
#[derive(Clone, Debug, PartialEq)]
pub struct BrickWeights {
    /// Voxels per axis of the whole volume.
    pub dims: UVec3,
    /// The brick edge in voxels (the split planes lie on brick faces).
    pub brick: u32,
    /// One weight per brick, x fastest: what the split balances (`render --distributed`: the
    /// voxels of the bricks the view needs).
    pub weight: Vec<u64>,
}

impl BrickWeights {
    /// Bricks per axis.
    pub fn bricks(dims: UVec3, brick: u32) -> UVec3 {
        let b = brick.max(1);
        UVec3::new(dims.x.div_ceil(b), dims.y.div_ceil(b), dims.z.div_ceil(b))
    }

    /// How many bricks of `brick` voxels a volume of `dims` has (in u64: no overflow for any
    /// dims, so callers can check it before [`Self::zeros`] allocates a weight for each).
    pub fn count(dims: UVec3, brick: u32) -> u64 {
        let n = Self::bricks(dims, brick);
        n.x as u64 * n.y as u64 * n.z as u64
    }

    /// Zero weights for `dims` in bricks of `brick` voxels.
    pub fn zeros(dims: UVec3, brick: u32) -> Self {
        let n = Self::bricks(dims, brick);
        let count = n.x as usize * n.y as usize * n.z as usize;
        Self { dims, brick: brick.max(1), weight: vec![0; count] }
    }

    /// The index of the brick holding voxel `v`.
    pub fn brick_of(&self, v: UVec3) -> usize {
        let n = Self::bricks(self.dims, self.brick);
        let b = v / self.brick;
        (b.x + n.x * (b.y + n.y * b.z)) as usize
    }

    /// The weight of the voxels of `bx` (in voxels, on brick faces) — the sum of its bricks'.
    fn weight_of(&self, bx: &VoxelBox) -> u64 {
        let n = Self::bricks(self.dims, self.brick);
        let (lo, hi) = (bx.lo / self.brick, (bx.hi + UVec3::splat(self.brick - 1)) / self.brick);
        let mut sum = 0;
        for z in lo.z..hi.z {
            for y in lo.y..hi.y {
                for x in lo.x..hi.x {
                    sum += self.weight[(x + n.x * (y + n.y * z)) as usize];
                }
            }
        }
        sum
    }
}

/// Why a volume cannot be split.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SplitError {
    /// Fewer bricks than processes along the axes a node can split.
    #[error(
        "a volume of {dims} voxels in bricks of {brick} cannot be split into {parts} boxes: a box of {size} voxels \
         has no brick face to split at; use fewer processes (mpirun -n) or a larger volume"
    )]
    TooSmall {
        /// The whole volume.
        dims: String,
        /// The brick edge.
        brick: u32,
        /// The parts asked of one box.
        parts: usize,
        /// That box.
        size: String,
    },
    /// No processes.
    #[error("cannot split a volume into 0 boxes")]
    NoParts,
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    /// The box of process `rank`.
    Leaf { rank: usize },
    /// Children along `axis`, in increasing coordinate, separated at the planes `at`
    /// (`at.len() == children.len() - 1`).
    Split { axis: usize, at: Vec<u32>, children: Vec<usize> },
}

/// The decomposition of a volume into one box per process.
#[derive(Clone, Debug, PartialEq)]
pub struct KdTree {
    /// The whole volume's voxels per axis.
    pub dims: UVec3,
    /// The box of each process, by rank.
    pub boxes: Vec<VoxelBox>,
    /// The children per level, top first (their product is the number of boxes).
    pub factors: Vec<usize>,
    nodes: Vec<Node>,
}

impl KdTree {
    /// Splits the volume of `weights` into `factors.iter().product()` boxes: the top node into
    /// `factors[0]` slabs along its longest axis that can be split, each of those into
    /// `factors[1]`, and so on; every plane lies on a brick face and is placed so that the
    /// slabs' weights are as equal as the bricks allow — at the last level, whose slabs are
    /// processes' boxes, so that the largest bounding box of weighted bricks a slab holds is
    /// smallest (a process holds that box). A node with no weight splits by voxel count (equal
    /// volume). Ranks are numbered in tree order, so the ranks of any node are
    /// consecutive.
    pub fn balanced(weights: &BrickWeights, factors: &[usize]) -> Result<Self, SplitError> {
        if factors.contains(&0) || factors.is_empty() {
            return Err(SplitError::NoParts);
        }
        let mut tree = Self { dims: weights.dims, boxes: Vec::new(), factors: factors.to_vec(), nodes: Vec::new() };
        tree.split(weights, VoxelBox::new(UVec3::ZERO, weights.dims), 0)?;
        Ok(tree)
    }

    /// A split into `ranks` boxes, one level per prime factor of `ranks` (largest first).
    pub fn balanced_into(weights: &BrickWeights, ranks: usize) -> Result<Self, SplitError> {
        Self::balanced(weights, &prime_factors(ranks))
    }

    fn split(&mut self, weights: &BrickWeights, bx: VoxelBox, level: usize) -> Result<usize, SplitError> {
        let index = self.nodes.len();
        if level == self.factors.len() {
            self.nodes.push(Node::Leaf { rank: self.boxes.len() });
            self.boxes.push(bx);
            return Ok(index);
        }
        let parts = self.factors[level];
        if parts == 1 {
            return self.split(weights, bx, level + 1);
        }
        self.nodes.push(Node::Leaf { rank: usize::MAX });
        let brick = weights.brick;
        let size = bx.size();
        // The longest axis with at least `parts` bricks.
        let faces = |axis: usize| -> Vec<u32> {
            let (lo, hi) = (bx.lo[axis], bx.hi[axis]);
            (lo / brick + 1..hi.div_ceil(brick)).map(|b| b * brick).filter(|&p| p > lo && p < hi).collect()
        };
        let axis = (0..3)
            .filter(|&a| faces(a).len() + 1 >= parts)
            .max_by_key(|&a| (size[a], std::cmp::Reverse(a)))
            .ok_or_else(|| SplitError::TooSmall {
                dims: dims_text(weights.dims),
                brick,
                parts,
                size: dims_text(size),
            })?;
        let candidates = faces(axis);
        let slab = |lo: u32, hi: u32| {
            let mut b = bx;
            b.lo[axis] = lo;
            b.hi[axis] = hi;
            b
        };
        let total_visible = weights.weight_of(&bx);
        let weight = |lo: u32, hi: u32| {
            let b = slab(lo, hi);
            if total_visible > 0 { weights.weight_of(&b) as f64 } else { b.voxels() as f64 }
        };
        let at = if total_visible > 0 && level + 1 == self.factors.len() {
            // The children are processes' boxes, and a process holds the bounding box of its
            // weighted bricks: balance those boxes, not the weights inside them.
            HeldBoxes::along(weights, bx, axis).planes(&candidates, parts)
        } else {
            let total = weight(bx.lo[axis], bx.hi[axis]);
            // Greedy planes: each at the face whose weight below best matches its share, leaving
            // at least one face for every plane still to place.
            let mut at = Vec::with_capacity(parts - 1);
            let mut from = 0usize;
            for i in 1..parts {
                let target = total * i as f64 / parts as f64;
                let last = candidates.len() - (parts - 1 - i) - 1;
                let best = (from..=last)
                    .min_by(|&a, &b| {
                        let da = (weight(bx.lo[axis], candidates[a]) - target).abs();
                        let db = (weight(bx.lo[axis], candidates[b]) - target).abs();
                        da.total_cmp(&db)
                    })
                    .unwrap_or(from);
                at.push(candidates[best]);
                from = best + 1;
            }
            at
        };
        let mut children = Vec::with_capacity(parts);
        let mut lo = bx.lo[axis];
        for i in 0..parts {
            let hi = at.get(i).copied().unwrap_or(bx.hi[axis]);
            children.push(self.split(weights, slab(lo, hi), level + 1)?);
            lo = hi;
        }
        self.nodes[index] = Node::Split { axis, at, children };
        Ok(index)
    }

    /// The ranks front to back for an eye at `eye_voxels` (voxel coordinates of the whole
    /// volume; anywhere, inside included): along every ray from the eye, a box earlier in the
    /// list is met before a later one. At a node, the slab holding the eye comes first, then the
    /// others by their distance from it — a ray from the eye crosses the planes on one side
    /// only, in that order.
    pub fn visibility_order(&self, eye_voxels: DVec3) -> Vec<usize> {
        let mut order = Vec::with_capacity(self.boxes.len());
        if !self.nodes.is_empty() {
            self.visit(0, eye_voxels, &mut order);
        }
        order
    }

    fn visit(&self, node: usize, eye: DVec3, order: &mut Vec<usize>) {
        match &self.nodes[node] {
            Node::Leaf { rank } => order.push(*rank),
            Node::Split { axis, at, children } => {
                for child in slab_order(eye[*axis], at) {
                    self.visit(children[child], eye, order);
                }
            }
        }
    }

    /// The front-to-back order of the children of the node that round `round` of radix-k
    /// composites for `rank` (round 0 combines siblings at the bottom level): child indices,
    /// which are the ranks' digits in that round.
    pub fn children_order(&self, rank: usize, round: usize, eye_voxels: DVec3) -> Vec<usize> {
        let level = self.factors.len() - 1 - round;
        // Walk down from the root along `rank`'s digits to the node at `level`.
        let mut node = 0;
        let mut digits = rank_digits(rank, &self.factors);
        digits.reverse(); // top first
        for (l, &digit) in digits.iter().enumerate().take(level) {
            if self.factors[l] == 1 {
                continue;
            }
            if let Node::Split { children, .. } = &self.nodes[node] {
                node = children[digit];
            }
        }
        match &self.nodes[node] {
            Node::Split { axis, at, .. } => slab_order(eye_voxels[*axis], at),
            Node::Leaf { .. } => vec![0],
        }
    }
}

/// The bounding boxes of the weighted bricks of a box's slabs along one axis: what a process
/// whose box is such a slab holds (`render --distributed` holds only the bricks the view needs,
/// and their bounding box is what it reads). One record per brick layer of the box along the
/// axis, so the box of any slab is a union over its layers.
struct HeldBoxes {
    bx: VoxelBox,
    axis: usize,
    brick: u32,
    dims: UVec3,
    /// Per brick layer along `axis` (from `bx.lo`), the weighted bricks' bounding box in the
    /// layer, in bricks (`None`: no weighted brick).
    layers: Vec<Option<(UVec3, UVec3)>>,
}

impl HeldBoxes {
    fn along(weights: &BrickWeights, bx: VoxelBox, axis: usize) -> Self {
        let brick = weights.brick;
        let n = BrickWeights::bricks(weights.dims, brick);
        let (lo, hi) = (bx.lo / brick, ((bx.hi + UVec3::splat(brick - 1)) / brick).min(n));
        let mut layers = vec![None::<(UVec3, UVec3)>; (hi[axis] - lo[axis]) as usize];
        for z in lo.z..hi.z {
            for y in lo.y..hi.y {
                for x in lo.x..hi.x {
                    if weights.weight[(x + n.x * (y + n.y * z)) as usize] == 0 {
                        continue;
                    }
                    let b = UVec3::new(x, y, z);
                    let layer = &mut layers[(b[axis] - lo[axis]) as usize];
                    *layer = Some(match *layer {
                        Some((l, h)) => (l.min(b), h.max(b + UVec3::ONE)),
                        None => (b, b + UVec3::ONE),
                    });
                }
            }
        }
        Self { bx, axis, brick, dims: weights.dims, layers }
    }

    /// The brick layer holding voxel plane `p` along the axis (a brick face or the box's end).
    fn layer_at(&self, p: u32) -> usize {
        (p.div_ceil(self.brick) - self.bx.lo[self.axis] / self.brick) as usize
    }

    /// The voxels of the bounding box of the weighted bricks between planes `from` and `to`,
    /// within the slab.
    fn held(&self, from: u32, to: u32) -> u64 {
        let (a, b) = (self.layer_at(from).min(self.layers.len()), self.layer_at(to).min(self.layers.len()));
        let bound = self.layers[a..b].iter().flatten().copied().reduce(|(l0, h0), (l1, h1)| (l0.min(l1), h0.max(h1)));
        let Some((l, h)) = bound else { return 0 };
        let mut slab = self.bx;
        slab.lo[self.axis] = from;
        slab.hi[self.axis] = to;
        VoxelBox::new((l * self.brick).max(slab.lo), (h * self.brick).min(self.dims).min(slab.hi)).voxels()
    }

    /// The `parts - 1` planes among `candidates` (increasing) that make the largest slab's held
    /// box smallest (then their sum): exact, by dynamic programming over the planes.
    fn planes(&self, candidates: &[u32], parts: usize) -> Vec<u32> {
        // Plane positions: the box's start, the candidates, its end.
        let mut p = Vec::with_capacity(candidates.len() + 2);
        p.push(self.bx.lo[self.axis]);
        p.extend_from_slice(candidates);
        p.push(self.bx.hi[self.axis]);
        let m = p.len();
        let held: Vec<Vec<u64>> =
            (0..m).map(|i| (0..m).map(|j| if i < j { self.held(p[i], p[j]) } else { 0 }).collect()).collect();
        // cost[k][j]: the best (largest, sum) of k slabs covering p[0]..p[j]; from[k][j] the
        // start of the last of them.
        let mut cost = vec![vec![(u64::MAX, u64::MAX); m]; parts + 1];
        let mut from = vec![vec![0usize; m]; parts + 1];
        cost[0][0] = (0, 0);
        for k in 1..=parts {
            for j in k..m {
                for i in (k - 1)..j {
                    let (largest, sum) = cost[k - 1][i];
                    if largest == u64::MAX {
                        continue;
                    }
                    let h = held[i][j];
                    let c = (largest.max(h), sum + h);
                    if c < cost[k][j] {
                        cost[k][j] = c;
                        from[k][j] = i;
                    }
                }
            }
        }
        let mut at = Vec::with_capacity(parts - 1);
        let mut j = m - 1;
        for k in (2..=parts).rev() {
            j = from[k][j];
            at.push(p[j]);
        }
        at.reverse();
        at
    }
}

/// Slabs separated at planes `at` (increasing) in front-to-back order from coordinate `eye`:
/// the eye's slab, then outwards, nearer first.
fn slab_order(eye: f64, at: &[u32]) -> Vec<usize> {
    let n = at.len() + 1;
    let home = at.iter().take_while(|&&p| eye >= p as f64).count();
    let mut order = Vec::with_capacity(n);
    order.push(home);
    let (mut below, mut above) = (home as isize - 1, home + 1);
    while order.len() < n {
        // Both sides are independent (no ray crosses both); alternate for determinism.
        if above < n {
            order.push(above);
            above += 1;
        }
        if below >= 0 {
            order.push(below as usize);
            below -= 1;
        }
    }
    order
}

/// `rank`'s digit per level, bottom level first: the digit of level `l` (top = 0) is its
/// child index at that node.
pub fn rank_digits(rank: usize, factors: &[usize]) -> Vec<usize> {
    let mut r = rank;
    factors
        .iter()
        .rev()
        .map(|&f| {
            let d = r % f;
            r /= f;
            d
        })
        .collect()
}

/// The prime factors of `n`, largest first (`[1]` for 1).
pub fn prime_factors(n: usize) -> Vec<usize> {
    let mut factors = Vec::new();
    let mut m = n.max(1);
    let mut p = 2;
    while p * p <= m {
        while m.is_multiple_of(p) {
            factors.push(p);
            m /= p;
        }
        p += 1;
    }
    if m > 1 || factors.is_empty() {
        factors.push(m);
    }
    factors.sort_unstable_by(|a, b| b.cmp(a));
    factors
}

/// The factors of `n` for radix-k rounds as IceT picks them: each as close to `target_k` as the
/// factorization allows without passing it (a prime larger than the target is one round).
pub fn radix_factors(n: usize, target_k: usize) -> Vec<usize> {
    let primes = prime_factors(n);
    let mut rounds: Vec<usize> = Vec::new();
    for p in primes {
        match rounds.iter_mut().filter(|r| **r * p <= target_k.max(2)).min() {
            Some(r) => *r *= p,
            None => rounds.push(p),
        }
    }
    rounds.sort_unstable_by(|a, b| b.cmp(a));
    rounds
}

fn dims_text(d: UVec3) -> String {
    format!("{}x{}x{}", d.x, d.y, d.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn uniform(dims: UVec3, brick: u32) -> BrickWeights {
        let mut w = BrickWeights::zeros(dims, brick);
        w.weight.iter_mut().for_each(|v| *v = 1);
        w
    }

    /// The boxes tile the volume: disjoint, and their voxels add up to the whole.
    fn assert_tiles(tree: &KdTree) {
        let total: u64 = tree.boxes.iter().map(VoxelBox::voxels).sum();
        assert_eq!(total, VoxelBox::new(UVec3::ZERO, tree.dims).voxels());
        for (i, a) in tree.boxes.iter().enumerate() {
            for b in &tree.boxes[i + 1..] {
                let overlap = a.lo.max(b.lo).cmplt(a.hi.min(b.hi)).all();
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
    }

    #[test]
    fn equal_weights_split_into_equal_boxes() {
        let tree = KdTree::balanced_into(&uniform(UVec3::new(128, 64, 64), 16), 4).expect("splits");
        assert_tiles(&tree);
        for b in &tree.boxes {
            assert_eq!(b.voxels(), 128 * 64 * 64 / 4, "{b:?}");
        }
    }

    /// Visible voxels only in the low-x half: the split puts the planes there, so each box
    /// holds about the same number of visible bricks.
    #[test]
    fn visible_voxels_balance_the_split() {
        let dims = UVec3::new(128, 32, 32);
        let mut w = BrickWeights::zeros(dims, 16);
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..4 {
                    let i = w.brick_of(UVec3::new(x * 16, y * 16, z * 16));
                    w.weight[i] = 100;
                }
            }
        }
        let tree = KdTree::balanced(&w, &[2]).expect("splits");
        assert_eq!(tree.boxes[0].hi.x, 32, "{:?}", tree.boxes);
    }

    /// A dense cluster at one end and two lone bricks further on: balancing the weights puts
    /// the plane inside the cluster, and the other process's box must then reach from there to
    /// the last lone brick. The processes hold the bounding boxes of their weighted bricks, so
    /// the plane goes where the larger of those is smallest.
    #[test]
    fn the_split_balances_the_boxes_processes_hold() {
        let dims = UVec3::new(256, 32, 32);
        let mut w = BrickWeights::zeros(dims, 16);
        for layer in [0, 1, 2, 3] {
            for (y, z) in [(0, 0), (16, 0), (0, 16), (16, 16)] {
                let i = w.brick_of(UVec3::new(layer * 16, y, z));
                w.weight[i] = 16 * 16 * 16;
            }
        }
        for layer in [8, 15] {
            let i = w.brick_of(UVec3::new(layer * 16, 0, 0));
            w.weight[i] = 16 * 16 * 16;
        }
        let tree = KdTree::balanced(&w, &[2]).expect("splits");
        assert_tiles(&tree);
        let layers = HeldBoxes::along(&w, VoxelBox::new(UVec3::ZERO, dims), 0);
        let held: Vec<u64> = tree.boxes.iter().map(|b| layers.held(b.lo.x, b.hi.x)).collect();
        // The best split: the cluster (64 × 32 × 32) on one side, the lone bricks (from 128 to
        // 256, one brick across) on the other; balancing weights held 224 × 32 × 32.
        assert_eq!(held, vec![64 * 32 * 32, 128 * 16 * 16], "{:?}", tree.boxes);
    }

    #[test]
    fn too_many_parts_is_an_error() {
        let e = KdTree::balanced_into(&uniform(UVec3::splat(16), 16), 2).expect_err("one brick");
        assert!(e.to_string().contains("cannot be split into 2 boxes"), "{e}");
    }

    #[test]
    fn radix_factors_stay_within_the_target() {
        assert_eq!(radix_factors(16, 8), vec![8, 2]);
        assert_eq!(radix_factors(12, 4), vec![4, 3]);
        assert_eq!(radix_factors(7, 4), vec![7]);
        assert_eq!(radix_factors(4, 2), vec![2, 2]);
        assert_eq!(prime_factors(12), vec![3, 2, 2]);
    }

    /// Walk a ray from the eye through the volume and list the boxes it meets: they come in
    /// the visibility order (for eyes outside and inside).
    fn ray_meets_boxes_in_order(tree: &KdTree, eye: DVec3, dir: DVec3) {
        let order = tree.visibility_order(eye);
        let position: Vec<usize> =
            (0..tree.boxes.len()).map(|r| order.iter().position(|&o| o == r).expect("every rank")).collect();
        let mut last = None;
        for i in 0..4000 {
            let p = eye + dir * (i as f64 * 0.1);
            let Some(rank) =
                tree.boxes.iter().position(|b| p.cmpge(b.lo.as_dvec3()).all() && p.cmplt(b.hi.as_dvec3()).all())
            else {
                continue;
            };
            if let Some(prev) = last {
                assert!(
                    position[rank] >= position[prev],
                    "eye {eye} dir {dir}: met {rank} after {prev}, order {order:?}"
                );
            }
            last = Some(rank);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn visibility_order_holds_along_every_ray(
            ranks in 1usize..9,
            eye in prop::array::uniform3(-80.0f64..200.0),
            dir in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let dir = DVec3::from_array(dir);
            prop_assume!(dir.length() > 0.1);
            let tree = KdTree::balanced(&uniform(UVec3::new(128, 96, 64), 8), &radix_factors(ranks, 4)).expect("splits");
            assert_tiles(&tree);
            ray_meets_boxes_in_order(&tree, DVec3::from_array(eye), dir.normalize());
        }
    }

    #[test]
    fn children_order_of_the_top_round_is_the_top_slab_order() {
        let tree = KdTree::balanced(&uniform(UVec3::new(128, 32, 32), 8), &[2, 2]).expect("splits");
        // Eye beyond the high-x end: the high child first at the top.
        let eye = DVec3::new(500.0, 16.0, 16.0);
        assert_eq!(tree.children_order(0, 1, eye), vec![1, 0]);
        assert_eq!(tree.visibility_order(eye), vec![3, 2, 1, 0]);
        assert_eq!(rank_digits(3, &[2, 2]), vec![1, 1]);
    }
}
