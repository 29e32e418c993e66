// The bricked raycaster of Ruijters & Vilanova 2006 (crates/passes/src/raycast_bricks.rs): one
// invocation per pixel marches the samples of the single-texture raycasters (common/ray_box.wgsl:
// k + 0.5 steps from the box entry; common/raymarch.wgsl's loop and compositing), but reads the
// volume from a pool of bricks — an atlas of `brick_cells + 3` voxels per side per slot: the
// brick's corner voxels (the overlap of §5) and one more on each side, so a filter tap at a
// brick face blends what it would in the whole volume — and
// skips what the transfer function leaves empty:
// - in a leaf of the octrees (`leaf_cells`³ cells, the node limit of §7) that no box chosen by
//   the ratio rule covers, the ray leaps out of the largest cube of such leaves around it
//   (`leaf_words`: Chebyshev distances, empty nodes and empty bricks alike);
// - a brick not in this dispatch's batch is left in one step (§5, §7: bricks drawn front to
//   back, one batch of resident bricks after another when the pool is smaller than the
//   visible bricks);
// - the samples of a cube of leaves worth drawing (within one brick) are a run with nothing but
//   sampling in the loop.
// The ray's colour survives between batches in `acc` (per pixel), so a frame drawn in several
// batches composites exactly like one drawn in a single pass; a ray stops at `threshold` (early
// ray termination: its remaining bricks cost nothing).

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/leap_empty.wgsl"
#import "common/workgroup_pixel.wgsl"

// Declared once in Rust (`BrickParams` in crates/passes/src/raycast_bricks.rs).
#import "params/BrickParams.wgsl"

@group(0) @binding(auto) var<uniform> bricks: BrickParams;
// This batch: word 0 = 1 for the first batch of the frame (start from a clear ray); word 1 + b
// = 0 when brick b is not drawn in this batch, else bit 31 and its slot's coordinates in the
// atlas, 10 bits per axis, x lowest (`slot_word` in crates/accel/src/brick_leaves.rs).
@group(0) @binding(auto) var<storage, read> table: array<u32>;
// Per leaf of the volume (x fastest; `leaf_word` in crates/accel/src/brick_leaves.rs): where no box to draw
// covers it, the Chebyshev distance d (1..=255) in leaves to the nearest such leaf (every leaf
// closer is empty too); where one does, `reach << 8`: the cube of leaves reach - 1 around it is
// drawn too, inside its brick.
@group(0) @binding(auto) var<storage, read> leaf_words: array<u32>;
// Per pixel: the premultiplied colour composited so far this frame.
@group(0) @binding(auto) var<storage, read_write> acc: array<vec4<f32>>;
#import "common/color_target.wgsl"

// Voxel coordinates (voxel centres at integers) of texture-space `p`, clamped to the voxels.
fn voxel_of(p: vec3<f32>) -> vec3<f32> {
    let n = frame.volume_dims.xyz;
    return clamp(p * n - vec3<f32>(0.5), vec3<f32>(0.0), max(n - vec3<f32>(1.0), vec3<f32>(0.0)));
}

// The texture-space box of voxel box [lo, hi]; a box at a face of the volume extends to the
// face, half a voxel beyond the last centre (like common/box.wgsl's cells).
fn voxel_box_lo(lo: vec3<f32>) -> vec3<f32> {
    return select((lo + vec3<f32>(0.5)) / frame.volume_dims.xyz, vec3<f32>(0.0), lo <= vec3<f32>(0.0));
}

fn voxel_box_hi(hi: vec3<f32>) -> vec3<f32> {
    let last = max(frame.volume_dims.xyz - vec3<f32>(1.0), vec3<f32>(0.0));
    return select((hi + vec3<f32>(0.5)) / frame.volume_dims.xyz, vec3<f32>(1.0), hi >= last);
}

fn brick_index(b: vec3<u32>) -> u32 {
    let grid = bricks.grid.xyz;
    return b.x + grid.x * (b.y + grid.y * b.z);
}

// The brick holding voxel position `c`, and the leaf.
fn brick_of(c: vec3<f32>) -> vec3<u32> {
    return min(vec3<u32>(c / f32(bricks.grid.w)), bricks.grid.xyz - vec3<u32>(1u));
}

fn leaf_of(c: vec3<f32>) -> vec3<u32> {
    return min(vec3<u32>(c / f32(bricks.leaves.x)), bricks.leaf_grid.xyz - vec3<u32>(1u));
}

// The constants of the leaps' look-ups, read once per ray (common/leap_empty.wgsl's `Leaping`).
struct LeapGrid {
    // The last voxel's index per axis.
    last: vec3<f32>,
    leaf_cells: f32,
    leaf_grid: vec3<u32>,
}

fn leap_grid() -> LeapGrid {
    return LeapGrid(max(frame.volume_dims.xyz - vec3<f32>(1.0), vec3<f32>(0.0)), f32(bricks.leaves.x), bricks.leaf_grid.xyz);
}

// What this dispatch leaps over (common/leap_empty.wgsl): the largest cube of leaves no box to
// draw covers, and a brick drawn in another batch; a leaf to draw reports the largest cube of
// leaves to draw around it within its brick, which the march runs to.
fn empty_region_at(p: vec3<f32>, grid: LeapGrid) -> EmptyRegion {
    let c = voxel_of(p);
    let last = grid.last;
    let leaf_cells = grid.leaf_cells;
    let leaf_grid = grid.leaf_grid;
    let l = leaf_of(c);
    let word = leaf_words[l.x + leaf_grid.x * (l.y + leaf_grid.y * l.z)];
    let d = word & 0xffu;
    // The cube of leaves within reach - 1 of l: empty (a leap) or drawn (a run of samples).
    let reach = vec3<u32>(select(word >> 8u, d, d > 0u) - 1u);
    let lo_leaf = l - min(l, reach);
    let hi_leaf = min(l + reach, leaf_grid - vec3<u32>(1u));
    let cube_lo = voxel_box_lo(vec3<f32>(lo_leaf) * leaf_cells);
    let cube_hi = voxel_box_hi(min(vec3<f32>(hi_leaf + vec3<u32>(1u)) * leaf_cells, last));
    if (d > 0u) {
        return EmptyRegion(true, cube_lo, cube_hi);
    }
    let b = brick_of(c);
    if (table[1u + brick_index(b)] == 0u) {
        let lo = vec3<f32>(b) * f32(bricks.grid.w);
        let hi = min(lo + vec3<f32>(f32(bricks.grid.w)), last);
        return EmptyRegion(true, voxel_box_lo(lo), voxel_box_hi(hi));
    }
    return EmptyRegion(false, cube_lo, cube_hi);
}

// The samples of `ray` from colour `start` on, through this batch's bricks: in rounds, like
// every leaping march (common/raymarch.wgsl): every lane leaps until it stands in a leaf to
// draw, then marches the samples of the drawn cube around it — the same samples, read from the
// brick's slot.
fn march_bricks(s: Samples, start: vec4<f32>) -> vec4<f32> {
    var out = start;
    begin_ray(s, 0u);
    let n = frame.volume_dims.xyz;
    let brick_cells = f32(bricks.grid.w);
    let inv_atlas = vec3<f32>(1.0) / bricks.atlas.xyz;
    let delta_atlas = s.delta * n * inv_atlas;
    // Read once per ray, not per leaf (common/raymarch.wgsl's `march_dvr` says why).
    let threshold = params.threshold;
    let slot_side = bricks.slot_side.xyz;
    let apron = f32(bricks.slot_side.w);
    let leaping = leaping_for(s);
    var k = 0u;
    loop {
        let stop = leap_stop(k, s, s.count, leaping);
        k = stop.k;
        if (k >= s.count || out.a >= threshold) {
            break;
        }
        // A cube of leaves to draw, up to where the ray leaves it — and on through its brick,
        // up to CHECK_EVERY samples in all, like every leaping run (common/raymarch.wgsl): the
        // whole brick is in its slot, and a sample in an empty leaf adds nothing, so a run that
        // does not stop at every thin cluster of leaves (a vessel) saves a round of leaps.
        let p = sample_at(s, k);
        let b = brick_of(voxel_of(p));
        let lo = vec3<f32>(b) * brick_cells;
        let hi = min(lo + vec3<f32>(brick_cells), leaping.grid.last);
        let cube_exit = past_box_by(k, p, leaping.step, stop.region.lo, stop.region.hi);
        let brick_exit = past_box_by(k, p, leaping.step, voxel_box_lo(lo), voxel_box_hi(hi));
        // Never one sample short of the brick's exit: that sample may lie on the brick's face,
        // where `brick_of` gives it to the next brick, and a batch (or sort-last rank) without
        // that brick leaps over its closed box, as the next brick's batch leaps over this one's.
        let run_end = k + CHECK_EVERY;
        let exit = min(max(cube_exit, select(run_end, brick_exit, run_end + 1u >= brick_exit)), s.count);
        // Its samples in the atlas: voxel v of the brick lies at texel origin + apron + 0.5 +
        // (v - lo).
        let word = table[1u + brick_index(b)];
        let slot = vec3<u32>(word, word >> 10u, word >> 20u) & vec3<u32>(0x3ffu);
        let origin = vec3<f32>(slot * slot_side);
        let shift = origin + vec3<f32>(apron + 0.5) - lo - vec3<f32>(0.5);
        let atlas = Samples((s.first * n + shift) * inv_atlas, delta_atlas, s.count, s.step, s.offset, s.cut);
        // The way back to the volume's texture space, for what is defined there (cut faces).
        sampled_scale = bricks.atlas.xyz / n;
        sampled_offset = -shift / n;
        resume_ray(sample_at(atlas, k) - atlas.delta);
        let m = march_dvr(atlas, k, exit, out);
        out = m.color;
        k = m.end;
    }
    return out;
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_main(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let p = begin_invocation(group, local);
    if (!in_viewport(p)) {
        return;
    }
    let i = p.y * u32(frame.viewport.x) + p.x;
    var c = vec4<f32>(0.0);
    if (table[0] == 0u) {
        c = acc[i];
    }
    let s = pixel_samples(analytic_ray(p), p);
    if (s.count > 0u && c.a < params.threshold) {
        c = march_bricks(s, c);
    }
    acc[i] = c;
    textureStore(color, vec2<i32>(p), c);
}
