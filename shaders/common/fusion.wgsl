// Several volumes in one march (crates/passes/src/fusion.rs; the f64 model is
// volgraph_accel::fusion, docs/rendering_model.md "Several volumes"): each sample of the frame
// volume is classified with a second volume sampled at the same patient-frame point, or, with
// FUSION_LABELS, the frame volume is itself a label map. Compiled in only with FUSION:
// - FUSION_LABELS: the frame volume's label, coloured through `label_table`;
// - FUSION_LABEL_MAP: `second` is a label map: `tint` colours the scan by the visible label,
//   `inside` keeps the scan only inside visible labels;
// - FUSION_SCALAR: `second` is scalar with its own `second_tf`: `fuse` (two media in one place)
//   or `add` (channels); FUSION_THIRD and FUSION_FOURTH add `third`/`third_tf` and
//   `fourth`/`fourth_tf` (up to four channels, all media in one place); with FUSION_OVERLAY a third volume, the label map `overlay`, lies over
//   the pair (`tint` or `inside`, as a label map does to one scan);
// - FUSION_LABEL_READS: one of the above samples a label map (the frame volume, `second` or
//   `overlay`: "the label map" below);
// - LABELS_NEAREST: labels at the nearest voxel, else each label's indicator interpolated and
//   the largest taken (a tie to the smaller label), so no label number is ever blended.

// Declared once: `FusionMap` (pass_params!) in crates/passes/src/fusion.rs.
#import "params/FusionMap.wgsl"
#import "common/nearest_clamp.wgsl"

@group(0) @binding(auto) var<uniform> fusion: FusionMap;

const COMBINE_INSIDE: u32 = 3u;
const COMBINE_ADD: u32 = 5u;

// The uniform's values and the textures' sizes, read once per ray (`begin_fusion`, from
// `begin_ray`): on llvmpipe a uniform or texture-size read inside the sample loop is repeated
// every sample, one lane at a time.
var<private> fusion_scale: vec3<f32>;
var<private> fusion_offset: vec3<f32>;
var<private> fusion_decode: vec2<f32>;
var<private> fusion_combine: u32;
#if FUSION_LABEL_READS
// The label map's voxels per axis, their inverse, and the label table's texel size.
var<private> label_n: vec3<f32>;
var<private> label_inv_n: vec3<f32>;
var<private> label_table_texel: vec2<f32>;
#endif
#if FUSION_OVERLAY
// Where the overlay lies, and what it does.
var<private> overlay_scale: vec3<f32>;
var<private> overlay_offset: vec3<f32>;
var<private> overlay_combine: u32;
#endif

fn begin_fusion() {
    fusion_scale = fusion.second_scale.xyz;
    fusion_offset = fusion.second_offset.xyz;
    fusion_combine = fusion.combine;
#if FUSION_LABELS
    fusion_decode = fusion.first_labels.xy;
#else
    fusion_decode = fusion.second_labels.xy;
#endif
#if FUSION_OVERLAY
    fusion_decode = fusion.overlay_labels.xy;
    overlay_scale = fusion.overlay_scale.xyz;
    overlay_offset = fusion.overlay_offset.xyz;
    overlay_combine = fusion.overlay_combine;
#endif
#if FUSION_LABEL_READS
    label_n = vec3<f32>(label_dims());
    label_inv_n = vec3<f32>(1.0) / label_n;
    label_table_texel = vec2<f32>(1.0) / vec2<f32>(textureDimensions(label_table));
    label_known = false;
#endif
}

#if FUSION_LABEL_READS
// Where the label map lies: its texture point is volume_position(u) · scale + offset (the frame
// volume itself with FUSION_LABELS).
fn label_map_scale() -> vec3<f32> {
    var scale = vec3<f32>(1.0);
#if FUSION_LABEL_MAP
    scale = fusion_scale;
#endif
#if FUSION_OVERLAY
    scale = overlay_scale;
#endif
    return scale;
}

fn label_map_offset() -> vec3<f32> {
    var offset = vec3<f32>(0.0);
#if FUSION_LABEL_MAP
    offset = fusion_offset;
#endif
#if FUSION_OVERLAY
    offset = overlay_offset;
#endif
    return offset;
}
#endif

#if FUSION_LABEL_MAP
// The second volume (a label map), normalized texels.
@group(0) @binding(auto) var second: texture_3d<f32>;
#endif
#if FUSION_SCALAR
// The second scalar volume and its transfer function.
@group(0) @binding(auto) var second: texture_3d<f32>;
@group(0) @binding(auto) var second_tf: texture_1d<f32>;
#endif
#if FUSION_THIRD
@group(0) @binding(auto) var third: texture_3d<f32>;
@group(0) @binding(auto) var third_tf: texture_1d<f32>;
#endif
#if FUSION_FOURTH
@group(0) @binding(auto) var fourth: texture_3d<f32>;
@group(0) @binding(auto) var fourth_tf: texture_1d<f32>;
#endif
#if FUSION_SCALAR
#if PREINTEGRATION
// With PREINTEGRATION each scalar medium composites its own TF's segment from its field at the
// sample before to its field here (`preintegrated` is the frame volume's table; these, built
// the same way, its partners'), and media in one place combine segments as they combine
// samples (volgraph_accel::fusion::Fusion::classify_scan). The fields at the sample before:
@group(0) @binding(auto) var second_preintegrated: texture_2d<f32>;
var<private> second_front: f32;
#if FUSION_THIRD
@group(0) @binding(auto) var third_preintegrated: texture_2d<f32>;
var<private> third_front: f32;
#endif
#if FUSION_FOURTH
@group(0) @binding(auto) var fourth_preintegrated: texture_2d<f32>;
var<private> fourth_front: f32;
#endif
#endif
#endif

#if FUSION_LABELS
// Colour and opacity per label value: label v at texel (v % 256, v / 256); 0 where hidden.
@group(0) @binding(auto) var label_table: texture_2d<f32>;

// The label map is the frame volume.
fn label_texel(at: vec3<f32>) -> f32 {
    return textureSampleLevel(volume, nearest_clamp, at, 0.0).r;
}
fn label_dims() -> vec3<i32> {
    return vec3<i32>(textureDimensions(volume));
}
#endif
#if FUSION_LABEL_MAP
@group(0) @binding(auto) var label_table: texture_2d<f32>;

// The label map is the second volume.
fn label_texel(at: vec3<f32>) -> f32 {
    return textureSampleLevel(second, nearest_clamp, at, 0.0).r;
}
fn label_dims() -> vec3<i32> {
    return vec3<i32>(textureDimensions(second));
}
#endif
#if FUSION_OVERLAY
@group(0) @binding(auto) var label_table: texture_2d<f32>;
// The third volume, a label map over the scalar pair, normalized texels.
@group(0) @binding(auto) var overlay: texture_3d<f32>;

// The label map is the overlay.
fn label_texel(at: vec3<f32>) -> f32 {
    return textureSampleLevel(overlay, nearest_clamp, at, 0.0).r;
}
fn label_dims() -> vec3<i32> {
    return vec3<i32>(textureDimensions(overlay));
}
#endif

#if FUSION_LABEL_READS
// A march's stretch of samples inside one label (common/label_cubes.wgsl): its label's table
// entry, and whether the sample being classified lies in it — then the label map is not read.
var<private> label_run_entry: vec4<f32>;
var<private> label_known: bool = false;

#if LABELS_NEAREST
#else
// Per voxel (x, y, z) the labels of voxels (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1) of
// its slice, clamped at the faces (volgraph_accel::labels::sample::label_quads): a sample's 8
// corners in two reads.
@group(0) @binding(auto) var label_quads: texture_3d<u32>;
#endif

// The label value of the voxel whose centre is at texture point `at` (the sampler clamps to the
// map's edge): a texel holds (v - lo) / (hi - lo), so v = lo + texel · (hi - lo).
fn label_at(at: vec3<f32>) -> u32 {
    let d = fusion_decode;
    return u32(max(round(d.x + label_texel(at) * d.y), 0.0));
}

// The label at the label map's texture point `u` (volgraph_accel::labels::sample_label).
fn sample_label(u: vec3<f32>) -> u32 {
    let p = u * label_n - vec3<f32>(0.5);
#if LABELS_NEAREST
    return label_at((floor(p + vec3<f32>(0.5)) + vec3<f32>(0.5)) * label_inv_n);
#else
    // Two reads whatever the sample. (A first read of a 4³ block's label where it is uniform
    // would spare a GPU's warps inside a structure the two, but llvmpipe runs both sides of
    // every branch: three reads a sample there, tried, 11–20 % slower; bench/multi.md.)
    let top = vec3<i32>(label_n) - vec3<i32>(1);
    let base = floor(p);
    let f = p - base;
    let g = vec3<f32>(1.0) - f;
    // The 8 corners' labels, corner (x, y, z) at x + 2y + 4z of (la, lb): the quads of the two
    // slices at the low corner (clamped into the map). Below the low faces (p < 0) both corners
    // of an axis are the face's voxel, as the clamped reads were: the quad's low entries twice.
    let lo = clamp(vec3<i32>(base), vec3<i32>(0), top);
    let z1 = min(lo.z + 1, top.z);
    let low = base < vec3<f32>(0.0);
    var la = textureLoad(label_quads, lo, 0);
    var lb = textureLoad(label_quads, vec3<i32>(lo.xy, select(z1, lo.z, low.z)), 0);
    la = select(la, la.xxzz, low.x);
    lb = select(lb, lb.xxzz, low.x);
    la = select(la, la.xyxy, low.y);
    lb = select(lb, lb.xyxy, low.y);
    let wa = vec4<f32>(g.x * g.y, f.x * g.y, g.x * f.y, f.x * f.y) * g.z;
    let wb = vec4<f32>(g.x * g.y, f.x * g.y, g.x * f.y, f.x * f.y) * f.z;
    // The nearest voxel's label holds the largest single weight: with more than half of the
    // weight it wins outright (the common case on a boundary between two labels).
    let o = vec3<u32>(f >= vec3<f32>(0.5));
    let k = o.x + 2u * o.y;
    let nearest_label = select(la[k], lb[k], o.z == 1u);
    var best = nearest_label;
    var best_w = label_weight(nearest_label, la, lb, wa, wb);
    // Else every corner's label by its summed weight; a tie goes to the smaller label (a loop
    // no lane takes a turn of where the nearest label won, for llvmpipe as above).
    let turns = select(4u, 0u, best_w > 0.5);
    for (var i = 0u; i < turns; i++) {
        let wi = label_weight(la[i], la, lb, wa, wb);
        if (wi > best_w || (wi == best_w && la[i] < best)) {
            best = la[i];
            best_w = wi;
        }
        let wj = label_weight(lb[i], la, lb, wa, wb);
        if (wj > best_w || (wj == best_w && lb[i] < best)) {
            best = lb[i];
            best_w = wj;
        }
    }
    return best;
#endif
}

#if LABELS_NEAREST
#else
// The summed weight of `label` over the corners (labels `la`, `lb`, weights `wa`, `wb`).
fn label_weight(label: u32, la: vec4<u32>, lb: vec4<u32>, wa: vec4<f32>, wb: vec4<f32>) -> f32 {
    let one = vec4<f32>(1.0);
    return dot(select(vec4<f32>(0.0), wa, la == vec4<u32>(label)), one) + dot(select(vec4<f32>(0.0), wb, lb == vec4<u32>(label)), one);
}
#endif

// The table's colour and opacity of `label` (hidden past its end), read at its texel's centre.
fn label_entry(label: u32) -> vec4<f32> {
    let at = (vec2<f32>(f32(label % 256u), f32(label / 256u)) + vec2<f32>(0.5)) * label_table_texel;
    if (at.y >= 1.0) {
        return vec4<f32>(0.0);
    }
    return textureSampleLevel(label_table, nearest_clamp, at, 0.0);
}
#endif

// Straight colour `c` with the corrected opacity of `a_tf`, premultiplied.
fn premultiplied(c: vec3<f32>, a_tf: f32) -> vec4<f32> {
    let a = corrected_alpha(a_tf);
    return vec4<f32>(c * a, a);
}

// Whether the texture point `u` lies in the box (voxel centres ± half a voxel).
fn in_box(u: vec3<f32>) -> bool {
    return all(u >= vec3<f32>(0.0)) && all(u <= vec3<f32>(1.0));
}

// The premultiplied, opacity-corrected colour of the sample at the frame volume's texture point
// `u`, whose field is `s` (volgraph_accel::fusion::Fusion::classify).
fn fused_sample(u: vec3<f32>, s: f32) -> vec4<f32> {
#if FUSION_LABELS
    var e = label_run_entry;
    if (!label_known) {
        e = label_entry(sample_label(u));
    }
    return premultiplied(e.rgb, e.a);
#else
    let c = sample_tf(s);
    // The frame volume's texture point (`u` is a brick atlas's in raycast_bricks).
    let uv = volume_position(u);
    let u2 = uv * fusion_scale + fusion_offset;
#if FUSION_LABEL_MAP
    // The scan's straight colour and corrected opacity: its TF at s, or with PREINTEGRATION the
    // segment from the previous sample to this one (volgraph_accel::fusion::classify_scan).
#if PREINTEGRATION
    let segment = lookup_preintegrated(ray_prev_scalar, s);
    ray_prev_scalar = s;
    let scan = vec4<f32>(select(vec3<f32>(0.0), segment.rgb / segment.a, segment.a > 0.0), segment.a);
#else
    let scan = vec4<f32>(c.rgb, corrected_alpha(c.a));
#endif
    // Where the scan is clear the label changes nothing (tint and inside keep its opacity).
    if (!(scan.a > 0.0)) {
        return vec4<f32>(0.0);
    }
    var e = label_run_entry;
    if (!label_known) {
        e = label_entry_at(u2);
    }
    let visible = e.a > 0.0;
    if (fusion_combine == COMBINE_INSIDE) {
        let a = select(0.0, scan.a, visible);
        return vec4<f32>(scan.rgb * a, a);
    }
    var rgb = scan.rgb;
    if (visible) {
        rgb = mix(scan.rgb, e.rgb, min(e.a, 1.0));
    }
    return vec4<f32>(rgb * scan.a, scan.a);
#endif
#if FUSION_SCALAR
    // Past the frame volume's box (rays cross every scalar volume's) it adds nothing.
#if PREINTEGRATION
    let p1 = select(vec4<f32>(0.0), lookup_preintegrated(ray_prev_scalar, s), in_box(uv));
    ray_prev_scalar = s;
#else
    let p1 = select(vec4<f32>(0.0), premultiplied(c.rgb, c.a), in_box(uv));
#endif
    let p2 = second_medium(u2);
    // Media in one place: opacity 1 - Π(1 - aᵢ); colour the opacity-weighted mean, or
    // (channels) the sum. `sum` holds Σ premultiplied colours and Σ opacities.
    var sum = p1 + p2;
    var clear = (1.0 - p1.a) * (1.0 - p2.a);
#if FUSION_THIRD
    let p3 = third_medium(uv * fusion.third_scale.xyz + fusion.third_offset.xyz);
    sum += p3;
    clear *= 1.0 - p3.a;
#endif
#if FUSION_FOURTH
    let p4 = fourth_medium(uv * fusion.fourth_scale.xyz + fusion.fourth_offset.xyz);
    sum += p4;
    clear *= 1.0 - p4.a;
#endif
    let a = 1.0 - clear;
    var fused = vec4<f32>(sum.rgb, a);
    if (fusion_combine != COMBINE_ADD) {
        if (!(sum.a > 0.0)) {
            return vec4<f32>(0.0);
        }
        fused = vec4<f32>(sum.rgb * (a / sum.a), a);
    }
#if FUSION_OVERLAY
    return overlaid(fused, uv);
#else
    return fused;
#endif
#endif
#endif
}

#if FUSION_SCALAR
// Scalar volume `v` through its TF `tf` at its texture point `at` (straight colour and the TF's
// opacity; nothing outside its box).
fn scalar_tf_at(v: texture_3d<f32>, tf: texture_1d<f32>, at: vec3<f32>) -> vec4<f32> {
    if (!in_box(at)) {
        return vec4<f32>(0.0);
    }
    let s = textureSampleLevel(v, linear_clamp, at, 0.0).r;
    return textureSampleLevel(tf, linear_clamp, s, 0.0);
}

// The premultiplied, corrected sample of scalar volume `v` through its TF `tf` at its texture
// point `at` (nothing outside its box).
fn scalar_medium(v: texture_3d<f32>, tf: texture_1d<f32>, at: vec3<f32>) -> vec4<f32> {
    let c = scalar_tf_at(v, tf, at);
    return premultiplied(c.rgb, c.a);
}

#if PREINTEGRATION
// A scalar medium's segment to its texture point `at` from its field `front` at the sample
// before, through its pre-integration `table` (nothing outside its box), and its field at `at`
// (the next segment's front).
struct MediumSegment {
    color: vec4<f32>,
    field: f32,
}

fn medium_segment(v: texture_3d<f32>, table: texture_2d<f32>, front: f32, at: vec3<f32>) -> MediumSegment {
    let field = textureSampleLevel(v, linear_clamp, at, 0.0).r;
    let color = select(vec4<f32>(0.0), lookup_segment(table, front, field), in_box(at));
    return MediumSegment(color, field);
}

// The partners' fields at the frame volume's texture point `u` (not an atlas's): the fronts of
// their first segments after a ray starts or resumes (`resume_ray`).
fn resume_media(u: vec3<f32>) {
    second_front = textureSampleLevel(second, linear_clamp, u * fusion_scale + fusion_offset, 0.0).r;
#if FUSION_THIRD
    third_front = textureSampleLevel(third, linear_clamp, u * fusion.third_scale.xyz + fusion.third_offset.xyz, 0.0).r;
#endif
#if FUSION_FOURTH
    fourth_front = textureSampleLevel(fourth, linear_clamp, u * fusion.fourth_scale.xyz + fusion.fourth_offset.xyz, 0.0).r;
#endif
}
#endif

// Each partner's sample (or, with PREINTEGRATION, segment) at its texture point `at`.
fn second_medium(at: vec3<f32>) -> vec4<f32> {
#if PREINTEGRATION
    let m = medium_segment(second, second_preintegrated, second_front, at);
    second_front = m.field;
    return m.color;
#else
    return scalar_medium(second, second_tf, at);
#endif
}

#if FUSION_THIRD
fn third_medium(at: vec3<f32>) -> vec4<f32> {
#if PREINTEGRATION
    let m = medium_segment(third, third_preintegrated, third_front, at);
    third_front = m.field;
    return m.color;
#else
    return scalar_medium(third, third_tf, at);
#endif
}
#endif

#if FUSION_FOURTH
fn fourth_medium(at: vec3<f32>) -> vec4<f32> {
#if PREINTEGRATION
    let m = medium_segment(fourth, fourth_preintegrated, fourth_front, at);
    fourth_front = m.field;
    return m.color;
#else
    return scalar_medium(fourth, fourth_tf, at);
#endif
}
#endif
#endif

#if FUSION_LABEL_READS
// The table's entry of the label at the label map's texture point `at` (hidden — zero —
// outside its box, where it reads background 0; volgraph_accel::fusion's label_entry_at).
fn label_entry_at(at: vec3<f32>) -> vec4<f32> {
    var label = 0u;
    if (in_box(at)) {
        label = sample_label(at);
    }
    return label_entry(label);
}

// Whether a visible label lies at the label map's texture point `at`.
fn visible_label_at(at: vec3<f32>) -> bool {
    return label_entry_at(at).a > 0.0;
}
#endif

// The opacity of the sample at `u` (the frame volume's field `s`) before the step's correction,
// as the combination makes it (volgraph_accel::fusion::Fusion::alpha): what the light volume of
// the `shadows` and `ambient_occlusion` effects attenuates by (light_volume.wgsl).
fn fused_alpha(u: vec3<f32>, s: f32) -> f32 {
#if FUSION_LABELS
    return clamp(label_entry(sample_label(u)).a, 0.0, 1.0);
#else
    let a1 = clamp(sample_tf(s).a, 0.0, 1.0);
    let uv = volume_position(u);
    let u2 = uv * fusion_scale + fusion_offset;
#if FUSION_LABEL_MAP
    if (fusion_combine == COMBINE_INSIDE && !visible_label_at(u2)) {
        return 0.0;
    }
    return a1;
#endif
#if FUSION_SCALAR
    var clear = (1.0 - select(0.0, a1, in_box(uv))) * (1.0 - clamp(scalar_tf_at(second, second_tf, u2).a, 0.0, 1.0));
#if FUSION_THIRD
    clear *= 1.0 - clamp(scalar_tf_at(third, third_tf, uv * fusion.third_scale.xyz + fusion.third_offset.xyz).a, 0.0, 1.0);
#endif
#if FUSION_FOURTH
    clear *= 1.0 - clamp(scalar_tf_at(fourth, fourth_tf, uv * fusion.fourth_scale.xyz + fusion.fourth_offset.xyz).a, 0.0, 1.0);
#endif
#if FUSION_OVERLAY
    if (overlay_combine == COMBINE_INSIDE && !visible_label_at(uv * overlay_scale + overlay_offset)) {
        return 0.0;
    }
#endif
    return 1.0 - clear;
#endif
#endif
}

#if FUSION_OVERLAY
// The premultiplied sample `fused` of the pair under the overlay at the frame volume's texture
// point `u` (not an atlas's) (volgraph_accel::fusion::Fusion::overlaid): `inside` keeps it only where a visible
// label lies; `tint` moves its colour towards the visible label's by the label's opacity.
fn overlaid(fused: vec4<f32>, u: vec3<f32>) -> vec4<f32> {
    let a = fused.a;
    if (!(a > 0.0)) {
        return vec4<f32>(0.0);
    }
    var e = label_run_entry;
    if (!label_known) {
        e = label_entry_at(u * overlay_scale + overlay_offset);
    }
    let visible = e.a > 0.0;
    if (overlay_combine == COMBINE_INSIDE) {
        return select(vec4<f32>(0.0), fused, visible);
    }
    if (!visible) {
        return fused;
    }
    let straight = fused.rgb / a;
    return vec4<f32>(mix(straight, e.rgb, min(e.a, 1.0)) * a, a);
}
#endif
