//! Scenes as files: `volgraph render --scene` renders every scene in `scenes/` (at a small size),
//! a positional graph and flags win over the scene's values, and a broken scene is an error
//! naming the file and line or field.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn volgraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(root())
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("the volgraph binary runs")
}

fn lit_fraction(path: &Path) -> f64 {
    let image = image::open(path).expect("a PNG was written").to_rgba8();
    let lit = image.pixels().filter(|p| p.0[..3].iter().any(|c| *c > 20)).count();
    lit as f64 / (image.width() * image.height()) as f64
}

#[test]
fn every_scene_in_the_scenes_folder_renders() {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .expect("scenes/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 3, "{scenes:?}");
    for scene in scenes {
        let out = std::env::temp_dir()
            .join(format!("volgraph_scene_{}.png", scene.file_stem().unwrap_or_default().to_string_lossy()));
        // Small and few frames: the scene's viewport and camera path are overridden.
        let o = volgraph(&[
            "render",
            "--scene",
            &scene.display().to_string(),
            "--size",
            "48x48",
            "--frames",
            "2",
            "-o",
            &out.display().to_string(),
        ]);
        assert!(o.status.success(), "{}: {}", scene.display(), String::from_utf8_lossy(&o.stderr));
        assert!(lit_fraction(&out) > 0.02, "{} shows something", scene.display());
    }
}

#[test]
fn a_graph_on_the_command_line_wins_over_the_scenes() {
    let out = std::env::temp_dir().join("volgraph_scene_graph_override.png");
    let o = volgraph(&[
        "render",
        "graphs/basic/isosurface.ron",
        "--scene",
        "scenes/marschner_lobb_shaded.ron",
        "--size",
        "32x32",
        "-o",
        &out.display().to_string(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("graphs/basic/isosurface.ron"), "the positional graph ran: {stderr}");
    // The isosurface has no shading or pre-integration to turn on: noted, not an error.
    assert!(stderr.contains("does not offer the scene's effect \"shading\""), "{stderr}");
}

#[test]
fn a_broken_scene_names_the_file_and_the_line_or_field() {
    let dir = std::env::temp_dir().join(format!("volgraph-scene-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let graph = Some("graphs/basic/compute_raycast.ron");
    let cases = [
        (
            "typo.ron",
            "Scene(\n    volume: Generated(\"ml16\"),\n    effectz: [\"shading\"],\n)\n",
            "typo.ron:3:",
            graph,
        ),
        (
            "effect.ron",
            "Scene(volume: Generated(\"ml16\"), effects: [\"scattering\"])\n",
            "effects: \"scattering\" is not an effect",
            graph,
        ),
        (
            "volume.ron",
            "Scene(volume: Generated(\"cube9\"))\n",
            "volume: Generated(\"cube9\") names no generated volume",
            graph,
        ),
        ("nograph.ron", "Scene(volume: Generated(\"ml16\"))\n", "no graph: give a graph file", None),
    ];
    for (name, text, expected, graph) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write");
        let out = dir.join("out.png");
        let (scene, out) = (path.display().to_string(), out.display().to_string());
        let mut args = vec!["render", "--scene", scene.as_str(), "-o", out.as_str()];
        args.extend(graph);
        let o = volgraph(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: expected {expected:?} in {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 24 §3: `--crop`/`--clip` and a scene's `crop:`/`clip:` are the same cut: the flags
/// render the scene's picture byte for byte, and the cut changes the picture.
#[test]
fn crop_and_clip_flags_equal_the_scenes_and_cut_the_image() {
    let dir = std::env::temp_dir().join(format!("volgraph-scene-cuts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = dir.join("cut.ron");
    std::fs::write(
        &scene,
        format!(
            "Scene(graph: \"{}\", volume: Generated(\"ml64\"), crop: (0, 0.1, 0, 0.6, 1, 1), clip: [(0, 1, 1, 0.7)])",
            root().join("graphs/modern/fastest.ron").display()
        ),
    )
    .expect("scene");
    let render = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args = vec!["render", "--size", "48x48", "-o", out.to_str().expect("utf-8")];
        args.extend_from_slice(extra);
        let o = volgraph(&args);
        assert!(o.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(&out).expect("written")
    };
    let from_scene = render(&["--scene", scene.to_str().expect("utf-8")], "scene.png");
    let from_flags =
        render(&["graphs/modern/fastest.ron", "--crop", "0,0.1,0,0.6,1,1", "--clip", "0,1,1,0.7"], "flags.png");
    let uncut = render(&["graphs/modern/fastest.ron"], "uncut.png");
    assert_eq!(from_scene, from_flags, "the scene's cuts and the flags render the same image");
    assert_ne!(from_scene, uncut, "the cut changes the image");
}

/// A bad crop or clip is an error naming the flag or field and the rule; a graph that cannot
/// cut is refused by pass name.
#[test]
fn bad_crops_and_clips_are_named() {
    let dir = std::env::temp_dir().join(format!("volgraph-scene-bad-cuts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("x.png");
    let out = out.to_str().expect("utf-8");
    for (args, expected) in [
        (vec!["--crop", "0,0,0,1,1"], "6 comma-separated numbers"),
        (vec!["--crop", "0.6,0,0,0.5,1,1"], "x axis"),
        (vec!["--clip", "0,0,0,1"], "no direction"),
        (vec!["--clip", "1,0,0,nan"], "not a finite number"),
    ] {
        let mut all = vec!["render", "graphs/modern/fastest.ron", "--size", "16x16", "-o", out];
        all.extend(args.iter().copied());
        let o = volgraph(&all);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} is refused");
        assert!(stderr.contains(expected) && stderr.contains(args[0]), "{args:?}: {stderr}");
    }
    let seven: Vec<&str> = (0..7).flat_map(|_| ["--clip", "1,0,0,0.1"]).collect();
    let mut all = vec!["render", "graphs/modern/fastest.ron", "--size", "16x16", "-o", out];
    all.extend(seven);
    let stderr = String::from_utf8_lossy(&volgraph(&all).stderr).to_string();
    assert!(stderr.contains("at most 6"), "{stderr}");
    let o = volgraph(&[
        "render",
        "graphs/kruger_westermann_2003/sbvr.ron",
        "--size",
        "16x16",
        "--crop",
        "0,0,0,0.5,1,1",
        "-o",
        out,
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("cannot crop") && stderr.contains("slices"), "{stderr}");
    let scene = dir.join("bad.ron");
    std::fs::write(&scene, "Scene(volume: Generated(\"ml64\"),\n  crop: (0, 0, 0, 1, 1, 2))").expect("scene");
    let o = volgraph(&["render", "graphs/modern/fastest.ron", "--scene", scene.to_str().expect("utf-8"), "-o", out]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("bad.ron") && stderr.contains("crop:") && stderr.contains("z axis"), "{stderr}");
}
