// Chebyshev distance, in blocks, from every block of the empty-block grid to the nearest block
// that may be visible (0 for such a block): a ray in a block at distance d may leap to where it
// leaves the cube of (2d - 1)³ blocks centred there, all of them empty. The L∞ distance
// transform is separable, one pass per axis over whole lines:
//   pass x: d_x(p)   = min over x' of |x - x'|          where block (x', y, z) is not empty
//   pass y: d_xy(p)  = min over y' of max(|y - y'|, d_x(x, y', z))
//   pass z: d(p)     = min over z' of max(|z - z'|, d_xy(x, y, z'))
// Distances are capped at DISTANCE_CAP (an all-empty grid reads the cap everywhere).
//
// Each line is solved in O(n) (the first version scanned every pair, O(n²), and took ~150 ms
// of a TF edit on a 64³ grid under lavapipe): g(i) = min over j of max(|i - j|, f(j)) is the
// smaller of the same minimum over j ≤ i and over j ≥ i, each one sweep with a queue of the
// candidates that can still win (a sliding-window minimum). Sweeping towards larger i, a
// candidate j is beaten for good by a later j' with f(j') ≤ f(j) (nearer, not larger), so the
// queue holds strictly increasing f from its oldest to its newest entry — at most
// DISTANCE_CAP + 1 entries, as the f are whole numbers up to the cap — and the oldest one is
// the answer once it is dropped whenever the gap to it has reached the next entry's f.

const DISTANCE_CAP: u32 = 255u;
// Longest grid line: the largest 3D texture edge wgpu guarantees (checked by the pass).
const MAX_LINE: u32 = 2048u;

// Declared once in Rust (`DistanceParams` in crates/passes/src/empty_distance.rs).
#import "params/DistanceParams.wgsl"

// 1.0 = empty (empty_space.wgsl).
@group(0) @binding(auto) var empty: texture_3d<f32>;
// The previous axis's distances (passes y and z).
@group(0) @binding(auto) var partial: texture_3d<f32>;
// This axis's distances: the next pass's `partial`, or the map after pass z.
@group(0) @binding(auto) var distance: texture_storage_3d<r32float, write>;
@group(0) @binding(auto) var<uniform> pass_params: DistanceParams;

// Cell `i` along `axis` of the line through `line` (the other two coordinates).
fn cell(line: vec2<u32>, axis: u32, i: u32) -> vec3<i32> {
    switch axis {
        case 0u: { return vec3<i32>(i32(i), i32(line.x), i32(line.y)); }
        case 1u: { return vec3<i32>(i32(line.x), i32(i), i32(line.y)); }
        default: { return vec3<i32>(i32(line.x), i32(line.y), i32(i)); }
    }
}

// f(i) of this pass: 0 or the cap for a block of the flags (x), else the previous axis's result.
fn source(line: vec2<u32>, axis: u32, i: u32) -> u32 {
    if (axis == 0u) {
        return select(0u, DISTANCE_CAP, textureLoad(empty, cell(line, axis, i), 0).r > 0.5);
    }
    return min(u32(textureLoad(partial, cell(line, axis, i), 0).r), DISTANCE_CAP);
}

// Writes this pass's distance `d` for cell `c`.
fn put(c: vec3<i32>, d: u32) {
    textureStore(distance, c, vec4<f32>(f32(d), 0.0, 0.0, 0.0));
}

// Pass x, where f is 0 or the cap: the distance to the nearest visible block of the line, filled
// in between each visible block and the one before it — every cell written once, no queue.
fn nearest_visible_along_x(line: vec2<u32>, n: u32) {
    // One past the previous visible block (0: none yet).
    var after_previous = 0u;
    var seen = false;
    for (var k = 0u; k <= n; k += 1u) {
        let visible = k < n && source(line, 0u, k) == 0u;
        if (!visible && k < n) {
            continue;
        }
        // Cells between the previous visible block and k (or the line's end).
        for (var c = after_previous; c < k; c += 1u) {
            let to_previous = select(DISTANCE_CAP, c - after_previous + 1u, seen);
            let to_next = select(DISTANCE_CAP, k - c, k < n);
            put(cell(line, 0u, c), min(min(to_previous, to_next), DISTANCE_CAP));
        }
        if (k < n) {
            put(cell(line, 0u, k), 0u);
        }
        after_previous = k + 1u;
        seen = true;
    }
}

// One line per invocation: x runs over (y, z), y over (x, z), z over (x, y).
@compute @workgroup_size(8, 8)
fn cs_line(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(distance);
    let axis = pass_params.axis;
    let across = select(select(vec2<u32>(dims.x, dims.y), vec2<u32>(dims.x, dims.z), axis == 1u), vec2<u32>(dims.y, dims.z), axis == 0u);
    if (id.x >= across.x || id.y >= across.y) {
        return;
    }
    let n = min(dims[axis], MAX_LINE);
    if (axis == 0u) {
        nearest_visible_along_x(id.xy, n);
        return;
    }
    // The backward sweep's answers, four 8-bit distances to a word.
    var from_above: array<u32, MAX_LINE / 4u>;
    // The candidates, (position in sweep order << 8) | f, a ring of DISTANCE_CAP + 1 entries
    // between `oldest` and `next` (both counting up); `& DISTANCE_CAP` is the ring's modulo, as
    // the cap is 2⁸ − 1 (f also fits the 8 bits under the position).
    var queue: array<u32, DISTANCE_CAP + 1u>;
    for (var sweep = 0u; sweep < 2u; sweep += 1u) {
        let backward = sweep == 0u;
        var oldest = 0u;
        var next = 0u;
        for (var k = 0u; k < n; k += 1u) {
            let i = select(k, n - 1u - k, backward);
            let f = source(id.xy, axis, i);
            // Older candidates with f no smaller are beaten by this one from here on.
            while (next > oldest && (queue[(next - 1u) & DISTANCE_CAP] & 255u) >= f) {
                next -= 1u;
            }
            queue[next & DISTANCE_CAP] = (k << 8u) | f;
            next += 1u;
            // The oldest is beaten for good once the gap to it reaches the next one's f.
            while (next - oldest >= 2u
                && k - (queue[oldest & DISTANCE_CAP] >> 8u) >= (queue[(oldest + 1u) & DISTANCE_CAP] & 255u)) {
                oldest += 1u;
            }
            let best = queue[oldest & DISTANCE_CAP];
            let d = min(max(k - (best >> 8u), best & 255u), DISTANCE_CAP);
            let shift = (i & 3u) * 8u;
            if (backward) {
                from_above[i >> 2u] |= d << shift;
            } else {
                let both = min(d, (from_above[i >> 2u] >> shift) & 255u);
                put(cell(id.xy, axis, i), both);
            }
        }
    }
}
