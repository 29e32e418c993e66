// Test shader for executor semantics: `next = value + 1` per pixel, `fill` writes a constant.
#import "common/fullscreen.wgsl"

@group(0) @binding(0) var value: texture_2d<f32>;

struct AddOut {
    @location(0) next: vec4<f32>,
}

@fragment
fn fs_add_one(in: FullscreenVertex) -> AddOut {
    return AddOut(textureLoad(value, vec2<i32>(in.clip.xy), 0) + vec4<f32>(1.0, 0.0, 0.0, 0.0));
}

struct FillOut {
    @location(0) filled: vec4<f32>,
}

@fragment
fn fs_fill(in: FullscreenVertex) -> FillOut {
    return FillOut(vec4<f32>(100.0, 0.0, 0.0, 0.0));
}
