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

#if RESLICE_LABELS
// A label map over the slice (`labels: true`): the nearest voxel's label, coloured by its row of
// `label_table` (label v at texel (v % 256, v / 256); colour as display values, opacity 0 where
// hidden) — volgraph_accel::reslice::LabelOverlay.
@group(0) @binding(auto) var labels: texture_3d<f32>;
@group(0) @binding(auto) var nearest_clamp: sampler;
@group(0) @binding(auto) var label_table: texture_2d<f32>;

// The label colour and its cover at the slice volume's texture point `u`; cover 0 outside the
// map, where the label is hidden or beyond the table.
fn label_colour(u: vec3<f32>) -> vec4<f32> {
    let v = u * slice_map.label_scale.xyz + slice_map.label_offset.xyz;
    if (any(v < vec3<f32>(0.0)) || any(v > vec3<f32>(1.0))) {
        return vec4<f32>(0.0);
    }
    // The nearest voxel's centre (clamped to the map's edge by the sampler).
    let n = vec3<f32>(textureDimensions(labels));
    let centre = (floor(v * n) + vec3<f32>(0.5)) / n;
    let texel = textureSampleLevel(labels, nearest_clamp, centre, 0.0).r;
    let value = u32(max(round(slice_map.label_decode.x + texel * slice_map.label_decode.y), 0.0));
    let at = vec2<u32>(value % 256u, value / 256u);
    if (at.y >= textureDimensions(label_table).y) {
        return vec4<f32>(0.0);
    }
    let c = textureLoad(label_table, at, 0);
    return vec4<f32>(c.rgb, c.a * slice_map.label_decode.z);
}
#endif

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
#if RESLICE_LABELS
        let label = label_colour(u);
        out = vec4<f32>(mix(out.rgb, label.rgb, label.a), 1.0);
#endif
    }
    textureStore(slice, vec2<i32>(id.xy), out);
}
