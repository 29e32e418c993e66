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
use volgraph_accel::light::Light;
use volgraph_accel::reference::{RaycastSettings, render_reference};
use volgraph_accel::transfer_function::{Preset, TransferFunction};
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::{CameraData, Image, VolumeDesc, scene_values_of};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;
use volgraph_passes::raycast_params::reference_settings;

mod support;

use support::{assert_shaded_like_reference, gpu, graph_source};

const SIZE: u32 = 96;

/// `graph` rendered with the scene's `light` and `features`, and the reference settings of its
/// "march" pass with that light.
fn render_lit(
    gpu: &std::sync::Arc<volgraph_core::runtime::Gpu>,
    graph: &str,
    (volume, lut): (&Volume, &[[f32; 4]]),
    camera: &OrbitCamera,
    (light, cuts): (Light, Cuts),
    features: &[&str],
) -> (Image, RaycastSettings) {
    let registry = builtin_registry();
    let source = graph_source(graph);
    let mut all = volgraph_core::cut_effects::features_of(&cuts);
    all.extend(features.iter().map(|f| f.to_string()));
    let mut options = CompileOptions::new(SIZE, SIZE).with_features(all);
    options.scene = scene_values_of(&VolumeDesc::of(volume));
    let plan = compile(graph, &source, &registry, &options).unwrap_or_else(|d| panic!("{graph}: {d}"));
    // Krüger–Westermann's termination test stops between segments, the reference per sample:
    // compared lossless (T = 1), as tests/kruger_westermann.rs compares them.
    let plan = match plan.steps.iter().find(|s| s.pass_id == "terminate") {
        Some(_) => {
            options = options.with_param("terminate", "threshold", 1.0).with_param("march", "threshold", 1.0);
            compile(graph, &source, &registry, &options).unwrap_or_else(|d| panic!("{graph}: {d}"))
        }
        None => plan,
    };
    let march = plan.steps.iter().find(|s| s.pass_id == "march").expect("a march step");
    let settings = RaycastSettings { light, cuts, ..reference_settings(&march.params) };
    let mut runtime = support::runtime(gpu);
    runtime.set_light(light);
    runtime.set_cuts(cuts);
    runtime.bind_scene(&plan.inputs, volume, lut).expect("binds");
    runtime.apply(plan.clone(), &registry).unwrap_or_else(|e| panic!("{graph}: {e}"));
    runtime.render(CameraData::from_orbit(camera, plan.viewport)).unwrap_or_else(|e| panic!("{graph}: {e}"));
    (runtime.read_output("image").expect("image"), settings)
}

#[test]
fn a_directional_light_shades_every_family_like_the_reference() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(64);
    // Opaque material: what shows is the shaded surface the light falls on.
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    let light = Light::Directional { azimuth_deg: -70.0, elevation_deg: 40.0 };
    for (graph, features) in [
        ("basic/fragment_raycast.ron", &["shading"][..]),
        ("modern/fastest.ron", &["shading"][..]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading"][..]),
        ("basic/isosurface.ron", &[][..]),
        ("klein_2005/leap_iso.ron", &[][..]),
    ] {
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, Cuts::NONE), features);
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        let headlight = RaycastSettings { light: Light::Headlight, ..settings };
        let headlit = render_reference(&volume, &lut, &camera, SIZE, SIZE, &headlight);
        // The light moved the picture: a test that passes with the headlight proves nothing.
        let moved = fraction_over(&headlit.color, &reference.color, 8.0 / 255.0).expect("same size");
        let extra = format!("; the light moved {:.0}% of pixels", moved * 100.0);
        assert_shaded_like_reference(graph, &image.to_rgba_f64(), &reference.color, &extra);
        assert!(moved > 0.1, "{graph}: the light must change the image ({:.1}%)", moved * 100.0);
    }
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
        render_lit(&gpu, "basic/isosurface.ron", (&volume, &lut), &camera, (Light::default(), Cuts::NONE), &[]);
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
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(32);
    // Dense enough that the rings shadow one another, clear enough that the shadows show.
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    let light = Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 };
    for (graph, features) in [
        ("basic/fragment_raycast.ron", &["shading", "shadows"][..]),
        ("basic/fragment_raycast.ron", &["shadows"][..]),
        ("modern/fastest.ron", &["shading", "shadows"][..]),
        ("kruger_westermann_2003/rc_b.ron", &["shading", "shadows"][..]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "shadows"][..]),
    ] {
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, Cuts::NONE), features);
        assert!(settings.effects.shadows, "{graph}: shadows reach the reference settings");
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        let unshadowed = RaycastSettings {
            effects: volgraph_accel::reference::Effects { shadows: false, ..settings.effects },
            ..settings
        };
        let lit = render_reference(&volume, &lut, &camera, SIZE, SIZE, &unshadowed);
        let shadowed = fraction_over(&lit.color, &reference.color, 8.0 / 255.0).expect("same size");
        let extra = format!("; shadows moved {:.0}% of pixels", shadowed * 100.0);
        assert_shaded_like_reference(&format!("{graph} {features:?}"), &image.to_rgba_f64(), &reference.color, &extra);
        assert!(shadowed > 0.05, "{graph}: the shadows must change the image ({:.1}%)", shadowed * 100.0);
    }
}

/// Ambient occlusion (Hernell et al. 2010, cones reduced to 14 rays of 8 voxels): every family
/// that computes the illumination volume on the GPU, and the brick raycaster on the CPU, darkens
/// the ambient light of occluded samples as the reference does, alone and with shadows.
#[test]
fn ambient_occlusion_darkens_the_ambient_light_like_the_reference() {
    let gpu = gpu();
    let volume = volgraph_accel::generate::marschner_lobb_f32(32);
    let lut = TransferFunction::preset(Preset::Opaque, volume.value_range).to_lut_for(&volume, 256);
    let camera = OrbitCamera { azimuth_deg: 25.0, elevation_deg: 15.0, ..OrbitCamera::default() };
    let light = Light::Directional { azimuth_deg: -80.0, elevation_deg: 50.0 };
    for (graph, features) in [
        ("basic/fragment_raycast.ron", &["shading", "ambient_occlusion"][..]),
        ("basic/fragment_raycast.ron", &["ambient_occlusion"][..]),
        ("modern/fastest.ron", &["shading", "shadows", "ambient_occlusion"][..]),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", &["shading", "ambient_occlusion"][..]),
    ] {
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, Cuts::NONE), features);
        assert!(settings.effects.ambient_occlusion, "{graph}: the effect reaches the reference settings");
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        let open = RaycastSettings {
            effects: volgraph_accel::reference::Effects { ambient_occlusion: false, ..settings.effects },
            ..settings
        };
        let unoccluded = render_reference(&volume, &lut, &camera, SIZE, SIZE, &open);
        let occluded = fraction_over(&unoccluded.color, &reference.color, 2.0 / 255.0).expect("same size");
        let extra = format!("; occlusion moved {:.0}% of pixels over 2/255", occluded * 100.0);
        assert_shaded_like_reference(&format!("{graph} {features:?}"), &image.to_rgba_f64(), &reference.color, &extra);
        assert!(occluded > 0.05, "{graph}: the occlusion must change the image ({:.1}%)", occluded * 100.0);
    }
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
        let (image, settings) = render_lit(&gpu, graph, (&volume, &lut), &camera, (light, cuts), features);
        assert_eq!(settings.cuts, cuts);
        let reference = render_reference(&volume, &lut, &camera, SIZE, SIZE, &settings);
        assert_shaded_like_reference(&format!("{graph} cut"), &image.to_rgba_f64(), &reference.color, "");
    }
    // In the reference's own grid: a point under the cut-away top, in the light's path through
    // it, is lit once the top is cut away.
    let frame = camera.frame(SIZE, SIZE);
    let settings = RaycastSettings {
        light,
        effects: volgraph_accel::reference::Effects { shadows: true, ..Default::default() },
        ..Default::default()
    };
    let whole = volgraph_accel::reference::shadow_grid(&volume, &lut, &frame, &settings).expect("a grid");
    let cut = volgraph_accel::reference::shadow_grid(&volume, &lut, &frame, &RaycastSettings { cuts, ..settings })
        .expect("a grid");
    let lit_more = whole.transmittance.iter().zip(&cut.transmittance).filter(|(w, c)| **c > **w + 0.1).count();
    assert!(lit_more > 100, "{lit_more} grid voxels lit more once the top is cut away");
}
