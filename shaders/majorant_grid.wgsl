// Per-block majorants for delta tracking (Novák et al. 2014 §3, "tight majorants are what make
// it fast"): the largest TF opacity any value in each block's [min, max] of the min/max grid can
// interpolate (common/lut_range.wgsl) — a bound on the extinction of every sample the block's
// box can take, the one-voxel apron of the grid included. The path tracer
// (path_trace.wgsl, BLOCK_MAJORANTS) turns it into σ̄ = −ln(1 − α) / L and steps block by block:
// an empty block (α 0) costs one step, a thin one few. A NaN texel counts as opaque. Rerun when
// the grid or the TF changes.
//
// Entry point: `cs_majorants` → `majorants` (R32Float 3D: the largest α).

#import "common/volume.wgsl"
#import "common/lut_range.wgsl"

// The min/max grid of minmax_grid.wgsl (r = min, g = max).
@group(0) @binding(auto) var grid: texture_3d<f32>;
@group(0) @binding(auto) var majorants: texture_storage_3d<r32float, write>;

@compute @workgroup_size(4, 4, 4)
fn cs_majorants(@builtin(global_invocation_id) id: vec3<u32>) {
    let blocks = textureDimensions(majorants);
    if (any(id >= blocks)) {
        return;
    }
    let range = textureLoad(grid, vec3<i32>(id), 0).rg;
    let texels = lut_texels_of(range, false, i32(textureDimensions(tf)));
    var most = 0.0;
    for (var i = texels.x; i <= texels.y; i += 1) {
        let a = textureLoad(tf, i, 0).a;
        most = max(most, select(clamp(a, 0.0, 1.0), 1.0, a != a));
    }
    textureStore(majorants, vec3<i32>(id), vec4<f32>(most, 0.0, 0.0, 0.0));
}
