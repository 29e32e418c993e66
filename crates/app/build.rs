//! Compiles every graph of the workspace's `graphs/` folder (not the transfer functions of
//! `graphs/tf/`) into the binary (`crate::builtin_graphs::EMBEDDED_GRAPHS`), so an installed
//! `volgraph` renders them by name from any folder: `volgraph render kruger_westermann_2003/rc_b`;
//! and the shipped scenes of `scenes/` (`EMBEDDED_SCENES`): `volgraph render --scene
//! engine_cut_open`.

use std::path::{Path, PathBuf};

fn collect(dir: &Path, root: &Path, out: &mut Vec<(String, PathBuf)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for path in paths {
        let relative = path.strip_prefix(root).unwrap_or(&path).to_string_lossy().replace('\\', "/");
        if path.is_dir() {
            if relative != "tf" {
                collect(&path, root, out);
            }
        } else if let Some(name) = relative.strip_suffix(".ron") {
            out.push((name.to_string(), path));
        }
    }
}

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".to_string());
    let root = Path::new(&manifest).join("../../graphs");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files = Vec::new();
    collect(&root, &root, &mut files);
    let mut code = String::from(
        "/// Every graph of the workspace's `graphs/` folder: `(name, text)`, the name its path there \
         without `.ron`.\npub static EMBEDDED_GRAPHS: &[(&str, &str)] = &[\n",
    );
    for (name, path) in &files {
        println!("cargo:rerun-if-changed={}", path.display());
        let absolute = path.canonicalize().unwrap_or_else(|_| path.clone());
        code.push_str(&format!("    ({name:?}, include_str!({:?})),\n", absolute.display().to_string()));
    }
    code.push_str("];\n");
    // The transfer functions of `graphs/tf/`, which presets and scenes name, and the shipped
    // scenes of `scenes/`, which name their graphs and TFs as built-ins.
    embed_folder(&mut code, "EMBEDDED_TFS", "transfer function of the workspace's `graphs/tf/`", &root.join("tf"));
    let scenes = Path::new(&manifest).join("../../scenes");
    embed_folder(&mut code, "EMBEDDED_SCENES", "scene of the workspace's `scenes/`", &scenes);
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap_or_else(|_| ".".to_string())).join("embedded_graphs.rs");
    if let Err(e) = std::fs::write(&out, code) {
        panic!("cannot write {}: {e}", out.display());
    }
}

/// Appends `pub static NAME: &[(&str, &str)]`: `(stem, text)` of every `.ron` file of `dir` (not
/// below it), in name order; `what` documents it.
fn embed_folder(code: &mut String, name: &str, what: &str, dir: &Path) {
    println!("cargo:rerun-if-changed={}", dir.display());
    code.push_str(&format!("/// Every {what} folder: `(stem, text)`.\npub static {name}: &[(&str, &str)] = &[\n"));
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.sort();
    for path in files.iter().filter(|p| p.extension().is_some_and(|e| e == "ron")) {
        println!("cargo:rerun-if-changed={}", path.display());
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let absolute = path.canonicalize().unwrap_or_else(|_| path.clone());
        code.push_str(&format!("    ({stem:?}, include_str!({:?})),\n", absolute.display().to_string()));
    }
    code.push_str("];\n");
}
