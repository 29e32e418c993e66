// The bricked raycaster of Ruijters & Vilanova 2006 (crates/passes/src/raycast_bricks.rs): one
// invocation per pixel marches the samples of the single-texture raycasters (common/
// analytic_ray.wgsl: k + 0.5 steps from the box entry, the same compositing), but reads the
// volume from a pool of bricks — an atlas of `brick_cells + 3` voxels per side per slot: the
// brick's corner voxels (the overlap of §5) and one more on each side, so a filter tap at a
// brick face blends what it would in the whole volume — and
// skips what the transfer function leaves empty:
// - in a leaf of the octrees (`leaf_cells`³ cells, the node limit of §7) that no box chosen by
//   the ratio rule covers, the ray leaps out of the largest cube of such leaves around it
//   (`leaf_distance`, Chebyshev distances: empty nodes and empty bricks alike);
// - a brick not in this dispatch's batch is left in one step (§5, §7: bricks drawn front to
//   back, one batch of resident bricks after another when the pool is smaller than the
//   visible bricks);
// - the samples of a leaf worth drawing are a run with nothing but sampling in the loop.
// The ray's colour survives between batches in `acc` (per pixel), so a frame drawn in several
// batches composites exactly like one drawn in a single pass; a ray stops at `threshold` (early
// ray termination: its remaining bricks cost nothing).

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/analytic_ray.wgsl"

override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;

struct BrickParams {
    // Bricks per axis (xyz); w = cells per brick side.
    grid: vec4<u32>,
    // Slots per atlas axis (xyz).
    slots: vec4<u32>,
    // Voxels per slot and axis (xyz): brick_cells + 3 (voxel lo - 1 first), fewer on an axis
    // thinner than a brick.
    slot_side: vec4<u32>,
    // x = cells per leaf side, y = leaves per brick side.
    leaves: vec4<u32>,
    // Leaves per axis over the whole volume (xyz).
    leaf_grid: vec4<u32>,
    // Atlas size in texels (xyz).
    atlas: vec4<f32>,
}

@group(0) @binding(auto) var<uniform> bricks: BrickParams;
// This batch: word 0 = 1 for the first batch of the frame (start from a clear ray); word 1 + b
// = slot + 1 of brick b when it is drawn in this batch, 0 when it is not.
@group(0) @binding(auto) var<storage, read> table: array<u32>;
// Per leaf of the volume (x fastest): 0 where a box to draw covers it, else the Chebyshev
// distance in leaves to the nearest such leaf (every leaf closer is empty too).
@group(0) @binding(auto) var<storage, read> leaf_distance: array<u32>;
// Per pixel: the premultiplied colour composited so far this frame.
@group(0) @binding(auto) var<storage, read_write> acc: array<vec4<f32>>;
#if COLOR_F32
@group(0) @binding(auto) var color: texture_storage_2d<rgba32float, write>;
#else
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;
#endif

// A ray's samples in voxel coordinates (voxel centres at integers): sample k at
// `first + k·delta`; `inv` = 1/delta per axis (0 where the ray runs parallel to an axis), so a
// leap costs multiplications only.
struct VoxelRay {
    first: vec3<f32>,
    delta: vec3<f32>,
    inv: vec3<f32>,
}

// The first sample index after the box [lo, hi] (voxel coordinates; a box at a face of the
// volume extends to the face, half a voxel beyond the last centre, like common/box.wgsl's
// cells) that sample k at `v` lies in.
fn past_box(k: u32, v: vec3<f32>, r: VoxelRay, lo: vec3<f32>, hi: vec3<f32>, last: vec3<f32>) -> u32 {
    let lo_v = select(lo, vec3<f32>(-0.5), lo <= vec3<f32>(0.0));
    let hi_v = select(hi, last + vec3<f32>(0.5), hi >= last);
    let bound = select(lo_v, hi_v, r.delta > vec3<f32>(0.0));
    let t_axis = select((bound - v) * r.inv, vec3<f32>(3.0e38), r.delta == vec3<f32>(0.0));
    let steps = min(t_axis.x, min(t_axis.y, t_axis.z));
    return k + max(1u, u32(clamp(floor(steps) + 1.0, 0.0, f32(params.max_steps))));
}

// The samples of `ray` from colour `start` on, through this batch's bricks.
fn march_bricks(ray: Ray, pixel: vec2<u32>, start: vec4<f32>) -> vec4<f32> {
    var out = start;
    let s = ray_samples(ray, pixel);
    begin_ray(s.first, s.delta);
    let n = frame.volume_dims.xyz;
    let last_voxel = max(n - vec3<f32>(1.0), vec3<f32>(0.0));
    let dv = s.delta * n;
    let r = VoxelRay(s.first * n - vec3<f32>(0.5), dv, select(vec3<f32>(1.0) / dv, vec3<f32>(0.0), dv == vec3<f32>(0.0)));
    let brick_cells = f32(bricks.grid.w);
    let leaf_cells = f32(bricks.leaves.x);
    let grid = bricks.grid.xyz;
    let leaf_grid = bricks.leaf_grid.xyz;
    var k = 0u;
    // In rounds, like raycast_fast: first every lane leaps until it stands in a leaf to draw
    // (cheap iterations that all lanes take together), then every lane marches its leaf. A lane
    // that leaps never waits for another's run of samples inside the same iteration.
    loop {
        if (k >= s.count || out.a >= params.threshold) {
            break;
        }
        var lo = vec3<f32>(0.0);
        var hi = vec3<f32>(0.0);
        var exit = k;
        var entry = 0u;
        loop {
            if (k >= s.count) {
                break;
            }
            let v = r.first + f32(k) * r.delta;
            let c = clamp(v, vec3<f32>(0.0), last_voxel);
            let l = min(vec3<u32>(c / leaf_cells), leaf_grid - vec3<u32>(1u));
            let d = leaf_distance[l.x + leaf_grid.x * (l.y + leaf_grid.y * l.z)];
            if (d > 0u) {
                // Out of the cube of empty leaves around this one.
                let reach = vec3<u32>(d - 1u);
                let lo_leaf = l - min(l, reach);
                let hi_leaf = min(l + reach, leaf_grid - vec3<u32>(1u));
                let cube_hi = min(vec3<f32>(hi_leaf + vec3<u32>(1u)) * leaf_cells, last_voxel);
                k = past_box(k, v, r, vec3<f32>(lo_leaf) * leaf_cells, cube_hi, last_voxel);
                continue;
            }
            let b = min(vec3<u32>(c / brick_cells), grid - vec3<u32>(1u));
            lo = vec3<f32>(b) * brick_cells;
            hi = min(lo + vec3<f32>(brick_cells), last_voxel);
            entry = table[1u + b.x + grid.x * (b.y + grid.y * b.z)];
            if (entry == 0u) {
                // Drawn in another batch.
                k = past_box(k, v, r, lo, hi, last_voxel);
                continue;
            }
            let leaf_lo = vec3<f32>(l) * leaf_cells;
            exit = past_box(k, v, r, leaf_lo, min(leaf_lo + vec3<f32>(leaf_cells), hi), last_voxel);
            break;
        }
        if (k >= s.count) {
            break;
        }
#if PREINTEGRATION
        resume_ray(s.first + (f32(k) - 1.0) * s.delta);
#endif
        // A leaf to draw: its samples read the brick's slot, clamped to the brick's voxels
        // (the volume's clamp-to-edge at its faces; rounding at the brick's own faces).
        let slot = entry - 1u;
        let slots = bricks.slots;
        let origin = vec3<f32>(vec3<u32>(slot % slots.x, (slot / slots.x) % slots.y, slot / (slots.x * slots.y)) * bricks.slot_side.xyz);
        let offset = origin + vec3<f32>(1.5) - lo;
        let end = min(exit, s.count);
        loop {
            if (k >= end) {
                break;
            }
            let ck = clamp(r.first + f32(k) * r.delta, lo, hi);
            out = composite_sample(out, (ck + offset) / bricks.atlas.xyz);
            k += 1u;
            if (out.a >= params.threshold) {
                break;
            }
        }
    }
    return out;
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if (f32(p.x) >= frame.viewport.x || f32(p.y) >= frame.viewport.y) {
        return;
    }
    let i = p.y * u32(frame.viewport.x) + p.x;
    var c = vec4<f32>(0.0);
    if (table[0] == 0u) {
        c = acc[i];
    }
    let ray = analytic_ray(p);
    if (ray.len > 0.0 && c.a < params.threshold && ray_is_valid(ray.u0, ray.d, ray.len)) {
        c = march_bricks(ray, p, c);
    }
    acc[i] = c;
    textureStore(color, vec2<i32>(p), c);
}
