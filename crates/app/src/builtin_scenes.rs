//! The shipped scenes (`scenes/` of the workspace, by `build.rs`), built in like the graphs:
//! `volgraph scenes` lists them, a `--scene` argument that is not a file names one
//! (`engine_cut_open`, `scenes/engine_cut_open.ron`), so the README's scene commands run from
//! any folder; `volgraph scenes --export NAME [DIR]` and `volgraph graphs --export NAME [DIR]`
//! write a built-in out to edit. A file on disk always wins over a built-in of the same name.
//!
//! A shipped scene names its graph and transfer function as built-ins (`graph:
//! "modern/fastest.ron"`, `File("tf/marschner_lobb.ron")`) and its volume as a dataset of the
//! data folder or a generated one, so it reads the same wherever it is rendered from; exported
//! beside an exported graph of that name, the graph file wins (a scene's names resolve beside
//! it first).

use std::path::{Path, PathBuf};

use anyhow::anyhow;

use crate::builtin_graphs::EMBEDDED_SCENES;

/// The shipped scene a `--scene` argument names when nothing exists at that path (a file, even a
/// dangling link, is the user's): `engine_cut_open`, with or without `scenes/` and `.ron`.
pub fn find(argument: &Path) -> Option<(&'static str, &'static str)> {
    if argument.symlink_metadata().is_ok() {
        return None;
    }
    let text = argument.to_string_lossy().replace('\\', "/");
    let name = text.strip_prefix("./").unwrap_or(&text);
    let name = name.strip_prefix("scenes/").unwrap_or(name);
    let name = name.strip_suffix(".ron").unwrap_or(name);
    EMBEDDED_SCENES.iter().find(|(n, _)| *n == name).copied()
}

/// Where a built-in scene "lives" for its messages and relative names: a folder no scene's
/// relative path can be found in, so its graph and TF resolve as built-ins and nothing is read
/// from the folder it is rendered from.
pub fn virtual_path(name: &str) -> PathBuf {
    PathBuf::from(format!("<built-in>/scenes/{name}.ron"))
}

/// The text of `volgraph scenes`: one line per shipped scene (name, graph, volume).
pub fn listing() -> String {
    let width = EMBEDDED_SCENES.iter().map(|(n, _)| n.len()).max().unwrap_or(0);
    let mut out = String::new();
    for (name, text) in EMBEDDED_SCENES {
        let about = match crate::scene::Scene::from_str(text, &virtual_path(name)) {
            Ok(scene) => {
                let graph = scene.graph.as_ref().map_or("no graph".to_string(), |g| g.display().to_string());
                format!("graph {graph}, {} effect(s): {}", scene.effects.len(), scene.effects.join(", "))
            }
            Err(e) => format!("does not read: {e}"),
        };
        out.push_str(&format!("{name:width$}  {about}\n"));
    }
    out.push_str(&format!(
        "\n{} scenes built in; `volgraph render --scene NAME` renders one from any folder (a file of that name \
         wins), `volgraph scenes --export NAME [DIR]` writes it out to edit.\n",
        EMBEDDED_SCENES.len()
    ));
    out
}

/// What `--export` writes out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builtin {
    /// A graph (`modern/fastest` → `DIR/modern/fastest.ron`, the name a scene gives it).
    Graph,
    /// A scene (`engine_cut_open` → `DIR/engine_cut_open.ron`).
    Scene,
}

/// Writes the built-in `name` of `kind` into `dir` (created when missing) under the name a graph
/// argument or a scene gives it; refuses to replace a file there. Returns the path written.
pub fn export(kind: Builtin, name: &str, dir: &Path) -> anyhow::Result<PathBuf> {
    let (found, listing) = match kind {
        Builtin::Graph => (crate::builtin_graphs::find(Path::new(name)), "volgraph graphs"),
        Builtin::Scene => {
            let normalized = name.strip_prefix("scenes/").unwrap_or(name);
            let normalized = normalized.strip_suffix(".ron").unwrap_or(normalized);
            (EMBEDDED_SCENES.iter().find(|(n, _)| *n == normalized).copied(), "volgraph scenes")
        }
    };
    let Some((name, text)) = found else {
        return Err(anyhow!("\"{}\" is not a built-in {}; `{listing}` lists them", name, what(kind)));
    };
    let path = dir.join(format!("{name}.ron"));
    if path.symlink_metadata().is_ok() {
        return Err(anyhow!(
            "{}: already exists; remove it or give another folder (`--export {name} DIR`): nothing was written",
            path.display()
        ));
    }
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| anyhow!("{}: cannot create the folder: {e}", parent.display()))?;
    }
    crate::atomic_write::write_atomically(&path, text)?;
    Ok(path)
}

fn what(kind: Builtin) -> &'static str {
    match kind {
        Builtin::Graph => "graph",
        Builtin::Scene => "scene",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every scene of `scenes/` is built in, reads as a scene from its virtual folder, and names
    /// a built-in graph (so it renders from any folder).
    #[test]
    fn every_shipped_scene_is_built_in_and_names_built_ins() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut on_disk = 0;
        for file in std::fs::read_dir(&root).expect("scenes/").flatten() {
            let path = file.path();
            if path.extension().is_some_and(|e| e == "ron") {
                on_disk += 1;
                let stem = path.file_stem().expect("a stem").to_string_lossy().into_owned();
                let (name, text) = find(Path::new(&format!("scenes/{stem}.ron"))).expect("built in");
                assert_eq!(text, std::fs::read_to_string(&path).expect("readable"));
                let scene = crate::scene::Scene::from_str(text, &virtual_path(name)).expect("reads");
                let graph = scene.graph.expect("a shipped scene names its graph");
                assert!(
                    crate::builtin_graphs::find(&graph).is_some(),
                    "{name}: {} is not a built-in graph",
                    graph.display()
                );
            }
        }
        assert_eq!(EMBEDDED_SCENES.len(), on_disk);
        assert!(on_disk >= 4);
        assert_eq!(find(Path::new("engine_cut_open")).map(|(n, _)| n), Some("engine_cut_open"));
        assert_eq!(find(Path::new("nope")), None);
        assert!(listing().contains("engine_cut_open"));
    }

    /// `--export` writes the built-in's text where a scene or graph argument finds it, creates the
    /// folder, and never replaces a file.
    #[test]
    fn export_writes_a_copy_and_never_replaces_one() {
        let dir = std::env::temp_dir().join(format!("volgraph-export-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let graph = export(Builtin::Graph, "graphs/modern/fastest.ron", &dir).expect("exports");
        assert_eq!(graph, dir.join("modern/fastest.ron"));
        assert_eq!(
            std::fs::read_to_string(&graph).expect("written"),
            crate::builtin_graphs::find(Path::new("modern/fastest")).expect("built in").1
        );
        let again = export(Builtin::Graph, "modern/fastest", &dir).expect_err("exists").to_string();
        assert!(again.contains("already exists") && again.contains("nothing was written"), "{again}");
        let scene = export(Builtin::Scene, "engine_cut_open", &dir).expect("exports");
        assert_eq!(scene, dir.join("engine_cut_open.ron"));
        let unknown = export(Builtin::Scene, "engine_cut", &dir).expect_err("unknown").to_string();
        assert!(unknown.contains("volgraph scenes"), "{unknown}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
