// Test shader of crates/passes/tests/fullscreen_overwrite.rs: two fullscreen fragment stages
// writing `image`, one that writes every pixel and one that discards the left half from the
// second frame on.

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"

struct Out {
    @location(0) image: vec4<f32>,
}

// Frame i writes i + 1 everywhere.
@fragment
fn fs_cover(in: FullscreenVertex) -> Out {
    return Out(vec4<f32>(f32(frame.frame_index + 1u)));
}

// Discards the left half from the second frame on.
fn discard_left_half(in: FullscreenVertex) {
    if (frame.frame_index > 0u && in.clip.x < 0.5 * frame.viewport.x) {
        discard;
    }
}

// Frame 0 writes 1 everywhere; later frames discard the left half (in a function it calls, as
// a shared helper would) and write i + 1 on the right.
@fragment
fn fs_half(in: FullscreenVertex) -> Out {
    discard_left_half(in);
    return Out(vec4<f32>(f32(frame.frame_index + 1u)));
}
