//! Issue 42: the built-in kinds' declarations build without wgpu. volgraph-passes' `gpu`
//! feature (on by default) adds the nodes; without it the crate is `builtin_kinds()`, the
//! parameter blocks and the shaders — what `volgraph plan` and the golden plans read. Checked
//! three ways: the dependency tree of the declarations-only build holds no wgpu and no runtime,
//! that build compiles, and its declarations plan every shipped graph exactly as the registry
//! of the full build does.

use std::process::Command;

use volgraph_compiler::{CompileOptions, KindLookup, compile};

fn cargo() -> Command {
    let mut command = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string()));
    command.current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    command
}

#[test]
fn the_declarations_only_build_depends_on_no_gpu_stack() {
    let out = cargo()
        .args([
            "tree",
            "--offline",
            "-e",
            "normal",
            "-p",
            "volgraph-passes",
            "--no-default-features",
            "--prefix",
            "none",
        ])
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree: {}", String::from_utf8_lossy(&out.stderr));
    let tree = String::from_utf8_lossy(&out.stdout);
    for crate_name in ["wgpu ", "wgpu-core ", "wgpu-hal ", "volgraph-core "] {
        assert!(!tree.lines().any(|l| l.starts_with(crate_name)), "{crate_name}in the declarations-only tree:\n{tree}");
    }
    assert!(tree.lines().any(|l| l.starts_with("volgraph-compiler ")), "the declarations need the compiler:\n{tree}");
}

#[test]
fn the_declarations_only_build_compiles() {
    // A target folder of its own: the one this test runs from is locked by the running build.
    let target = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("declarations-only");
    let out = cargo()
        .args(["check", "--offline", "--quiet", "--lib", "-p", "volgraph-passes", "--no-default-features"])
        .arg("--target-dir")
        .arg(&target)
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo check --no-default-features:\n{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn the_declarations_plan_every_graph_as_the_registry_does() {
    let declarations = volgraph_passes::builtin_kinds();
    let registry = volgraph_passes::builtin_registry();
    assert_eq!(declarations.kind_names(), registry.kind_names());
    assert_eq!(declarations.uniform_imports(), registry.uniform_imports());
    let options = CompileOptions::new(512, 512);
    let root = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../graphs"));
    let mut planned = 0;
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("graphs/") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                if !path.ends_with("tf") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "ron") {
                continue;
            }
            let source = std::fs::read_to_string(&path).expect("readable");
            let name = path.display().to_string();
            let from_declarations = compile(&name, &source, &declarations, &options).map(|p| p.to_text());
            let from_registry = compile(&name, &source, &registry, &options).map(|p| p.to_text());
            match (from_declarations, from_registry) {
                (Ok(a), Ok(b)) => assert_eq!(a, b, "{name}"),
                (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{name}: one plans, the other does not"),
            }
            planned += 1;
        }
    }
    assert!(planned >= 25, "planned {planned} graphs");
}
