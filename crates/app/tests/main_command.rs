//! The README's main command (`volgraph render graphs/basic/fragment_raycast.ron -o out.png`),
//! run at a small size: it needs nothing but a fresh clone (generated volume, built-in transfer
//! function) and writes a PNG with the volume visible in it.

use std::process::Command;

#[test]
fn the_main_command_renders_the_default_scene() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = std::env::temp_dir().join("volgraph_main_command.png");
    let _ = std::fs::remove_file(&out);
    let status = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(["render", "graphs/basic/fragment_raycast.ron", "--size", "64x64", "-o"])
        .arg(&out)
        .current_dir(&root)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .status()
        .expect("the volgraph binary runs");
    assert!(status.success(), "volgraph render exited with {status}");
    let image = image::open(&out).expect("a PNG was written").to_rgba8();
    assert_eq!(image.dimensions(), (64, 64));
    // The default camera sees the whole box; the Marschner–Lobb shells cover a good part of it.
    let lit = image.pixels().filter(|p| p.0[..3].iter().any(|c| *c > 20)).count();
    assert!(lit > 64 * 64 / 10, "only {lit} of {} pixels show anything", 64 * 64);
}
