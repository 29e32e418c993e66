//! The screen footprint of the volume: the image points whose ray meets the box a frame's rays
//! are met with (`shaders/common/ray_box.wgsl` `analytic_ray`: the grid box, cut to a sort-last
//! window's own box, the scene's crop box and clip planes, past the near plane) — the projection
//! of a convex body, so a convex polygon, computed once per frame on the CPU from the frame's
//! uniform block. Two uses:
//! - the frame block carries it, grown by a pixel, as a fan of triangles
//!   ([`FrameUniforms::footprint`], `shaders/common/footprint.wgsl`): a fragment pass whose
//!   pixels without a ray write zeros draws that instead of the screen
//!   ([`super::RecordContext::draw_footprint`]), so no fragment outside it runs — on llvmpipe,
//!   which runs every line of a shader for every pixel it draws, that is most of a raycast's
//!   fixed cost (bench/one-march-final.md, "Footprint draws");
//! - `hole_fill` takes one span per image row ([`Footprint::row_spans`]) and asks whether a
//!   pixel lies near the footprint's edge with two reads where it used to meet four corner rays
//!   with the box (Klein et al. 2005 §4.4).
//!
//! Everything happens in the texture space of the shaders: image point (x, y) (pixel centres at
//! +0.5) looks along `base + x·dx + y·dy` from the eye (`FrameUniforms::ray_*_texture`), so a
//! point p lies on the ray of (x, y) at parameter t where `[base dx dy]·(t, t·x, t·y) = p − eye`.

use glam::{DMat3, DVec2, DVec3};

use super::FrameUniforms;

/// The most vertices of the polygon a footprint draw takes (`FOOTPRINT_FAN_VERTICES` in
/// `shaders/common/footprint.wgsl`); one with more draws the whole viewport.
pub const FAN_VERTICES: usize = 12;

/// The vertices a footprint draw takes: a fan of `FAN_VERTICES - 2` triangles.
pub const FAN_DRAW_VERTICES: u32 = 3 * (FAN_VERTICES as u32 - 2);

/// What a footprint draw covers.
#[derive(Clone, Debug, PartialEq)]
pub enum Coverage {
    /// No pixel: no ray meets the box.
    Nothing,
    /// The convex polygon of these vertices (pixels, in order around it).
    Polygon(Vec<DVec2>),
    /// The whole viewport (a footprint not computed, or of more than [`FAN_VERTICES`] vertices).
    Whole,
}

/// A frame's footprint.
#[derive(Clone, Debug, PartialEq)]
pub enum Footprint {
    /// The points (x, y) with `a·x + b·y + c >= 0` for every edge `[a, b, c]` (unit `(a, b)`:
    /// the value is the distance to the edge in pixels).
    Polygon(Vec<[f64; 3]>),
    /// No ray meets a body of volume.
    Nothing,
    /// A camera whose near plane is not in front of the eye: not computed.
    Unknown,
}

impl Footprint {
    /// The polygon grown by `grow` pixels (every edge moved out by it), for a footprint draw:
    /// every pixel centre inside the footprint lies inside it by `grow`, so the rasterizer covers
    /// it whatever its rounding.
    pub fn coverage(&self, grow: f64) -> Coverage {
        let edges = match self {
            Footprint::Polygon(edges) => edges,
            Footprint::Nothing => return Coverage::Nothing,
            Footprint::Unknown => return Coverage::Whole,
        };
        let mut vertices = Vec::with_capacity(edges.len());
        for (i, &[a0, b0, c0]) in edges.iter().enumerate() {
            let [a1, b1, c1] = edges[(i + 1) % edges.len()];
            // The corner the two grown edges meet at: a·x + b·y + c + grow = 0 for both.
            let det = a0 * b1 - a1 * b0;
            if det.abs() < 1e-12 {
                continue;
            }
            let (r0, r1) = (-(c0 + grow), -(c1 + grow));
            vertices.push(DVec2::new((r0 * b1 - r1 * b0) / det, (a0 * r1 - a1 * r0) / det));
        }
        // Far corners (an eye at the box) would lose f32 precision; they lie off screen anyway.
        let far = |v: &DVec2| !v.is_finite() || v.abs().max_element() >= 1.0e6;
        if vertices.len() > FAN_VERTICES || vertices.iter().any(far) {
            return Coverage::Whole;
        }
        Coverage::Polygon(vertices)
    }

    /// For each of `rows` image rows, the x range `[x0, x1]` of its pixel centres' line
    /// (y = row + 0.5) lying at least `margin` pixels inside the polygon; `x0 > x1` where none
    /// does (every row of [`Footprint::Nothing`] and [`Footprint::Unknown`]).
    pub fn row_spans(&self, rows: u32, margin: f64) -> Vec<[f32; 2]> {
        const NONE: [f32; 2] = [1.0, 0.0];
        let Footprint::Polygon(edges) = self else { return vec![NONE; rows as usize] };
        (0..rows)
            .map(|row| {
                let y = row as f64 + 0.5;
                let (mut x0, mut x1) = (f64::NEG_INFINITY, f64::INFINITY);
                for &[a, b, c] in edges {
                    // a·x >= margin − c − b·y
                    let bound = margin - c - b * y;
                    if a > 0.0 {
                        x0 = x0.max(bound / a);
                    } else if a < 0.0 {
                        x1 = x1.min(bound / a);
                    } else if bound > 0.0 {
                        return NONE;
                    }
                }
                // f32 keeps ±inf; a span wider than any viewport is clamped for the GPU.
                if x0 <= x1 { [x0.max(-1.0e30) as f32, x1.min(1.0e30) as f32] } else { NONE }
            })
            .collect()
    }
}

/// The half-space `n·p >= d` in texture space.
#[derive(Clone, Copy, Debug)]
struct HalfSpace {
    n: DVec3,
    d: f64,
}

fn v3(v: [f32; 4]) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
}

/// The faces of the box `[lo, hi]`.
fn box_faces(lo: DVec3, hi: DVec3) -> impl Iterator<Item = HalfSpace> {
    (0..3).flat_map(move |a| {
        let e = DVec3::AXES[a];
        [HalfSpace { n: e, d: lo[a] }, HalfSpace { n: -e, d: -hi[a] }]
    })
}

/// The footprint of the frame whose uniform block is `u` (its rays, boxes and cuts; the
/// footprint fields are not read).
pub fn footprint(u: &FrameUniforms) -> Footprint {
    let near = u.camera_forward[3] as f64;
    let eye = v3(u.eye_texture);
    let rays = DMat3::from_cols(v3(u.ray_base_texture), v3(u.ray_dx_texture), v3(u.ray_dy_texture));
    if near.is_nan() || near <= 0.0 || rays.determinant().abs() < 1e-300 {
        return Footprint::Unknown;
    }
    // Row 0 of the inverse gives a point's ray parameter t.
    let to_ray = rays.inverse();
    let t_of = to_ray.row(0);
    let window = u.grid_lo[3] == 1.0;
    let (grid_lo, grid_hi) = if window { (v3(u.grid_lo), v3(u.grid_hi)) } else { (DVec3::ZERO, DVec3::ONE) };
    let mut planes: Vec<HalfSpace> = box_faces(grid_lo, grid_hi).collect();
    if window {
        planes.extend(box_faces(v3(u.own_lo), v3(u.own_hi)));
    }
    // The crop box is the grid box unless the scene crops (FrameUniforms::with_cuts).
    planes.extend(box_faces(v3(u.crop_lo), v3(u.crop_hi)));
    planes.extend(u.clip_planes.iter().filter(|p| p[..3] != [0.0; 3]).map(|p| HalfSpace { n: v3(*p), d: p[3] as f64 }));
    planes.push(HalfSpace { n: t_of, d: near + t_of.dot(eye) });

    let image_point = |p: DVec3| {
        let q = to_ray * (p - eye);
        DVec2::new(q.y / q.x, q.z / q.x)
    };
    let corners: Vec<DVec2> = vertices(&planes).into_iter().map(image_point).collect();
    let hull = convex_hull(corners);
    if hull.len() < 3 {
        // A point, a segment or nothing: no ray crosses a body of volume.
        return Footprint::Nothing;
    }
    let centroid = hull.iter().copied().sum::<DVec2>() / hull.len() as f64;
    let mut edges = Vec::with_capacity(hull.len());
    for (i, a) in hull.iter().enumerate() {
        let b = hull[(i + 1) % hull.len()];
        let along = b - *a;
        let length = along.length();
        if length < 1e-12 {
            continue;
        }
        let mut n = DVec2::new(-along.y, along.x) / length;
        if n.dot(centroid - *a) < 0.0 {
            n = -n;
        }
        edges.push([n.x, n.y, -n.dot(*a)]);
    }
    Footprint::Polygon(edges)
}

/// The corners of the convex body the half-spaces bound: every point three of their planes meet
/// in that all of them keep (to rounding). At most 25 planes: 2,300 triples, a few microseconds.
fn vertices(planes: &[HalfSpace]) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let (a, b, c) = (planes[i], planes[j], planes[k]);
                let m = DMat3::from_cols(a.n, b.n, c.n).transpose();
                let det = m.determinant();
                if det.abs() < 1e-12 {
                    continue;
                }
                let p = m.inverse() * DVec3::new(a.d, b.d, c.d);
                let kept = planes.iter().all(|h| h.n.dot(p) >= h.d - 1e-9 * (1.0 + h.d.abs()));
                if kept && p.is_finite() {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's monotone
/// chain).
fn convex_hull(mut points: Vec<DVec2>) -> Vec<DVec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup_by(|a, b| (*a - *b).length() < 1e-9);
    if points.len() < 3 {
        return points;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &DVec2>> =
            if pass == 0 { Box::new(points.iter()) } else { Box::new(points.iter().rev()) };
        for &p in ordered {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 1e-12 {
                hull.pop();
            }
            hull.push(p);
        }
        // The last point of each chain is the first of the other.
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::UVec3;
    use volgraph_accel::camera::OrbitCamera;

    use crate::runtime::{CameraData, FrameData, VolumeDesc};

    fn frame(orbit: OrbitCamera, viewport: (u32, u32)) -> FrameData {
        let data = volgraph_accel::volume::VoxelData::U8(vec![0; 40 * 30 * 20]);
        let volume = volgraph_accel::volume::Volume::new("v", UVec3::new(40, 30, 20), DVec3::ONE, data);
        FrameData {
            viewport,
            camera: CameraData::from_orbit(&orbit, viewport),
            previous_camera: None,
            frame_index: 0,
            history_age: 0,
            volume: Some(VolumeDesc::of(&volume)),
            gpu_memory_budget: None,
            cuts: Default::default(),
            lights: Default::default(),
            environment: false,
        }
    }

    /// Whether the ray of image point (x, y) meets the box past the near plane, as
    /// `analytic_ray` decides it (slab test), in f64.
    fn ray_meets_box(u: &FrameUniforms, x: f64, y: f64) -> bool {
        let dir = v3(u.ray_base_texture) + x * v3(u.ray_dx_texture) + y * v3(u.ray_dy_texture);
        let eye = v3(u.eye_texture);
        let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if !(0.0..=1.0).contains(&eye[a]) {
                    return false;
                }
                continue;
            }
            let (ta, tb) = (-eye[a] / dir[a], (1.0 - eye[a]) / dir[a]);
            t_in = t_in.max(ta.min(tb));
            t_out = t_out.min(ta.max(tb));
        }
        t_in.max(u.camera_forward[3] as f64) < t_out
    }

    /// A pixel centre lies in its row's span only when its ray meets the box (the spans are
    /// conservative), and every pixel centre whose ray meets the box, but for those within a
    /// few hundredths of a pixel of the polygon's edge, lies in it — seen from outside, from close
    /// by (the near plane cuts the box) and from inside the box.
    #[test]
    fn the_row_spans_hold_the_pixels_whose_rays_meet_the_box() {
        let viewport = (96, 64);
        for (azimuth, elevation, distance) in
            [(30.0, 20.0, 3.2), (200.0, -60.0, 1.2), (10.0, 5.0, 0.9), (75.0, 40.0, 0.2)]
        {
            let orbit = OrbitCamera { azimuth_deg: azimuth, elevation_deg: elevation, distance, ..Default::default() };
            let u = FrameUniforms::of(&frame(orbit, viewport));
            let polygon = footprint(&u);
            let Footprint::Polygon(edges) = &polygon else { panic!("{orbit:?}: the box is in view") };
            let spans = polygon.row_spans(viewport.1, 0.01);
            let (mut inside, mut near_edge) = (0, 0);
            for y in 0..viewport.1 {
                for x in 0..viewport.0 {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let [x0, x1] = spans[y as usize];
                    let in_span = x0 as f64 <= px && px <= x1 as f64;
                    let meets = ray_meets_box(&u, px, py);
                    assert!(!in_span || meets, "{orbit:?}, pixel ({x}, {y}): in its span, but its ray misses");
                    let distance = edges.iter().map(|e| e[0] * px + e[1] * py + e[2]).fold(f64::INFINITY, f64::min);
                    if distance > 0.03 {
                        assert!(in_span, "{orbit:?}, pixel ({x}, {y}): {distance} px inside, not in its span");
                    }
                    inside += in_span as usize;
                    near_edge += (meets && !in_span) as usize;
                }
            }
            assert!(inside > 100 && near_edge < 4, "{orbit:?}: {inside} in the spans, {near_edge} more meet the box");
        }
    }

    /// Behind the eye the box has no footprint; a crop box shrinks it.
    #[test]
    fn a_box_behind_the_eye_has_none_and_a_crop_box_shrinks_it() {
        let viewport = (64, 64);
        let orbit = OrbitCamera { distance: 3.2, ..Default::default() };
        let mut u = FrameUniforms::of(&frame(orbit, viewport));
        let area = |f: &Footprint| f.row_spans(64, 0.01).iter().map(|[x0, x1]| (x1 - x0).max(0.0)).sum::<f32>();
        let whole = area(&footprint(&u));
        u.crop_lo = [0.25, 0.25, 0.25, 0.0];
        u.crop_hi = [0.75, 0.75, 0.75, 0.0];
        let cropped = area(&footprint(&u));
        assert!(cropped > 0.0 && cropped < whole / 2.0, "{cropped} of {whole}");
        // Turn the rays around: the box lies behind the eye.
        for r in [&mut u.ray_base_texture, &mut u.ray_dx_texture, &mut u.ray_dy_texture] {
            for c in r.iter_mut().take(3) {
                *c = -*c;
            }
        }
        assert_eq!(footprint(&u), Footprint::Nothing);
        assert!(Footprint::Nothing.row_spans(3, 0.01).iter().all(|[x0, x1]| x0 > x1));
    }

    /// The grown polygon holds every pixel centre whose ray meets the box by a pixel's margin:
    /// each of its edges lies a pixel out from an edge of the footprint.
    #[test]
    fn the_grown_polygon_lies_a_pixel_outside_the_footprint() {
        let viewport = (96, 64);
        for (azimuth, elevation, distance) in [(30.0, 20.0, 3.2), (200.0, -60.0, 1.2), (10.0, 5.0, 0.9)] {
            let orbit = OrbitCamera { azimuth_deg: azimuth, elevation_deg: elevation, distance, ..Default::default() };
            let u = FrameUniforms::of(&frame(orbit, viewport));
            let polygon = footprint(&u);
            let Footprint::Polygon(edges) = &polygon else { panic!("{orbit:?}: in view") };
            let Coverage::Polygon(grown) = polygon.coverage(1.0) else { panic!("{orbit:?}: a polygon") };
            assert_eq!(grown.len(), edges.len(), "{orbit:?}");
            for v in &grown {
                // Each grown corner lies a pixel out from the two edges it moved, and outside none.
                let distances: Vec<f64> = edges.iter().map(|e| e[0] * v.x + e[1] * v.y + e[2]).collect();
                assert_eq!(
                    distances.iter().filter(|d| (**d + 1.0).abs() < 1e-9).count(),
                    2,
                    "{orbit:?}: {distances:?}"
                );
                assert!(distances.iter().all(|d| *d >= -1.0 - 1e-9), "{orbit:?}: {distances:?}");
            }
        }
        assert_eq!(Footprint::Nothing.coverage(1.0), Coverage::Nothing);
        assert_eq!(Footprint::Unknown.coverage(1.0), Coverage::Whole);
    }
}
