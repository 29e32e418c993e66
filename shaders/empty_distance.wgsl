// Chebyshev distance, in blocks, from every block of the empty-block grid to the nearest block
// that may be visible (0 for such a block): a ray in a block at distance d may leap to where it
// leaves the cube of (2d - 1)³ blocks centred there, all of them empty. The L∞ distance
// transform is separable, one pass per axis over whole lines:
//   pass x: d_x(p)   = min over x' of |x - x'|          where block (x', y, z) is not empty
//   pass y: d_xy(p)  = min over y' of max(|y - y'|, d_x(x, y', z))
//   pass z: d(p)     = min over z' of max(|z - z'|, d_xy(x, y, z'))
// Distances are capped at DISTANCE_CAP (an all-empty grid reads the cap everywhere).

const DISTANCE_CAP: f32 = 255.0;

struct DistanceParams {
    // 0, 1, 2: the axis this dispatch runs along.
    axis: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// 1.0 = empty (empty_space.wgsl).
@group(0) @binding(auto) var empty: texture_3d<f32>;
// The previous axis's distances (passes y and z).
@group(0) @binding(auto) var partial: texture_3d<f32>;
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

// One line per invocation: x runs over (y, z), y over (x, z), z over (x, y).
@compute @workgroup_size(8, 8)
fn cs_line(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = textureDimensions(distance);
    let axis = pass_params.axis;
    let across = select(select(vec2<u32>(dims.x, dims.y), vec2<u32>(dims.x, dims.z), axis == 1u), vec2<u32>(dims.y, dims.z), axis == 0u);
    if (id.x >= across.x || id.y >= across.y) {
        return;
    }
    let n = dims[axis];
    for (var i = 0u; i < n; i += 1u) {
        var best = DISTANCE_CAP;
        for (var j = 0u; j < n; j += 1u) {
            let gap = abs(f32(i) - f32(j));
            if (gap >= best) {
                continue;
            }
            var d = 0.0;
            if (axis == 0u) {
                d = select(0.0, DISTANCE_CAP, textureLoad(empty, cell(id.xy, axis, j), 0).r > 0.5);
            } else {
                d = textureLoad(partial, cell(id.xy, axis, j), 0).r;
            }
            best = min(best, max(gap, d));
        }
        textureStore(distance, cell(id.xy, axis, i), vec4<f32>(best, 0.0, 0.0, 0.0));
    }
}
