// Slice-based volume rendering (SBVR), the baseline of Krüger & Westermann 2003 Table 1 (§1.1,
// Figure 1): view-aligned planes through the volume box, each drawn as its intersection
// polygon with the box and blended front to back (dst += (1 - dst.a)·src, the paper's
// front-to-back equation with premultiplied source). No rays: every pixel's samples lie where
// its view ray crosses the planes.
//
// Plane i sits at distance d_i = (floor(d_near / Δ) + i + 0.5)·Δ along the camera's forward axis
// (Δ = slice_voxels · unit_world), so the planes stay put as the box moves through them. The
// vertex stage of instance i computes the plane's polygon (≤ 6 edge crossings, sorted by angle,
// drawn as a 4-triangle fan; missing triangles and planes outside the box degenerate to a
// point). Opacity correction uses the distance between planes along the pixel's ray,
// Δ / cos θ in unit steps, so the sum approximates the same integral as the raycasters.
//
// Pipeline: `vs_slice` + `fs_slice` → `color` (blended); draw(0..12, 0..max_slices).

#import "common/frame.wgsl"
#import "common/volume.wgsl"

// Declared once: `SliceParams` (pass_params!) in crates/passes/src/slice_render.rs,
// which generates the struct imported here.
#import "params/SliceParams.wgsl"

@group(0) @binding(auto) var<uniform> slices: SliceParams;

struct SliceVertex {
    @builtin(position) clip: vec4<f32>,
    // World position on the plane (interpolated perspective-correctly).
    @location(0) world: vec3<f32>,
}

// The 12 box edges as pairs of corner indices (corner bit 0: +x, bit 1: +y, bit 2: +z).
const EDGES = array<vec2<u32>, 12>(
    vec2<u32>(0u, 1u), vec2<u32>(2u, 3u), vec2<u32>(4u, 5u), vec2<u32>(6u, 7u),
    vec2<u32>(0u, 2u), vec2<u32>(1u, 3u), vec2<u32>(4u, 6u), vec2<u32>(5u, 7u),
    vec2<u32>(0u, 4u), vec2<u32>(1u, 5u), vec2<u32>(2u, 6u), vec2<u32>(3u, 7u),
);

fn corner(i: u32) -> vec3<f32> {
    let s = vec3<f32>(select(-1.0, 1.0, (i & 1u) != 0u), select(-1.0, 1.0, (i & 2u) != 0u), select(-1.0, 1.0, (i & 4u) != 0u));
    return s * frame.half_extent.xyz;
}

// World distance between planes.
fn plane_spacing() -> f32 {
    return slices.slice_voxels * frame.half_extent.w;
}

@vertex
fn vs_slice(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) instance: u32) -> SliceVertex {
    let eye = frame.eye_world.xyz;
    let f = frame.camera_forward.xyz;
    let spacing = plane_spacing();
    // Nearest box corner along f, but never in front of the near plane.
    var d_near = 3.0e38;
    for (var c = 0u; c < 8u; c += 1u) {
        d_near = min(d_near, dot(corner(c) - eye, f));
    }
    d_near = max(d_near, frame.camera_forward.w);
    let d = (floor(d_near / spacing) + f32(instance) + 0.5) * spacing;
    // Crossings of the plane dot(p - eye, f) = d with the box edges.
    var points: array<vec3<f32>, 6>;
    var count = 0u;
    for (var e = 0u; e < 12u; e += 1u) {
        let a = corner(EDGES[e].x);
        let b = corner(EDGES[e].y);
        let da = dot(a - eye, f) - d;
        let db = dot(b - eye, f) - d;
        if (count < 6u && ((da <= 0.0 && db > 0.0) || (da > 0.0 && db <= 0.0))) {
            points[count] = a + (b - a) * (da / (da - db));
            count += 1u;
        }
    }
    var out: SliceVertex;
    out.world = eye + d * f;
    out.clip = vec4<f32>(0.0, 0.0, 2.0, 1.0); // degenerate, outside the depth range
    if (count < 3u) {
        return out;
    }
    // Sort by angle around the centroid (insertion sort of ≤ 6 points).
    var centre = vec3<f32>(0.0);
    for (var i = 0u; i < count; i += 1u) {
        centre += points[i];
    }
    centre /= f32(count);
    let axis_u = normalize(points[0] - centre);
    let axis_v = cross(f, axis_u);
    var angles: array<f32, 6>;
    for (var i = 0u; i < count; i += 1u) {
        let p = points[i] - centre;
        angles[i] = atan2(dot(p, axis_v), dot(p, axis_u));
    }
    for (var i = 1u; i < count; i += 1u) {
        var j = i;
        while (j > 0u && angles[j - 1u] > angles[j]) {
            let ta = angles[j];
            angles[j] = angles[j - 1u];
            angles[j - 1u] = ta;
            let tp = points[j];
            points[j] = points[j - 1u];
            points[j - 1u] = tp;
            j -= 1u;
        }
    }
    // Triangle fan: triangle k = (0, k+1, k+2) for k + 2 < count.
    let k = vertex_index / 3u;
    let corner_in_triangle = vertex_index % 3u;
    if (k + 2u >= count) {
        return out;
    }
    var p = points[0];
    if (corner_in_triangle == 1u) {
        p = points[k + 1u];
    } else if (corner_in_triangle == 2u) {
        p = points[k + 2u];
    }
    out.world = p;
    out.clip = frame.clip_from_world * vec4<f32>(p, 1.0);
    return out;
}

struct SliceOut {
    @location(0) color: vec4<f32>,
}

@fragment
fn fs_slice(in: SliceVertex) -> SliceOut {
    let u = texture_from_world(in.world);
    let c = sample_tf(sample_volume(clamp(u, vec3<f32>(0.0), vec3<f32>(1.0))));
    let cos_theta = abs(dot(normalize(in.world - frame.eye_world.xyz), frame.camera_forward.xyz));
    let a_tf = clamp(c.a, 0.0, 1.0);
    var alpha = 0.0;
    if (a_tf >= 1.0) {
        alpha = 1.0;
    } else if (a_tf > 0.0) {
        alpha = 1.0 - pow(1.0 - a_tf, slices.slice_voxels / max(cos_theta, 1e-3));
    }
    return SliceOut(vec4<f32>(alpha * c.rgb, alpha));
}
