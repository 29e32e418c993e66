// The single-pass fragment raycaster with empty-space leaping: the modern alternative to
// Krüger & Westermann 2003 §2.3's termination-pass skipping. The same sample sequence and
// compositing as raycast.wgsl (docs/rendering_model.md), but when sample k falls into a block
// that `empty_space` flagged empty, the ray jumps to its first sample past that block's box
// (slab exit), block by block along the ray (a DDA over the block grid that only stops at
// non-empty blocks). Lossless: every skipped sample lies in the closed box of an empty block,
// whose conservative range says it is fully transparent; the box exit's f32 rounding is far
// inside the half-voxel margin the block's apron adds.
//
// Pipeline: `vs_fullscreen` + `fs_dvr` → `color`.

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"
#import "common/raymarch.wgsl"
#import "common/empty_blocks.wgsl"

@group(0) @binding(auto) var entry: texture_2d<f32>;
@group(0) @binding(auto) var dir: texture_2d<f32>;

// Declared once: `BlockSize` (pass_params!) in crates/passes/src/shared.rs.
struct EssParams {
    block_size: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(auto) var<uniform> ess: EssParams;

struct RaycastOut {
    @location(0) color: vec4<f32>,
}

// march_dvr with empty-block leaping.
fn march_dvr_leaping(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, pixel: vec2<u32>) -> vec4<f32> {
    var acc = vec4<f32>(0.0);
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return acc;
    }
    let step_tex = ray_step_tex(d_tex);
    let jitter = ray_jitter(pixel);
    begin_ray(u0 + (0.5 + jitter) * step_tex * d_tex, step_tex * d_tex);
    var k = 0u;
    var known_block = vec3<u32>(0xffffffffu);
    var known_empty = false;
    var leaped = false;
    loop {
        if (k >= params.max_steps) {
            break;
        }
        let t = (f32(k) + 0.5 + jitter) * step_tex;
        if (!(t < len_tex)) {
            break;
        }
        let u = u0 + t * d_tex;
        let b = block_of(u, ess.block_size);
        // One flag look-up per block entered, not per sample.
        if (any(b != known_block)) {
            known_block = b;
            known_empty = block_is_empty(b);
        }
        if (known_empty) {
            let next = first_sample_past_block(b, ess.block_size, u0, d_tex, step_tex, jitter);
            k = max(k + 1u, u32(clamp(next, 0.0, f32(params.max_steps))));
            leaped = true;
            continue;
        }
        if (leaped) {
            // The segment in front of this sample starts at the skipped sample k - 1.
            resume_ray(u0 + (f32(k) - 0.5 + jitter) * step_tex * d_tex);
            leaped = false;
        }
        acc = composite_sample(acc, u);
        if (acc.a >= params.threshold) {
            break;
        }
        k += 1u;
    }
    return acc;
}

@fragment
fn fs_dvr(in: FullscreenVertex) -> RaycastOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var color = vec4<f32>(0.0);
    if (e.w != 0.0) {
        color = march_dvr_leaping(e.xyz, d.xyz, d.w, pixel);
    }
    return RaycastOut(color);
}
