// Empty-space leaping, the one rule (Krüger & Westermann 2003 §2.3; the modern single-pass
// form): from sample k, while it lies in a region the importing shader's empty-space structure
// says is fully transparent, jump to the first sample past that region's box (`past_box`). The
// structure provides `struct LeapGrid`, `fn leap_grid() -> LeapGrid` (its constants: uniforms,
// texture sizes) and `fn empty_region_at(p: vec3<f32>, grid: LeapGrid) -> EmptyRegion` for
// texture-space `p`:
// common/empty_blocks.wgsl (per-block flags), common/empty_cubes.wgsl (Chebyshev distance map:
// the largest cube of empty blocks), raycast_bricks.wgsl (empty leaves, bricks of other batches).
// Lossless: every sample leapt over lies in the closed box of an empty region, whose
// conservative range (a one-voxel apron) also covers the f32 rounding of the box exit.

#import "common/ray_box.wgsl"

// A box in texture space around a sample and whether it is empty (then every sample in the
// closed box classifies to alpha 0).
struct EmptyRegion {
    empty: bool,
    lo: vec3<f32>,
    hi: vec3<f32>,
}

// Where a leap stopped: the first sample at or after the start (before `end`) that may be
// visible, or `end`, and the region around it the importer reported (not empty), whose box a
// march over that region can run to (a brick's cube of drawn leaves).
struct LeapStop {
    k: u32,
    region: EmptyRegion,
}

// What every leap of a ray reads, read once per ray (`leaping_for`): the structure's constants
// and the step's reciprocal. On llvmpipe a uniform or texture-size read inside a loop that calls
// a texture function is repeated every iteration, one lane at a time.
struct Leaping {
    grid: LeapGrid,
    step: StepExit,
}

fn leaping_for(s: Samples) -> Leaping {
    return Leaping(leap_grid(), step_exit(s.delta));
}

fn leap_stop(k_from: u32, s: Samples, end: u32, leaping: Leaping) -> LeapStop {
    var k = k_from;
    var region = EmptyRegion(false, vec3<f32>(0.0), vec3<f32>(0.0));
    let grid = leaping.grid;
    let step = leaping.step;
    loop {
        if (k >= end) {
            break;
        }
        let p = sample_at(s, k);
        region = empty_region_at(p, grid);
        if (!region.empty) {
            break;
        }
        k = past_box_by(k, p, step, region.lo, region.hi);
    }
    return LeapStop(min(k, end), region);
}

// The first sample at or after k (before `end`) that may be visible, or `end`.
fn leap(k_from: u32, s: Samples, end: u32, leaping: Leaping) -> u32 {
    return leap_stop(k_from, s, end, leaping).k;
}
