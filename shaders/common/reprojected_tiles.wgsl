// The layout of `reprojection_tiles`' per-tile depth bounds (Klein et al. 2005 §4.3–4.4 per
// tile), shared by the pass that writes them (reprojection_tiles.wgsl) and the raycasters that
// start their rays from them (common/pixel_march.wgsl, START_TILES): TILES_HEADER words — the
// tile edge in pixels (0: no bounds, every ray from the box), tiles per image row — then one
// key per tile, row by row. A key orders depths so that the nearest is the largest (atomicMax
// keeps it): `depth_key(z)` for a view depth z ≥ 0, NO_BOUND_YET (0) where no hit landed and
// FROM_THE_BOX (all ones, nearer than any depth) where rays must start at the box.

#import "common/frame.wgsl"

const TILES_HEADER: u32 = 2u;
const NO_BOUND_YET: u32 = 0u;
const FROM_THE_BOX: u32 = 0xffffffffu;

// The view depth of world point `p` this frame: its distance from the eye along the camera's
// forward axis (any camera: the plane of equal depth is the image plane's).
fn view_depth(p: vec3<f32>) -> f32 {
    return dot(p - frame.eye_world.xyz, frame.camera_forward.xyz);
}

// The key of view depth `z`: the bits of a non-negative f32 grow with its value, so their
// complement shrinks; never 0 (NO_BOUND_YET) for a finite depth. Depths at or behind the eye's
// plane become 0 — the key of "from the box".
fn depth_key(z: f32) -> u32 {
    return ~bitcast<u32>(max(z, 0.0));
}

// Where along the texture-space ray u0 + t·d (t in the units of `d`, a unit vector) the view
// depth of a tile `key` lies; 0 (the ray's entry) for no bound.
fn tile_bound_t(key: u32, u0: vec3<f32>, d: vec3<f32>) -> f32 {
    if (key == NO_BOUND_YET) {
        return 0.0;
    }
    let z = bitcast<f32>(~key);
    // The view depth along the ray is affine in t: z(t) = z(u0) + t · along.
    let along = dot(d * (2.0 * frame.half_extent.xyz), frame.camera_forward.xyz);
    if (!(along > 0.0)) {
        return 0.0;
    }
    return max((z - view_depth(world_from_texture(u0))) / along, 0.0);
}
