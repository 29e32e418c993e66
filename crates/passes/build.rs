//! Compiles every file of the workspace's `shaders/` folder into the binary
//! (`volgraph_passes::EMBEDDED_SHADERS`), so an installed `volgraph` needs no source tree. A
//! developer's edits still show up: the runtime reads a shader folder on disk first when one is
//! given or found beside the graph (`ShaderSources`).

use std::path::{Path, PathBuf};

fn collect(dir: &Path, root: &Path, out: &mut Vec<(String, PathBuf)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for path in paths {
        if path.is_dir() {
            collect(&path, root, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let relative = path.strip_prefix(root).unwrap_or(&path).to_string_lossy().replace('\\', "/");
            out.push((relative, path));
        }
    }
}

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".to_string());
    let root = Path::new(&manifest).join("../../shaders");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    collect(&root, &root, &mut files);
    let mut code = String::from(
        "/// Every shader of the workspace's `shaders/` folder: `(relative name, text)`.\npub static EMBEDDED_SHADERS: &[(&str, &str)] = &[\n",
    );
    for (name, path) in &files {
        let absolute = path.canonicalize().unwrap_or_else(|_| path.clone());
        code.push_str(&format!("    ({name:?}, include_str!({:?})),\n", absolute.display().to_string()));
    }
    code.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap_or_else(|_| ".".to_string())).join("embedded_shaders.rs");
    if let Err(e) = std::fs::write(&out, code) {
        panic!("cannot write {}: {e}", out.display());
    }
}
