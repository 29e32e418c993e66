// A pixel's ray in texture space for the fragment, compute and segment raycasters: met
// analytically with the box (ANALYTIC, `rays: "analytic"`: common/ray_box.wgsl, no raster
// passes) or read from Krüger & Westermann 2003 §2.1's targets `entry` ((u0, 1) where the ray
// enters the box, zeros where it misses) and `dir` ((d_tex, len_tex)).

#import "common/ray_box.wgsl"

#if ANALYTIC
fn pixel_ray(pixel: vec2<u32>) -> Ray {
    return analytic_ray(pixel);
}
#else
@group(0) @binding(auto) var entry: texture_2d<f32>;
@group(0) @binding(auto) var dir: texture_2d<f32>;

fn pixel_ray(pixel: vec2<u32>) -> Ray {
#if FUSION_SCALAR
    // With several scalar volumes rays cross the union of their boxes (march_lo/hi), which
    // the rasterized box — the frame volume's — does not cover: met with it from the eye.
    return analytic_ray(pixel);
#else
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    return own_segment(Ray(e.xyz, d.xyz, select(0.0, d.w, e.w != 0.0), 0.0, false));
#endif
}
#endif
