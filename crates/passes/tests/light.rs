//! The scene's light (issue "light that scatters", item 1; `volgraph_accel::light`): a
//! directional light fixed in the world shades every raycaster family as the f64 reference
//! shades with the same light — Blinn–Phong with `h` halfway between light and eye — and moves
//! the picture away from the headlight's.
//!
//! With the `shadows` effect (Behrens & Ratering 1998) every family reads the light volume —
//! the transmittance toward the light on a grid of up to 64³, `volgraph_accel::light::LightGrid`,
//! which the reference computes with the same function — and matches the reference within the
//! same bounds: the grid is uploaded as f16 (T within 2⁻¹¹) and filtered by the sampler, whose
//! weights carry 8 fractional bits on llvmpipe, so across a shadow's edge (T from 0 to 1 between
//! two grid voxels) T may differ by 1/256: about one 255th of colour.
//!
//! Tolerances: `support::assert_shaded_like_reference`, the bounds of shaded images (at most
//! 0.5 % of pixels over 2/255, mean under 0.5/255 per channel of premultiplied linear RGBA).

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::{ClipPlane, Cuts};
use volgraph_accel::image_diff::fraction_over;
use volgraph_accel::light::{Light, Lights};
use volgraph_accel::reference::{Effects, RaycastSettings, render_reference};
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Image, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

mod support;

use support::{assert_shaded_like_reference, gpu, graph_source};

const SIZE: u32 = 96;

/// `graph` rendered with the scene's light and cuts and `features`, and the reference settings
/// of its "march" pass with them (`support::render_in_scene`).
fn render_lit(
    gpu: &std::sync::Arc<volgraph_core::runtime::Gpu>,
    graph: &str,
    scene: (&Volume, &[[f32; 4]]),
    camera: &OrbitCamera,
    light_and_cuts: (Lights, Cuts),
    features: &[&str],
) -> (Image, RaycastSettings) {
    support::render_in_scene(gpu, (graph, SIZE), scene, camera, light_and_cuts, features)
}

/// Each (graph, features) rendered with `light` on ML 32³ (opaque) against the reference of the
/// same effects, and the reference without the effect `off` takes away: the effect must move
/// more than 5 % of pixels by more than `moved` (a test that passes without it proves nothing).
fn effect_like_reference(
    cases: &[(&str, &[&str])],
    light: impl Into<Lights>,
    (what, off): (&str, fn(Effects) -> Effects),
    moved: f64,
) {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(32);
    // Opaque material: what shows is the shaded surface the light falls on.
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    let light = light.into();
    for &(graph, features) in cases {
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, Cuts::NONE), features);
        assert_ne!(off(settings.effects), settings.effects, "{graph}: {what} reaches the reference settings");
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        let without = RaycastSettings { effects: off(settings.effects), ..settings };
        let without = render_reference(&volume, &lut, &camera, SIZE, SIZE, &without);
        let changed = fraction_over(&without.color, &reference.color, moved).expect("same size");
        let extra = format!("; {what} moved {:.0}% of pixels", changed * 100.0);
        assert_shaded_like_reference(&format!("{graph} {features:?}"), &image.to_rgba_f64(), &reference.color, &extra);
        assert!(changed > 0.05, "{graph}: {what} must change the image ({:.1}%)", changed * 100.0);
    }
}

/// Every family lit by `light` against the reference lit alike — a fragment raycaster, the
/// compute path, the brick atlas (whose samples map back to the volume by `volume_position`), a
/// first-hit isosurface and Klein's leaping march — on ML 64³ (opaque) — and the picture moved
/// by more than 8/255 on over `min_moved` of the pixels from the reference lit by `other` (a
/// test that passes with the other light proves nothing).
fn shades_every_family_like_the_reference(light: impl Into<Lights>, other: impl Into<Lights>, min_moved: f64) {
    let (light, other) = (light.into(), other.into());
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(64);
    // Opaque material: what shows is the shaded surface the light falls on.
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    for (graph, features) in [
        ("basic/fragment_raycast.ron", &["shading"][..]),
        ("modern/fastest.ron", &["shading"][..]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading"][..]),
        ("basic/isosurface.ron", &[][..]),
        ("klein_2005/leap_iso.ron", &[][..]),
    ] {
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, Cuts::NONE), features);
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        let by_other =
            render_reference(&volume, &lut, &camera, SIZE, SIZE, &RaycastSettings { lights: other, ..settings });
        let moved = fraction_over(&by_other.color, &reference.color, 8.0 / 255.0).expect("same size");
        let extra = format!("; {light:?} moved {:.0}% of pixels from {other:?}", moved * 100.0);
        assert_shaded_like_reference(graph, &image.to_rgba_f64(), &reference.color, &extra);
        assert!(moved > min_moved, "{graph}: the light must change the image ({:.1}%)", moved * 100.0);
    }
}

#[test]
fn a_directional_light_shades_every_family_like_the_reference() {
    let light = Light::Directional { azimuth_deg: -70.0, elevation_deg: 40.0 };
    shades_every_family_like_the_reference(light, Light::Headlight, 0.1);
}

/// A point light: its direction changes from sample to sample. Just outside the box's corner,
/// directions across the volume differ by up to ~90° from the distant light of the same side.
#[test]
fn a_point_light_shades_every_family_like_the_reference() {
    let light = Light::Point { x: 1.2, y: 1.0, z: 1.1 };
    shades_every_family_like_the_reference(light, Light::Directional { azimuth_deg: 47.5, elevation_deg: 35.0 }, 0.05);
}

/// Two lights, a key light from the upper left and a point light near the box's corner: every
/// family sums both lights' Blinn–Phong terms as the reference does, and the image is not the
/// key light's alone.
#[test]
fn two_lights_shade_every_family_like_the_reference() {
    let key = Light::Directional { azimuth_deg: -70.0, elevation_deg: 40.0 };
    let lights = Lights::new(&[key, Light::Point { x: 1.2, y: 1.0, z: 1.1 }]).expect("two lights");
    shades_every_family_like_the_reference(lights, key, 0.1);
}

/// Three lights, each with its own shadow (one channel of the light volume each): a
/// directional key light, a point light inside the box and the headlight — computed on the GPU
/// (fragment, compute; shaded and unshaded, where a sample takes the mean of what reaches it)
/// and on the CPU (the brick raycaster's grid) as in the reference.
#[test]
fn each_of_three_lights_casts_its_own_shadow_like_the_reference() {
    let cases: [(&str, &[&str]); 4] = [
        ("basic/fragment_raycast.ron", &["shading", "shadows"]),
        ("basic/fragment_raycast.ron", &["shadows"]),
        ("modern/fastest.ron", &["shading", "shadows", "ambient_occlusion"]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "shadows"]),
    ];
    let lights = Lights::new(&[
        Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 },
        Light::Point { x: 0.1, y: 0.35, z: 0.2 },
        Light::Headlight,
    ])
    .expect("three lights");
    effect_like_reference(&cases, lights, ("shadows", |e| Effects { shadows: false, ..e }), 8.0 / 255.0);
}

/// Shadows toward a point light: each light-volume voxel looks toward the light from where it
/// is, and material beyond the light casts no shadow — on the GPU (fragment, compute) and on
/// the CPU (the brick raycaster's grid) as in the reference.
#[test]
fn shadows_toward_a_point_light_are_the_references() {
    let cases: [(&str, &[&str]); 3] = [
        ("basic/fragment_raycast.ron", &["shading", "shadows"]),
        ("modern/fastest.ron", &["shadows"]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "shadows"]),
    ];
    // Inside the box, above its centre: material above the light casts no shadow on what is
    // below it.
    let light = Light::Point { x: 0.1, y: 0.35, z: 0.2 };
    effect_like_reference(&cases, light, ("shadows", |e| Effects { shadows: false, ..e }), 8.0 / 255.0);
}

/// The headlight is the default and draws what it always drew: a runtime whose light was set
/// and reset renders the same bytes as one never given a light.
#[test]
fn the_headlight_is_the_default_light() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(32);
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera::default();
    let (plain, _) =
        render_lit(&gpu, "basic/isosurface.ron", (&volume, &lut), &camera, (Lights::default(), Cuts::NONE), &[]);
    let registry = builtin_registry();
    let source = graph_source("basic/isosurface.ron");
    let mut options = CompileOptions::new(SIZE, SIZE);
    options.scene = scene_values_of(&VolumeDesc::of(&volume));
    let plan = compile("basic/isosurface.ron", &source, &registry, &options).expect("compiles");
    let mut runtime = support::runtime(&gpu);
    runtime.set_light(Light::Directional { azimuth_deg: 10.0, elevation_deg: 10.0 });
    runtime.set_light(Light::Headlight);
    runtime.bind_scene(&plan.inputs, &volume, &lut).expect("binds");
    runtime.apply(plan.clone(), &registry).expect("applies");
    runtime.render(CameraData::from_orbit(&camera, plan.viewport)).expect("renders");
    assert_eq!(runtime.read_output("image").expect("image").data, plain.data);
}

#[test]
fn shadows_darken_what_the_light_cannot_reach_like_the_reference() {
    let cases: [(&str, &[&str]); 5] = [
        ("basic/fragment_raycast.ron", &["shading", "shadows"]),
        ("basic/fragment_raycast.ron", &["shadows"]),
        ("modern/fastest.ron", &["shading", "shadows"]),
        ("kruger_westermann_2003/rc_b.ron", &["shading", "shadows"]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "shadows"]),
    ];
    let light = Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 };
    effect_like_reference(&cases, light, ("shadows", |e| Effects { shadows: false, ..e }), 8.0 / 255.0);
}

/// Ambient occlusion (Hernell et al. 2010, cones reduced to 14 rays of 8 voxels): every family
/// that computes the illumination volume on the GPU, and the brick raycaster on the CPU, darkens
/// the ambient light of occluded samples as the reference does, alone and with shadows.
#[test]
fn ambient_occlusion_darkens_the_ambient_light_like_the_reference() {
    let cases: [(&str, &[&str]); 4] = [
        ("basic/fragment_raycast.ron", &["shading", "ambient_occlusion"]),
        ("basic/fragment_raycast.ron", &["ambient_occlusion"]),
        ("modern/fastest.ron", &["shading", "shadows", "ambient_occlusion"]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "ambient_occlusion"]),
    ];
    let light = Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 };
    // The ambient term is 0.15 of the light: occlusion moves pixels by a few 255ths.
    let off = |e: Effects| Effects { ambient_occlusion: false, ..e };
    effect_like_reference(&cases, light, ("occlusion", off), 2.0 / 255.0);
}

/// Shadows with a cut (issue "light that scatters": effects compose with crop/clip): what the
/// clip plane cuts away casts no shadow on what it keeps, on the GPU as in the reference, and a
/// cut face is lit by the light.
#[test]
fn what_a_cut_removes_casts_no_shadow() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(32);
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    let light = Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 };
    let cuts =
        Cuts::new(None, &[ClipPlane::new(glam::DVec3::new(0.0, -1.0, 0.0), -0.55).expect("plane")]).expect("cuts");
    for graph in ["basic/fragment_raycast.ron", "modern/fastest.ron"] {
        let features = &["shading", "shadows", "ambient_occlusion"][..];
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light.into(), cuts), features);
        assert_eq!(settings.cuts, cuts);
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        assert_shaded_like_reference(&format!("{graph} cut"), &image.to_rgba_f64(), &reference.color, "");
    }
    // In the reference's own grid: a point under the cut-away top, in the light's path through
    // it, is lit once the top is cut away.
    let frame = camera.frame(SIZE, SIZE);
    let settings = RaycastSettings {
        lights: light.into(),
        effects: volgraph_accel::reference::Effects { shadows: true, ..Default::default() },
        ..Default::default()
    };
    let whole = volgraph_accel::reference::shadow_grid(&volume, &lut, None, &frame, &settings).expect("a grid");
    let cut =
        volgraph_accel::reference::shadow_grid(&volume, &lut, None, &frame, &RaycastSettings { cuts, ..settings })
            .expect("a grid");
    let lit_more = whole.transmittance[0].iter().zip(&cut.transmittance[0]).filter(|(w, c)| **c > **w + 0.1).count();
    assert!(lit_more > 100, "{lit_more} grid voxels lit more once the top is cut away");
}
