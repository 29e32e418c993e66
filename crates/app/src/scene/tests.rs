//! Scene files parsed and checked: paths, camera paths and bounds, names, volume options.

use super::*;

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_str(text, Path::new("scenes/test.ron"))
}

#[test]
fn a_full_scene_resolves_paths_against_its_folder() {
    let s = parse(
        r#"Scene(graph: "../graphs/modern/fastest.ron", volume: File("v.raw"),
            transfer_function: File("tf.ron"), camera: Orbit(azimuth: 10, elevation: 5, distance: 2.5),
            viewport: (64, 32), effects: ["shading", "jitter"], precision: F32, opacity_reference: World)"#,
    )
    .expect("parses");
    assert_eq!(s.graph, Some(PathBuf::from("scenes/../graphs/modern/fastest.ron")));
    assert_eq!(s.volume, VolumeSource::File("scenes/v.raw".into()));
    assert_eq!(s.transfer_function, Some(TfSource::File("scenes/tf.ron".into())));
    assert_eq!(
        (s.viewport, s.precision, s.opacity_reference),
        (Some((64, 32)), Some(Precision::F32), OpacityReference::World)
    );
    assert_eq!(s.frame_count(), 1);
}

#[test]
fn a_camera_path_interpolates_and_sets_the_frame_count() {
    let s = parse(
        r#"Scene(volume: Generated("ml32"), camera: Path(keyframes: [
            (frame: 0, azimuth: 0, elevation: 0, distance: 3),
            (frame: 10, azimuth: 90, elevation: 20, distance: 2)]))"#,
    )
    .expect("parses");
    assert_eq!(s.frame_count(), 11);
    let cam = s.camera.as_ref().expect("a camera");
    let mid = cam.at(5);
    assert!((mid.azimuth_deg - 45.0).abs() < 1e-12 && (mid.distance - 2.5).abs() < 1e-12);
    assert_eq!(cam.at(20).azimuth_deg, 90.0);
}

#[test]
fn mistakes_name_the_line_or_field_and_the_fix() {
    let err = parse("Scene(volume: Generated(\"ml32\"), effects: [\"shadng\"])").expect_err("bad effect").to_string();
    assert!(err.contains("effects: \"shadng\" is not an effect") && err.contains("shading"), "{err}");
    let err = parse("Scene(\n  volume: Generated(\"ml32\"),\n  colour: 3)").expect_err("unknown field").to_string();
    assert!(err.starts_with("scenes/test.ron:3:"), "{err}");
    let err = parse("Scene(volume: Generated(\"ml32\"), viewport: (0, 5))").expect_err("bad size").to_string();
    assert!(err.contains("viewport: (0, 5)"), "{err}");
    let err = parse("Scene(volume: Generated(\"ml32\"), camera: Path(keyframes: []))").expect_err("empty").to_string();
    assert!(err.contains("camera: a Path needs at least one keyframe"), "{err}");
}

/// Issue 19: a keyframe at frame 10⁹ rendered 10⁹ frames, one at 2³²−1 wrapped to 0 frames
/// (a black PNG); elevations beyond ±90° and distances like 1e-300 were accepted.
#[test]
fn camera_paths_and_orbits_are_bounded_like_the_cli() {
    let path = |frame: u64| {
        format!(
            "Scene(volume: Generated(\"ml32\"), camera: Path(keyframes: [(frame: 0, azimuth: 0, elevation: 0, \
             distance: 3), (frame: {frame}, azimuth: 9, elevation: 0, distance: 3)]))"
        )
    };
    for frame in [1_000_000_000u64, u64::from(u32::MAX)] {
        let err = parse(&path(frame)).expect_err("too long").to_string();
        assert!(err.contains(&format!("keyframe 1: frame {frame} is beyond the last frame")), "{err}");
    }
    assert_eq!(parse(&path(u64::from(MAX_FRAMES - 1))).expect("the longest path").frame_count(), MAX_FRAMES);
    for (camera, expected) in [
        ("Orbit(azimuth: 0, elevation: 91, distance: 3)", "elevation 91 must be within -90..=90"),
        ("Orbit(azimuth: 0, elevation: -200, distance: 3)", "elevation -200 must be within"),
        ("Orbit(azimuth: 0, elevation: 0, distance: 1e-300)", "distance 1e-300 must be within"),
    ] {
        let err =
            parse(&format!("Scene(volume: Generated(\"ml32\"), camera: {camera})")).expect_err(camera).to_string();
        assert!(err.contains(expected), "{camera}: {err}");
    }
}

/// Issue 19: `Data("…")` climbed out of `$VOLGRAPH_DATA/tf`.
#[test]
fn a_data_transfer_function_stays_in_the_data_folder() {
    for name in ["../../../etc/passwd", "/etc/passwd", "..", "a/b", ""] {
        let text = format!("Scene(volume: Generated(\"ml32\"), transfer_function: Data(\"{name}\"))");
        let err = parse(&text).expect_err(name).to_string();
        assert!(err.contains("transfer_function: Data(") && err.contains("without folders"), "{name}: {err}");
    }
    parse("Scene(volume: Generated(\"ml32\"), transfer_function: Data(\"engine_opaque\"))").expect("a stem");
}

/// Issue 47 §5: a built-in graph or a TF preset named in a scene resolved only in the scene's
/// folder. A relative name is the file beside the scene where there is one, else the built-in.
#[test]
fn names_resolve_beside_the_scene_first_else_as_built_ins() {
    let dir = std::env::temp_dir().join(format!("volgraph-scene-names-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    let text = "Scene(graph: \"basic/fragment_raycast\", volume: Generated(\"ml32\"), transfer_function: \
                File(\"ct-bone\"))";
    let s = Scene::from_str(text, &dir.join("s.ron")).expect("parses");
    assert_eq!(s.graph, Some(PathBuf::from("basic/fragment_raycast")));
    assert_eq!(s.transfer_function, Some(TfSource::Preset("ct-bone".into())));
    // A file of that name beside the scene wins.
    std::fs::write(dir.join("ct-bone"), "").expect("file");
    let s = Scene::from_str(text, &dir.join("s.ron")).expect("parses");
    assert_eq!(s.transfer_function, Some(TfSource::File(dir.join("ct-bone").display().to_string())));
    let _ = std::fs::remove_dir_all(&dir);
    // Preset() takes the scanner presets; a wrong name is refused with the list.
    parse("Scene(volume: Generated(\"ml32\"), transfer_function: Preset(\"mr-default\"))").expect("a preset");
    let err = parse("Scene(volume: Generated(\"ml32\"), transfer_function: Preset(\"ct-bones\"))")
        .expect_err("no such preset")
        .to_string();
    assert!(
        err.contains("transfer_function: Preset(\"ct-bones\") is not a preset") && err.contains("ct-bone,"),
        "{err}"
    );
}

/// Issue 47 §5: `view --volume ml32` and its saved `Generated("ml32")` got two default TFs;
/// one rule now, and only where the TF's 0..255 points fit (not the float `mlf` volumes).
#[test]
fn the_marschner_lobb_tf_is_the_default_of_the_8_bit_ml_volumes_only() {
    let generated = |n: &str| VolumeSource::Generated(n.to_string());
    assert!(marschner_lobb_tf(&generated("ml32")) && marschner_lobb_tf(&generated("ml64")));
    for other in [generated("mlf64"), generated("sphere32"), VolumeSource::Dataset("ml32".into())] {
        assert!(!marschner_lobb_tf(&other), "{other:?}");
    }
}

/// Issue 47 §5: `volume_options` are checked as the flags they stand for.
#[test]
fn volume_options_are_checked_like_the_flags() {
    let s =
        parse("Scene(volume: File(\"v.raw\"), volume_options: (dims: (4, 4, 2), dtype: \"uint16\", series: \"2\"))")
            .expect("parses");
    let o = s.volume_options.load_options().expect("valid");
    assert_eq!((o.raw.dims, o.series.as_deref()), (Some(glam::UVec3::new(4, 4, 2)), Some("2")));
    for (options, expected) in [
        ("(dims: (0, 4, 4))", "volume_options: --dims \"0x4x4\""),
        ("(dtype: \"int64\")", "--dtype \"int64\""),
        ("(spacing: (1, 1, 1e9))", "times the shortest"),
        ("(colour: 1)", "scenes/test.ron:1:"),
    ] {
        let err = parse(&format!("Scene(volume: File(\"v.raw\"), volume_options: {options})"))
            .expect_err(options)
            .to_string();
        assert!(err.contains(expected), "{options}: {err}");
    }
}

/// `lights:` (issue "light that scatters", item 1): up to three lights, each checked like
/// `--light`; none is the headlight; four, or an elevation past 90°, name the field and the fix.
#[test]
fn a_scene_has_up_to_three_lights_checked_like_the_flag() {
    use volgraph_accel::light::Light;
    let s = parse("Scene(volume: Generated(\"ml32\"))").expect("parses");
    assert_eq!(s.lights.as_slice(), &[Light::Headlight]);
    let s = parse("Scene(volume: Generated(\"ml32\"), lights: [Directional(azimuth_deg: 30, elevation_deg: 45)])")
        .expect("parses");
    assert_eq!(s.lights.as_slice(), &[Light::Directional { azimuth_deg: 30.0, elevation_deg: 45.0 }]);
    // The issue's spelling of an environment map: an Environment(…) entry beside the light.
    let lit = parse(
        "Scene(volume: Generated(\"ml32\"), lights: [Directional(azimuth_deg: 30, elevation_deg: 45), \
         Environment(File(\"sky.exr\"))])",
    )
    .expect("a light and an environment");
    assert_eq!(lit.lights.as_slice(), &[Light::Directional { azimuth_deg: 30.0, elevation_deg: 45.0 }]);
    assert!(lit.environment.as_ref().is_some_and(|p| p.ends_with("sky.exr")), "{:?}", lit.environment);
    let sky = parse("Scene(volume: Generated(\"ml32\"), lights: [Environment(Sky)])").expect("the generated sky");
    assert_eq!((sky.lights.as_slice(), sky.environment), (&[Light::Headlight][..], None));
    let both = "Scene(volume: Generated(\"ml32\"), environment: \"a.exr\", lights: [Environment(File(\"b.exr\"))])";
    let e = parse(both).expect_err("two environments").to_string();
    assert!(e.contains("lights: a scene has one environment"), "{e}");
    let typo = "Scene(volume: Generated(\"ml32\"), lights: [Directional(azimuth: 30, elevation_deg: 45)])";
    assert!(parse(typo).is_err(), "an unknown field of a light is an error");
    let point =
        parse("Scene(volume: Generated(\"ml32\"), lights: [Point(x: 0.5, y: 2, z: -1)])").expect("a point light");
    assert_eq!(point.lights.as_slice(), &[Light::Point { x: 0.5, y: 2.0, z: -1.0 }]);
    let two = "Scene(volume: Generated(\"ml32\"), lights: [Headlight, Directional(azimuth_deg: 0, elevation_deg: 0), \
               Environment(Sky)])";
    let two = parse(two).expect("two lights and the sky");
    let key = Light::Directional { azimuth_deg: 0.0, elevation_deg: 0.0 };
    assert_eq!(two.lights.as_slice(), &[Light::Headlight, key]);
    let four = "Scene(volume: Generated(\"ml32\"), lights: [Headlight, Headlight, Headlight, Headlight])";
    let e = parse(four).expect_err("four lights").to_string();
    assert!(e.contains("lights: 4 lights: a scene has 1 to 3"), "{e}");
    assert!(e.contains("keep at most 3"), "{e}");
    let second = "Scene(volume: Generated(\"ml32\"), lights: [Headlight, Point(x: 0, y: NaN, z: 0)])";
    let e = parse(second).expect_err("a NaN point").to_string();
    assert!(e.contains("lights: light 2: a point light's position must be finite"), "{e}");
    let e = parse("Scene(volume: Generated(\"ml32\"), lights: [Directional(azimuth_deg: 0, elevation_deg: 95)])")
        .expect_err("95°")
        .to_string();
    assert!(e.contains("lights: a light's elevation is -90..90 degrees, not 95"), "{e}");
}
