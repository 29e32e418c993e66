//! The bounding-box triangles of `shaders/common/box.wgsl` are counter-clockwise seen from
//! outside, so that with wgpu's `FrontFace::Ccw` (counter-clockwise in NDC, y up) `cull_mode:
//! Back` keeps the faces toward the eye (Krüger & Westermann 2003 §2.1 pass 1, entry points) and
//! `cull_mode: Front` the faces away from it (pass 2, exits). The test parses the index table out
//! of the WGSL file and projects it with the orbit camera's matrices exactly as `vs_box` does.

use glam::{DVec2, DVec3, DVec4};
use volgraph_accel::camera::OrbitCamera;

/// `BOX_CORNER_INDICES` from shaders/common/box.wgsl.
fn box_indices() -> Vec<u32> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shaders/common/box.wgsl");
    let text = std::fs::read_to_string(path).expect("shaders/common/box.wgsl is part of the repository");
    let start = text.find("BOX_CORNER_INDICES = array<u32, 36>(").expect("box.wgsl declares BOX_CORNER_INDICES");
    let body = &text[start..];
    let open = body.find('(').expect("array constructor has '('") + 1;
    let close = body.find(')').expect("array constructor has ')'");
    body[open..close]
        .split(',')
        .map(|t| t.trim().trim_end_matches('u').parse::<u32>().expect("indices are u32 literals"))
        .collect()
}

/// `box_corner`: bit 0 → x, bit 1 → y, bit 2 → z, each ±1.
fn corner(i: u32) -> DVec3 {
    let c = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
    DVec3::new(c(1), c(2), c(4))
}

fn triangles() -> Vec<[DVec3; 3]> {
    let idx = box_indices();
    assert_eq!(idx.len(), 36, "12 triangles");
    idx.chunks(3).map(|t| [corner(t[0]), corner(t[1]), corner(t[2])]).collect()
}

/// Twice the signed area of a 2D triangle (shoelace): positive when counter-clockwise in a
/// y-up frame.
fn signed_area2(p: [DVec2; 3]) -> f64 {
    (p[1] - p[0]).perp_dot(p[2] - p[0])
}

#[test]
fn every_triangle_is_counter_clockwise_from_outside() {
    for (i, t) in triangles().iter().enumerate() {
        let normal = (t[1] - t[0]).cross(t[2] - t[0]);
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        // The box is centred at the origin, so outward means along the centroid. |normal| is
        // twice the area, 4, for a right triangle with legs 2, and the centroid lies on the face
        // plane at distance 1, so the product is exactly 4 for an outward triangle, -4 inward.
        assert_eq!(normal.dot(centroid), 4.0, "triangle {i} {t:?} faces inward (normal {normal})");
    }
}

#[test]
fn box_is_closed_and_consistently_oriented() {
    // Every directed edge of a closed, consistently wound mesh appears once, its reverse once.
    let idx = box_indices();
    let mut edges = std::collections::BTreeMap::new();
    for t in idx.chunks(3) {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "edge {a}->{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}->{b} has no reverse");
    }
    assert_eq!(edges.len(), 36, "12 triangles × 3 directed edges");
}

#[test]
fn faces_toward_the_eye_are_ccw_in_ndc_and_in_framebuffer_terms() {
    let half = DVec3::new(0.5, 0.3, 0.2); // non-cubic, as vs_box scales by half_extent
    let (w, h) = (640u32, 480u32);
    let mut checked_nearest = 0;
    for az in (-180..180).step_by(25) {
        for el in [-80.0, -45.0, -10.0, 0.0, 10.0, 45.0, 80.0, 90.0] {
            let camera = OrbitCamera { azimuth_deg: az as f64, elevation_deg: el, distance: 2.2, ..Default::default() };
            let frame = camera.frame(w, h);
            let mut nearest: Option<(f64, bool, bool)> = None;
            for t in triangles() {
                let world = t.map(|c| c * half);
                // vs_box: clip = clip_from_world * (corner * half, 1); the rasterizer divides by w.
                let clip = world.map(|p| frame.clip_from_world * DVec4::from((p, 1.0)));
                assert!(clip.iter().all(|c| c.w > 0.0), "camera at distance 2.2 sees the box in front");
                let ndc = clip.map(|c| DVec2::new(c.x / c.w, c.y / c.w));
                // Framebuffer coordinates, y down (row 0 at the top), as wgpu rasterizes.
                let fb = ndc.map(|p| DVec2::new((p.x + 1.0) * 0.5 * w as f64, (1.0 - p.y) * 0.5 * h as f64));
                let normal = (world[1] - world[0]).cross(world[2] - world[0]).normalize();
                let centroid = (world[0] + world[1] + world[2]) / 3.0;
                let to_eye = (frame.eye - centroid).normalize();
                let facing = normal.dot(to_eye);
                if facing.abs() < 1e-3 {
                    continue; // edge-on: zero area, culled either way
                }
                let ccw_ndc = signed_area2(ndc) > 0.0;
                // y-down flips the sign: a triangle that looks counter-clockwise on screen has a
                // negative shoelace area in framebuffer coordinates.
                let ccw_on_screen = signed_area2(fb) < 0.0;
                assert_eq!(ccw_ndc, ccw_on_screen, "NDC and framebuffer must agree (az {az}, el {el})");
                assert_eq!(facing > 0.0, ccw_ndc, "az {az}, el {el}: triangle {world:?} facing {facing}");
                let dist = (frame.eye - centroid).length();
                if nearest.is_none_or(|(d, _, _)| dist < d) {
                    nearest = Some((dist, facing > 0.0, ccw_ndc));
                }
            }
            let (_, facing, ccw) = nearest.expect("some triangle is not edge-on");
            assert!(facing && ccw, "az {az}, el {el}: the triangle nearest the eye must face it and be CCW");
            checked_nearest += 1;
        }
    }
    assert_eq!(checked_nearest, 15 * 8);
}
