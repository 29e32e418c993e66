// Ray-guided multiresolution raycasting of a volume streamed brick by brick
// (crates/passes/src/raycast_stream.rs; Hadwiger et al. 2012 §4–5, Crassin et al. 2009 §5):
// one invocation per pixel marches the samples every raycaster takes (common/ray_box.wgsl) and
// reads each from a brick of the level its projected size asks for:
// - the level: a voxel of level l is 2^l voxels of level 0 wide; a sample wants the coarsest
//   level whose voxel is not wider than a pixel there (`lod` scales that: 2 while the camera
//   moves);
// - the page table says, per brick of every level, where its slot is (bit 31 and the slot's
//   coordinates), that it is empty under the transfer function (EMPTY_BRICK: leapt over), or
//   nothing yet (0): then the brick is requested in `feedback` and the march draws the finest
//   coarser level that is resident — the coarsest level always is, so a frame never waits;
// - a run of samples inside one brick takes one sample for every 2^l of the ray's grid (the
//   step of that level), at their centre, its opacity corrected for that step, through the shared DVR loop
//   (common/raymarch.wgsl's `march_dvr`) with the brick's slot as the texture;
// - inside a brick, the shared march leaps over its empty sub-blocks (8×8×8 per brick,
//   common/leap_empty.wgsl), so a brick a thin vessel crosses costs the vessel's samples;
// - bricks keep `apron` more voxels on every side (clamped at the volume's faces), so a
//   filter tap near a face blends what the level holds there and levels meet without seams.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/leap_empty.wgsl"
#import "common/workgroup_pixel.wgsl"

// Declared once in Rust (`StreamParams` in crates/passes/src/raycast_stream.rs).
#import "params/StreamParams.wgsl"

@group(0) @binding(auto) var<uniform> stream: StreamParams;

// Per level l: xyz = bricks per axis, w = the page-table index of its brick (0, 0, 0).
@group(0) @binding(auto) var<storage, read> level_grid: array<vec4<u32>>;
// Per level l: xyz = its voxels per texture unit (level-0 voxels / 2^l, per axis), w = 2^l.
@group(0) @binding(auto) var<storage, read> level_scale: array<vec4<f32>>;
// Per brick of every level (crates/passes/src/stream_cache.rs): 0 = not resident, EMPTY_BRICK,
// or bit 31 and the slot's coordinates, 10 bits per axis, x lowest.
@group(0) @binding(auto) var<storage, read> page_table: array<u32>;
// Per brick of every level: bit 0 = a ray wanted it and it was not resident, bit 1 = a ray drew
// from it (what the cache keeps); read back after the frame.
@group(0) @binding(auto) var<storage, read_write> feedback: array<atomic<u32>>;
// Per slot, SUB_WORDS words: bit i set when sub-block i (SUB_BLOCKS³ per brick, x fastest) holds
// a voxel the transfer function shows, its apron included (crates/passes/src/stream_cache.rs).
@group(0) @binding(auto) var<storage, read> occupancy: array<u32>;
#import "common/color_target.wgsl"

const EMPTY_BRICK: u32 = 0x40000000u;
// Sub-blocks per brick axis, and occupancy words per slot (`SUB_BLOCKS` in stream_cache.rs).
const SUB_BLOCKS: u32 = 8u;
const SUB_WORDS: u32 = 16u;
const WANTED: u32 = 1u;
const DRAWN: u32 = 2u;

// Brick of level `l` holding texture-space `p`, and its page-table index.
fn brick_at(l: u32, p: vec3<f32>, brick_cells: f32) -> vec3<u32> {
    let v = max(p * level_scale[l].xyz, vec3<f32>(0.0));
    return min(vec3<u32>(v / brick_cells), level_grid[l].xyz - vec3<u32>(1u));
}

fn entry_of(l: u32, b: vec3<u32>) -> u32 {
    let g = level_grid[l];
    return g.w + b.x + g.x * (b.y + g.y * b.z);
}

// How the level a sample wants grows along a ray, read once per ray: a sample's footprint in
// level-0 voxels per pixel is linear in its index (its distance along the camera's forward axis
// times the pixel's size there), times the level of detail.
struct LevelRamp {
    first: f32,
    per_sample: f32,
    coarsest: u32,
}

fn level_ramp(s: Samples) -> LevelRamp {
    let n0 = level_scale[0].xyz;
    let pixel_voxels = length(frame.ray_dx_texture.xyz * n0) * stream.lod.x;
    let to_world = 2.0 * frame.half_extent.xyz;
    let forward = frame.camera_forward.xyz;
    let first = dot((s.first - frame.eye_texture.xyz) * to_world, forward) * pixel_voxels;
    return LevelRamp(first, dot(s.delta * to_world, forward) * pixel_voxels, stream.brick.w - 1u);
}

// The level sample k wants: the coarsest whose voxel is at most `lod` pixels wide there.
fn wanted_level(k: u32, ramp: LevelRamp) -> u32 {
    let footprint = ramp.first + f32(k) * ramp.per_sample;
    return min(u32(floor(log2(max(footprint, 1.0)))), ramp.coarsest);
}

// Sets a feedback bit of brick `e`, reading first: most rays of a frame find it set already,
// and a read costs less than an atomic write to a word every lane shares.
fn note(e: u32, bit: u32) {
    if ((atomicLoad(&feedback[e]) & bit) == 0u) {
        atomicOr(&feedback[e], bit);
    }
}

// `count` samples of `s` from grid sample k on, each standing for `m` grid samples: at their
// centre (so a coarse step does not shift what the ray sees along it; m = 1 is the grid sample
// itself), with the opacity of m steps, read from the slot `shift` places in the atlas.
fn march_groups(s: Samples, k: u32, count: u32, m: u32, scale: vec3<f32>, shift: vec3<f32>, start: vec4<f32>) -> Marched {
    let inv_atlas = ray_leap_grid.inv_atlas;
    let centre = sample_at(s, k) + s.delta * (0.5 * f32(m - 1u));
    let run = Samples((centre * scale + shift) * inv_atlas, s.delta * f32(m) * scale * inv_atlas, count, s.step * f32(m), s.offset, s.cut);
    // The pass always compiles LEVEL_STEPS (crates/passes/src/raycast_stream/node.rs); the
    // guard lets the file validate on its own.
#if LEVEL_STEPS
    step_multiple = f32(m);
#endif
    return march_dvr(run, 0u, count, start);
}

// What the shared march leaps over inside a run (common/leap_empty.wgsl): the atlas's size and
// slot layout, read from the uniform once per ray (`begin_stream_ray`; on llvmpipe a uniform
// read in a loop is repeated every time, lane by lane).
struct LeapGrid {
    atlas: vec3<f32>,
    inv_atlas: vec3<f32>,
    side: f32,
    apron: f32,
    sub: f32,
    slots: vec2<u32>,
}

var<private> ray_leap_grid: LeapGrid;

fn begin_stream_ray() {
    let side = f32(stream.brick.z);
    let slots = vec2<u32>(stream.atlas.xy / side + vec2<f32>(0.5));
    let atlas = stream.atlas.xyz;
    ray_leap_grid = LeapGrid(atlas, vec3<f32>(1.0) / atlas, side, f32(stream.brick.y), f32(stream.brick.x) / f32(SUB_BLOCKS), slots);
}

fn leap_grid() -> LeapGrid {
    return ray_leap_grid;
}

// The sub-block of the slot that atlas position `p` lies in, and whether it is empty.
fn empty_region_at(p: vec3<f32>, grid: LeapGrid) -> EmptyRegion {
    let t = p * grid.atlas;
    let slot = floor(t / grid.side);
    let last = f32(SUB_BLOCKS - 1u);
    let sb = clamp(floor((t - slot * grid.side - vec3<f32>(grid.apron)) / grid.sub), vec3<f32>(0.0), vec3<f32>(last));
    let s = vec3<u32>(slot);
    let n = f32(SUB_BLOCKS);
    let i = u32(sb.x + n * (sb.y + n * sb.z));
    let word = occupancy[SUB_WORDS * (s.x + grid.slots.x * (s.y + grid.slots.y * s.z)) + (i >> 5u)];
    let lo = (slot * grid.side + vec3<f32>(grid.apron) + sb * grid.sub) / grid.atlas;
    let hi = lo + vec3<f32>(grid.sub) / grid.atlas;
    return EmptyRegion(((word >> (i & 31u)) & 1u) == 0u, lo, hi);
}

fn march_stream(s: Samples) -> vec4<f32> {
    var out = vec4<f32>(0.0);
    begin_ray(s, 0u);
    begin_stream_ray();
    let threshold = params.threshold;
    let brick_cells = f32(stream.brick.x);
    let apron = f32(stream.brick.y);
    let slot_side = vec3<f32>(f32(stream.brick.z));
    let atlas = stream.atlas.xyz;
    let ramp = level_ramp(s);
    let exits = step_exit(s.delta);
    let coarsest = stream.brick.w;
    var k = 0u;
    loop {
        if (k >= s.count || out.a >= threshold) {
            break;
        }
        let p = sample_at(s, k);
        // The wanted level's brick, else the finest coarser one resident (the coarsest always
        // is) — for the samples inside the wanted brick only, so the ray asks for every brick
        // it crosses this frame, not one per frame.
        let want = wanted_level(k, ramp);
        var l = want;
        var b = brick_at(l, p, brick_cells);
        var e = entry_of(l, b);
        var word = page_table[e];
        let want_lo = vec3<f32>(b) * brick_cells;
        let want_scale = level_scale[l].xyz;
        if (word == 0u) {
            note(e, WANTED);
            loop {
                l += 1u;
                b = brick_at(l, p, brick_cells);
                e = entry_of(l, b);
                word = page_table[e];
                if (word != 0u || l + 1u >= coarsest) {
                    break;
                }
            }
        }
        // The wanted brick's box in texture space, and the first sample past it (on the ray's
        // grid): it lies inside the brick drawn from (bricks of a coarser level nest them).
        let scale = level_scale[l];
        let lo = vec3<f32>(b) * brick_cells;
        let box_lo = want_lo / want_scale;
        let box_hi = min((want_lo + vec3<f32>(brick_cells)) / want_scale, vec3<f32>(1.0));
        let exit = min(past_box_by(k, p, exits, box_lo, box_hi), s.count);
        if (word == EMPTY_BRICK || word == 0u) {
            k = exit;
            if (k < s.count) {
                resume_ray(sample_at(s, k) - s.delta);
            }
            continue;
        }
        note(e, DRAWN);
        // One sample for every m of the grid, m = 2^l: the level's step; the samples short of a
        // whole group before the brick's exit are one more sample of their own length, so the
        // run ends exactly at the exit and every grid step is composited once.
        let m = u32(scale.w);
        let slot = vec3<f32>(vec3<u32>(word, word >> 10u, word >> 20u) & vec3<u32>(0x3ffu));
        // Level voxel coordinate v (0 at the volume's face) lies at atlas texel
        // slot·side + apron + (v - lo).
        let shift = slot * slot_side + vec3<f32>(apron) - lo;
        // The way back to the volume's texture space, for what is defined there (cut faces).
        sampled_scale = atlas / scale.xyz;
        sampled_offset = -shift / scale.xyz;
        let groups = (exit - k) / m;
        let rest = exit - k - groups * m;
        if (groups > 0u) {
            let marched = march_groups(s, k, groups, m, scale.xyz, shift, out);
            out = marched.color;
            k += marched.end * m;
        }
        if (rest > 0u && k + rest == exit && out.a < threshold) {
            out = march_groups(s, k, 1u, rest, scale.xyz, shift, out).color;
            k = exit;
        }
        if (k < s.count) {
            resume_ray(sample_at(s, k) - s.delta);
        }
    }
    return out;
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_main(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let p = begin_invocation(group, local);
    if (!in_viewport(p)) {
        return;
    }
    var c = vec4<f32>(0.0);
    let s = pixel_samples(analytic_ray(p), p);
    if (s.count > 0u) {
        c = march_stream(s);
    }
    textureStore(color, vec2<i32>(p), c);
}
