// Last frame's leap hit at a pixel seen with this frame's camera (Klein et al. 2005 §4.3): the
// one projection both reprojections make — the per-pixel splats (reprojection_splat.wgsl) and
// the per-tile depth bounds (reprojection_tiles.wgsl). The importing shader binds `hits`: xyz
// texture space, w = 1 (surface) or 0.5 (exit point), w = 0 where there was no ray.

#import "common/frame.wgsl"

struct ReprojectedHit {
    // The hit in texture space.
    texture: vec3<f32>,
    // In world space.
    world: vec3<f32>,
    // In this frame's normalized device coordinates (y up, z in [0, 1]).
    ndc: vec3<f32>,
    // False where the pixel had no hit, or the hit is at or behind this frame's eye plane.
    valid: bool,
}

fn reprojected_hit(pixel: vec2<u32>) -> ReprojectedHit {
    var out = ReprojectedHit(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), false);
    let hit = textureLoad(hits, vec2<i32>(pixel), 0);
    if (hit.w == 0.0) {
        return out;
    }
    out.texture = hit.xyz;
    out.world = world_from_texture(hit.xyz);
    let clip = frame.clip_from_world * vec4<f32>(out.world, 1.0);
    if (!(clip.w > 0.0)) {
        return out;
    }
    out.ndc = clip.xyz / clip.w;
    out.valid = true;
    return out;
}

// The pixel position (y down, pixel units) of a point at `ndc`.
fn pixel_from_ndc(ndc: vec2<f32>) -> vec2<f32> {
    return vec2<f32>((ndc.x + 1.0) * 0.5 * frame.viewport.x, (1.0 - ndc.y) * 0.5 * frame.viewport.y);
}
