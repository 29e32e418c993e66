// Test shader for runtime semantics: `next = value + amount` per pixel, `fill` writes a constant.
#import "common/fullscreen.wgsl"

@group(0) @binding(0) var value: texture_2d<f32>;

struct AddParams {
    amount: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(1) var<uniform> params: AddParams;

struct AddOut {
    @location(0) next: vec4<f32>,
}

@fragment
fn fs_add_one(in: FullscreenVertex) -> AddOut {
    return AddOut(textureLoad(value, vec2<i32>(in.clip.xy), 0) + vec4<f32>(params.amount, 0.0, 0.0, 0.0));
}

struct FillOut {
    @location(0) filled: vec4<f32>,
}

@fragment
fn fs_fill(in: FullscreenVertex) -> FillOut {
    return FillOut(vec4<f32>(100.0, 0.0, 0.0, 0.0));
}
