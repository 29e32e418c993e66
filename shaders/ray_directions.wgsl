// Krüger & Westermann 2003 §2.1, pass 2 (ray direction determination): the box's back faces
// (`front_face: Ccw, cull_mode: Front`) give each ray's exit point u1; with the entry u0 read
// from `entry`, the `dir` target gets (normalize(u1 - u0), |u1 - u0|) in texture space
// (docs/rendering_model.md "Ray segment inside the box"). Pixels without an entry, or whose
// segment is shorter than MIN_RAY_LENGTH_TEX, get (0,0,0,0): no ray.

#import "common/frame.wgsl"
#import "common/box_vertex.wgsl"

// Pass 1's output: (u0, 1) where the ray enters the box, (0,0,0,0) where it misses.
@group(0) @binding(auto) var entry: texture_2d<f32>;

// Shorter segments count as "no ray" (t_out <= t0 in the model). 1e-6 texture units is far
// below any sample spacing in use (0.01 voxel of a 4096³ volume is 2.4e-6), yet well above the
// f32 rounding of u near 1 (6e-8), so it only removes the degenerate rays of grazing pixels.
const MIN_RAY_LENGTH_TEX: f32 = 1e-6;

struct DirOut {
    @location(0) dir: vec4<f32>,
}

// Back faces: (normalize(exit - entry), length) or zero.
@fragment
fn fs_dir(in: BoxVertex) -> DirOut {
    let e = textureLoad(entry, vec2<i32>(in.clip.xy), 0);
    let exit = clamp(in.u, grid_box_lo(), grid_box_hi());
    let delta = exit - e.xyz;
    let len = length(delta);
    if (e.w == 0.0 || !(len >= MIN_RAY_LENGTH_TEX)) {
        return DirOut(vec4<f32>(0.0));
    }
    return DirOut(vec4<f32>(delta / len, len));
}
