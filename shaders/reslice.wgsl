// `reslice`: one axial, coronal or sagittal slice of the volume resampled into the pane
// (`slice`, Rgba8Unorm) and mapped to grey through a window — multi-planar reformatting as the
// clinical viewers show it. The node computes the pane-to-texture map, the slice's rectangle in
// the pane and the window in normalized values from the bound volume
// (crates/passes/src/reslice.rs, `SliceMap::of`); the f64 twin is volgraph_accel::reslice.
// The grey level is written as the display value (a window maps data to what the screen
// shows, as in DICOM's VOI LUT), so the 8-bit target holds it unchanged.

// Declared once: `SliceMap` (pass_params!) in crates/passes/src/reslice.rs.
#import "params/SliceMap.wgsl"

// Normalized scalar values, trilinear with clamp-to-edge: s(u) of the rendering model.
@group(0) @binding(auto) var volume: texture_3d<f32>;
@group(0) @binding(auto) var linear_clamp: sampler;
@group(0) @binding(auto) var<uniform> slice_map: SliceMap;
@group(0) @binding(auto) var slice: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8)
fn cs_reslice(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(slice);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2<f32>(id.xy) + vec2<f32>(0.5);
    var out = vec4<f32>(0.0);
    if (all(p >= slice_map.fit.xy) && all(p <= slice_map.fit.zw)) {
        let u = slice_map.origin.xyz + p.x * slice_map.per_column.xyz + p.y * slice_map.per_row.xyz;
        let s = textureSampleLevel(volume, linear_clamp, u, 0.0).r;
        let grey = clamp((s - slice_map.window.x) * slice_map.window.y, 0.0, 1.0);
        out = vec4<f32>(vec3<f32>(grey), 1.0);
    }
    textureStore(slice, vec2<i32>(id.xy), out);
}
