//! First-hit isosurface in the f64 reference renderer (`docs/rendering_model.md`, "First-hit
//! isosurface"; Krüger & Westermann 2003 §2.2).

use glam::{DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reference::{Phong, RaycastSettings, RenderMode, render_reference};
use volgraph_accel::volume::{Volume, VoxelData};

const N: u32 = 32;

/// A radial field on an N³ cube: value `-r` with r the texture-space distance of the voxel centre
/// from the box centre, so the normalized scalar is a decreasing linear function of r and the
/// iso value for radius `radius` is `(max - r) / (max - min)`.
fn radial_volume() -> (Volume, f64, f64) {
    let mut data = Vec::new();
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                let u = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / N as f64;
                data.push(-(u - 0.5).length() as f32);
            }
        }
    }
    let lo = data.iter().copied().fold(f32::INFINITY, f32::min) as f64;
    let hi = data.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    let volume = Volume {
        dims: UVec3::splat(N),
        spacing: DVec3::ONE,
        data: VoxelData::F32(data),
        name: "radial".into(),
        value_range: (lo, hi),
        meta: Default::default(),
    };
    (volume, lo, hi)
}

fn iso_for_radius(radius: f64, lo: f64, hi: f64) -> f64 {
    (-radius - lo) / (hi - lo)
}

const BASE: [f32; 4] = [0.5, 0.2, 0.0, 1.0];

#[test]
fn hits_lie_on_the_sphere() {
    let (volume, lo, hi) = radial_volume();
    let radius = 0.3;
    let settings = RaycastSettings {
        mode: RenderMode::Isosurface { iso: iso_for_radius(radius, lo, hi), shading: Phong::default() },
        ..Default::default()
    };
    for (az, el) in [(0.0, 0.0), (37.0, 23.0), (-120.0, -60.0)] {
        let camera = OrbitCamera { azimuth_deg: az, elevation_deg: el, distance: 2.2, ..Default::default() };
        let (w, h) = (40, 40);
        let image = render_reference(&volume, &[BASE; 4], &camera, w, h, &settings);
        let frame = camera.frame(w, h);
        let (mut hits, mut worst) = (0, 0.0f64);
        for y in 0..h {
            for x in 0..w {
                let i = image.index(x, y);
                let (c, hit) = (image.color[i], image.hit[i]);
                // Distance of this pixel's ray from the centre (world = texture - 0.5 here: cube).
                let (eye, d) = frame.pixel_ray(x, y);
                let miss_distance = (eye - eye.dot(d) * d).length();
                if hit[3] == 0.0 {
                    assert_eq!(c, [0.0; 4], "a miss is transparent");
                    // Rays passing well inside the sphere must hit; 1.5 voxels of margin covers
                    // the trilinear error of the radial field and a grazing ray whose chord is
                    // shorter than one step.
                    assert!(
                        miss_distance > radius - 1.5 / N as f64,
                        "az {az} el {el} ({x},{y}) missed at {miss_distance}"
                    );
                    continue;
                }
                hits += 1;
                assert_eq!(hit[3], 1.0);
                assert_eq!(c[3], 1.0, "isosurface pixels are opaque");
                let r = (DVec3::new(hit[0], hit[1], hit[2]) - 0.5).length();
                worst = worst.max((r - radius).abs());
                assert!(miss_distance < radius + 1.0 / N as f64, "a ray passing outside the sphere cannot hit");
            }
        }
        // The secant refinement is exact for a field linear between samples; the error left is
        // the trilinear interpolation of the curved cone r: at most h²/8·|r''|·3 axes with
        // h = 1/32, r'' <= 1/r ≈ 3.3 → 1.2e-3, plus the cubic variation of trilinear along a
        // 1/64 step (smaller). 2e-3 (≈ 0.06 voxel) bounds both.
        assert!(worst < 2e-3, "az {az} el {el}: worst radial error {worst}");
        // The sphere of radius 0.3 covers π·0.3²/(2·2.2·tan 15°)² ≈ 20 % of the image.
        assert!(hits > 200, "az {az} el {el}: only {hits} hits");
    }
}

#[test]
fn centre_pixel_hits_the_pole_facing_the_eye() {
    let (volume, lo, hi) = radial_volume();
    let shading = Phong::default();
    let settings = RaycastSettings {
        mode: RenderMode::Isosurface { iso: iso_for_radius(0.25, lo, hi), shading },
        ..Default::default()
    };
    let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, ..Default::default() };
    let image = render_reference(&volume, &[BASE; 2], &camera, 1, 1, &settings);
    let hit = image.hit[0];
    // The ray runs down -z through the centre: it meets r = 0.25 at u = (0.5, 0.5, 0.75).
    // 1e-3: the trilinear error bound of `hits_lie_on_the_sphere` at r = 0.25.
    assert!((hit[0] - 0.5).abs() < 1e-9 && (hit[1] - 0.5).abs() < 1e-9, "hit {hit:?}");
    assert!((hit[2] - 0.75).abs() < 1e-3, "hit {hit:?}");
    // The normal is the sphere's, along +z, toward the eye: |n·l| = 1, so
    // rgb = base·(0.15 + 0.75) + 0.25 = (0.7, 0.43, 0.25), all below the clamp.
    // 1e-9: the symmetric gradient cancels in x and y up to f64 rounding.
    let want = [0.5 * 0.9 + 0.25, 0.2f32 as f64 * 0.9 + 0.25, 0.25, 1.0];
    for c in 0..4 {
        assert!((image.color[0][c] - want[c]).abs() < 1e-9, "colour {:?} want {want:?}", image.color[0]);
    }
    // Samples stop at the hit: from u_z = 1 with step 1/64, the first t_k = (k + 0.5)/64 past
    // the surface at t = 0.25 is k = 16, so samples k = 0..=16 are taken.
    assert_eq!(image.samples, 17);
}

#[test]
fn a_constant_field_above_iso_hits_at_the_first_sample_with_a_headlight_normal() {
    // 1×1×1 volume: every gradient is exactly zero, so n faces the eye and |n·l| = 1.
    let volume = Volume {
        dims: UVec3::ONE,
        spacing: DVec3::ONE,
        data: VoxelData::U8(vec![200]),
        name: "one".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    };
    let settings = RaycastSettings {
        mode: RenderMode::Isosurface { iso: 0.5, shading: Phong { specular: 0.0, ..Default::default() } },
        ..Default::default()
    };
    let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, ..Default::default() };
    let image = render_reference(&volume, &[[1.0, 1.0, 1.0, 1.0]], &camera, 1, 1, &settings);
    // k = 0 hit: t = t_0 = 0.5·step_tex; 1 voxel → unit_world = 1, step_tex = 0.5, entry at
    // u_z = 1, so the hit is at u_z = 0.75.
    assert_eq!(image.samples, 1);
    assert!((image.hit[0][2] - 0.75).abs() < 1e-12, "hit {:?}", image.hit[0]);
    // base·(ambient + diffuse) = 0.9; 1e-12 for the f64 rounding of the ray direction.
    assert!((image.color[0][0] - 0.9).abs() < 1e-12, "colour {:?}", image.color[0]);
}

#[test]
fn settings_deserialize_with_defaults_and_reject_unknown_fields() {
    let s: RaycastSettings = ron::from_str("(mode: Isosurface(iso: 0.4))").expect("valid settings");
    assert_eq!(s.step_voxels, 0.5);
    assert_eq!(
        s.mode,
        RenderMode::Isosurface {
            iso: 0.4,
            shading: Phong { ambient: 0.15, diffuse: 0.75, specular: 0.25, shininess: 32.0 }
        }
    );
    let err = ron::from_str::<RaycastSettings>("(step: 0.5)").expect_err("`step` is not a field");
    assert!(err.to_string().contains("step"), "{err}");
    let err = ron::from_str::<RaycastSettings>("(mode: Isosurface(iso: 0.4, shade: ()))")
        .expect_err("`shade` is not a field");
    assert!(err.to_string().contains("shade"), "{err}");
    // The lights are a list of one to three, checked as a scene's.
    let lit: RaycastSettings =
        ron::from_str("(lights: [Headlight, Directional(azimuth_deg: 10, elevation_deg: 20)])").expect("two lights");
    assert_eq!(lit.lights.as_slice().len(), 2);
    assert_eq!(ron::from_str::<RaycastSettings>(&ron::to_string(&lit).expect("writes")).expect("reads"), lit);
    let err = ron::from_str::<RaycastSettings>("(lights: [])").expect_err("no light");
    assert!(err.to_string().contains("0 lights"), "{err}");
}

#[test]
fn normals_are_world_space_on_anisotropic_volumes() {
    // Regression for the gradient scaling (docs/rendering_model.md: n = -normalize(g·dims/half)).
    // A linear field f(p) = a·p in world space on a non-cubic volume with anisotropic spacing:
    // trilinear interpolation and central differences are exact for it away from the clamped
    // border, so the shading normal must be -a, and with ambient 0, diffuse 1, specular 0 and a
    // white LUT the colour is |a·d|.
    let dims = UVec3::new(24, 16, 12);
    let spacing = DVec3::new(1.0, 1.5, 3.0);
    let mut volume = Volume {
        dims,
        spacing,
        data: VoxelData::F32(vec![]),
        name: "plane".into(),
        value_range: (0.0, 1.0),
        meta: Default::default(),
    };
    let half = volume.half_extent_world();
    let a = DVec3::new(1.0, 2.0, 3.0).normalize();
    let mut data = Vec::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let u = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / dims.as_dvec3();
                data.push(a.dot((u - 0.5) * 2.0 * half) as f32);
            }
        }
    }
    let lo = data.iter().copied().fold(f32::INFINITY, f32::min) as f64;
    let hi = data.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
    volume.data = VoxelData::F32(data);
    volume.value_range = (lo, hi);
    let shading = Phong { ambient: 0.0, diffuse: 1.0, specular: 0.0, shininess: 1.0 };
    let settings =
        RaycastSettings { mode: RenderMode::Isosurface { iso: (0.0 - lo) / (hi - lo), shading }, ..Default::default() };
    // Looking from the low side of f, so rays cross the plane inside rather than starting above it.
    let camera = OrbitCamera { azimuth_deg: 205.0, elevation_deg: -30.0, ..Default::default() };
    let (w, h) = (32, 32);
    let image = render_reference(&volume, &[[1.0; 4]], &camera, w, h, &settings);
    let frame = camera.frame(w, h);
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let hit = image.hit[image.index(x, y)];
            let u = DVec3::new(hit[0], hit[1], hit[2]);
            let margin = 1.5 / dims.as_dvec3(); // central differences reach one voxel out
            if hit[3] == 0.0 || (u - 0.5).abs().cmpgt(0.5 - margin).any() {
                continue;
            }
            let (_, d) = frame.pixel_ray(x, y);
            let want = a.dot(d).abs();
            // 1e-5: the field is stored as f32 (relative rounding ~6e-8 of values ~0.5 over
            // differences ~0.1 → ~1e-6 in the normal). The old texture-space formula,
            // -normalize(g / (2·half)) ∝ -a/dims, tilts the normal by ~10° here and moves |n·l|
            // by ~0.02 at the centre pixel, far outside this tolerance.
            let got = image.color[image.index(x, y)][0];
            assert!((got - want).abs() < 1e-5, "({x},{y}): |n·l| {got}, want {want}");
            checked += 1;
        }
    }
    assert!(checked > 50, "only {checked} interior hits");
}
