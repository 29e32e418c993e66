//! The shaders compiled into the binary (`EMBEDDED_SHADERS`) are exactly the files of the
//! workspace's `shaders/` folder, and a folder on disk in front of them wins (what a developer
//! edits and the viewer hot-reloads), with imports still resolved through the embedded layer.

use volgraph_core::shader_source::{ShaderSources, assemble, default_shader_root};
use volgraph_passes::{EMBEDDED_SHADERS, builtin_shaders};

fn files_under(dir: &std::path::Path, prefix: &str, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).expect("shaders/ is readable").flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            files_under(&path, &format!("{prefix}{name}/"), out);
        } else if name.ends_with(".wgsl") {
            out.push(format!("{prefix}{name}"));
        }
    }
}

#[test]
fn every_shader_file_is_embedded_with_its_text() {
    let root = default_shader_root();
    let mut on_disk = Vec::new();
    files_under(&root, "", &mut on_disk);
    on_disk.sort();
    let mut embedded: Vec<String> = EMBEDDED_SHADERS.iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(embedded, on_disk);
    for (name, text) in EMBEDDED_SHADERS {
        assert_eq!(*text, std::fs::read_to_string(root.join(name)).expect("readable"), "{name}");
    }
}

#[test]
fn a_disk_folder_in_front_wins_and_imports_fall_through() {
    let dir = std::env::temp_dir().join(format!("volgraph-shader-layer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("present.wgsl"), "#import \"common/fullscreen.wgsl\"\n// edited copy\n").expect("write");
    let sources: ShaderSources = builtin_shaders().prepend_disk(&dir);
    let source = assemble(&sources, "present.wgsl").expect("assembles");
    assert!(source.text.contains("// edited copy"), "the disk copy wins");
    assert_eq!(source.files[0].path.as_deref(), Some(dir.join("present.wgsl").as_path()));
    assert!(source.files[1].path.is_none(), "the import came from the embedded layer");
    assert_eq!(source.disk_paths(), vec![dir.join("present.wgsl")], "only disk files are watched");
    // Line mapping through #import: the first line of text is fullscreen.wgsl's line 1.
    let (path, line) = source.origin_of_line(1).expect("mapped");
    assert!(path.ends_with("common/fullscreen.wgsl"), "{}", path.display());
    assert_eq!(line, 1);
}
