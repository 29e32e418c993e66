//! The graphs compiled into the binary (`graphs/` of the workspace, by `build.rs`): `volgraph
//! graphs` lists them, and a graph argument that is not a file names one
//! (`kruger_westermann_2003/rc_b`), so an installed binary renders every paper's graphs from any
//! folder. A file on disk always wins over a built-in graph of the same name.

use std::path::Path;

include!(concat!(env!("OUT_DIR"), "/embedded_graphs.rs"));

/// One built-in graph.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltinGraph {
    /// `folder/stem`, e.g. `kruger_westermann_2003/rc_b`.
    pub name: &'static str,
    /// The paper its folder reproduces.
    pub paper: &'static str,
    /// The graph's `description:` (empty when it has none).
    pub description: String,
    /// The RON text.
    pub text: &'static str,
}

/// The paper (or purpose) of a `graphs/` folder.
fn paper_of(folder: &str) -> &'static str {
    match folder {
        "kruger_westermann_2003" => "Krüger & Westermann 2003",
        "compute_raycast_2013" => "the DirectCompute raycasting thesis (2013)",
        "klein_2005" => "Klein et al. 2005",
        "ruijters_vilanova_2006" => "Ruijters & Vilanova 2006",
        "modern" => "all four papers combined",
        "bench" => "benchmarks",
        "basic" => "basic raycasters",
        "clinical" => "clinical viewer",
        _ => "",
    }
}

/// Every built-in graph, in name order.
pub fn all() -> Vec<BuiltinGraph> {
    EMBEDDED_GRAPHS
        .iter()
        .map(|(name, text)| BuiltinGraph {
            name,
            paper: paper_of(name.split('/').next().unwrap_or_default()),
            description: volgraph_core::graph::parse_graph(text).map(|g| g.description).unwrap_or_default(),
            text,
        })
        .collect()
}

/// The built-in graph a command-line graph argument names: `folder/stem`, optionally with
/// `.ron` and a leading `graphs/` (as the source tree spells it).
pub fn find(argument: &Path) -> Option<(&'static str, &'static str)> {
    let name = normalized(argument);
    EMBEDDED_GRAPHS.iter().find(|(n, _)| *n == name).copied()
}

/// The built-in transfer function a path names when nothing exists at that path (a file, even
/// a dangling link, always wins): `graphs/tf/vessels.ron`, `tf/vessels.ron` or `tf/vessels` →
/// `("vessels", text)`.
pub fn find_tf(argument: &Path) -> Option<(&'static str, &'static str)> {
    if argument.symlink_metadata().is_ok() {
        return None;
    }
    builtin_tf(argument)
}

/// The built-in transfer function a name spells (`graphs/tf/vessels.ron`, `tf/vessels`), whatever
/// exists at that path: for a scene, whose names never depend on the folder it is rendered from.
pub fn builtin_tf(argument: &Path) -> Option<(&'static str, &'static str)> {
    let name = normalized(argument);
    let stem = name.strip_prefix("tf/")?;
    EMBEDDED_TFS.iter().find(|(n, _)| *n == stem).copied()
}

/// A graph argument as a built-in name would be spelled: `/` separators, without `./`,
/// `graphs/` or `.ron`.
pub fn normalized(argument: &Path) -> String {
    let text = argument.to_string_lossy().replace('\\', "/");
    let name = text.strip_prefix("./").unwrap_or(&text);
    let name = name.strip_prefix("graphs/").unwrap_or(name);
    name.strip_suffix(".ron").unwrap_or(name).to_string()
}

/// The text of `volgraph graphs`: one line per graph (name, paper, description).
pub fn listing() -> String {
    let graphs = all();
    let width = graphs.iter().map(|g| g.name.len()).max().unwrap_or(0);
    let mut out = String::new();
    for g in &graphs {
        let about = match (g.paper, g.description.as_str()) {
            ("", d) => d.to_string(),
            (p, "") => p.to_string(),
            (p, d) => format!("{p}: {d}"),
        };
        out.push_str(&format!("{:width$}  {about}\n", g.name));
    }
    out.push_str(&format!(
        "\n{} graphs built in; give a name to plan, render or view (a file of that name wins), e.g. \
         `volgraph render kruger_westermann_2003/rc_b -o rc_b.png`.\n",
        graphs.len()
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every graph file of `graphs/` (but the TFs) is built in and compiles with the built-in
    /// passes; names resolve with or without `graphs/` and `.ron`.
    #[test]
    fn every_graph_is_built_in_and_found_by_name() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs");
        let mut on_disk = 0;
        for folder in std::fs::read_dir(&root).expect("graphs/").flatten() {
            if folder.file_name() == "tf" || !folder.path().is_dir() {
                continue;
            }
            for file in std::fs::read_dir(folder.path()).expect("a folder").flatten() {
                let path = file.path();
                if path.extension().is_some_and(|e| e == "ron") {
                    on_disk += 1;
                    let relative = path.strip_prefix(&root).expect("inside graphs/");
                    let (_, text) = find(relative).unwrap_or_else(|| panic!("{} is not built in", relative.display()));
                    assert_eq!(text, std::fs::read_to_string(&path).expect("readable"));
                }
            }
        }
        assert_eq!(all().len(), on_disk);
        assert!(on_disk >= 20, "{on_disk}");
        for spelling in [
            "kruger_westermann_2003/rc_b",
            "graphs/kruger_westermann_2003/rc_b.ron",
            "./kruger_westermann_2003/rc_b.ron",
        ] {
            assert_eq!(find(Path::new(spelling)).map(|(n, _)| n), Some("kruger_westermann_2003/rc_b"), "{spelling}");
        }
        assert_eq!(find(Path::new("tf/default")), None, "transfer functions are not graphs");
        // Transfer functions by name, where nothing of that name is on disk (tests run in
        // crates/app, which has no graphs/); a file on disk is the user's.
        assert_eq!(find_tf(Path::new("graphs/tf/vessels.ron")).map(|(n, _)| n), Some("vessels"));
        assert_eq!(find_tf(Path::new("tf/nope.ron")), None);
        assert_eq!(find_tf(Path::new("Cargo.toml")), None);
        assert_eq!(find_tf(Path::new("graphs/tf/../../etc/passwd.ron")), None, "no climbing out");
        let registry = volgraph_passes::builtin_registry();
        for g in all() {
            volgraph_core::compile(g.name, g.text, &registry, &volgraph_core::CompileOptions::new(64, 64))
                .unwrap_or_else(|d| panic!("{}: {d}", g.name));
        }
        let listing = listing();
        assert!(
            listing.contains("kruger_westermann_2003/rc_b") && listing.contains("Krüger & Westermann 2003"),
            "{listing}"
        );
    }
}
