// Krüger & Westermann 2003 §2.3 on the GPU: the min/max grid of B³-voxel blocks, conservative
// for trilinear interpolation exactly like `volgraph_accel::minmax::MinMaxGrid`: block b's range
// is the min/max over its own voxels [b·B, min((b+1)·B, n)) plus a one-voxel apron on each side,
// clamped to the volume (the voxels any trilinear sample inside the block's texel footprints can
// read; two voxels with TRICUBIC, the B-spline's footprint). One invocation per block; values are the volume texture's normalized texels, i.e. what
// the raycasters sample.
//
// Entry point: `cs_minmax` → `grid` (Rg32Float 3D: r = min, g = max).

#import "common/volume.wgsl"

// Declared once: `BlockSize` (pass_params!) in crates/passes/src/shared.rs,
// which generates the struct imported here.
#import "params/BlockSize.wgsl"

@group(0) @binding(auto) var grid: texture_storage_3d<rg32float, write>;
@group(0) @binding(auto) var<uniform> minmax: BlockSize;

// Workgroups of 4³ blocks.
@compute @workgroup_size(4, 4, 4)
fn cs_minmax(@builtin(global_invocation_id) id: vec3<u32>) {
    let blocks = textureDimensions(grid);
    if (any(id >= blocks)) {
        return;
    }
    let n = textureDimensions(volume);
    let b = minmax.block_size;
    let start = id * b;
    let end = min((id + vec3<u32>(1u)) * b, n); // exclusive
#if TRICUBIC
    // The tricubic B-spline reads two voxels beyond the trilinear footprint's one.
    let lo = max(start, vec3<u32>(2u)) - vec3<u32>(2u);
    let hi = min(end + vec3<u32>(1u), n - vec3<u32>(1u));
#else
    let lo = max(start, vec3<u32>(1u)) - vec3<u32>(1u);
    let hi = min(end, n - vec3<u32>(1u)); // inclusive: the apron voxel past the block
#endif
    var mn = 3.0e38;
    var mx = -3.0e38;
    for (var z = lo.z; z <= hi.z; z += 1u) {
        for (var y = lo.y; y <= hi.y; y += 1u) {
            for (var x = lo.x; x <= hi.x; x += 1u) {
                let v = textureLoad(volume, vec3<i32>(vec3<u32>(x, y, z)), 0).r;
                mn = min(mn, v);
                mx = max(mx, v);
            }
        }
    }
    textureStore(grid, vec3<i32>(id), vec4<f32>(mn, mx, 0.0, 0.0));
}
