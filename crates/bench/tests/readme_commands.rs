//! The README runs from anywhere (issue 45, item 4): every command of its "Using it" block runs
//! as written from an empty folder with the installed binaries — copied away from the source
//! tree, found on `PATH` — and the real data folder, in the README's order (the graph exported
//! is the one `set` edits). A command that cannot run there is listed with the reason
//! (the user's own files, a window, MPI from the source tree, a benchmark's minutes, an
//! optional tool); at least 25 must run, so the test cannot pass by skipping.

use std::path::{Path, PathBuf};
use std::process::Command;

mod support;

/// The commands of the first ```sh block after "## Using it": continuation lines joined,
/// comments and blank lines dropped.
fn readme_commands(readme: &str) -> Vec<String> {
    let section = readme.split("## Using it").nth(1).expect("a \"Using it\" section");
    let block = section.split("```sh").nth(1).expect("a sh block").split("```").next().expect("its end");
    let mut commands = Vec::new();
    let mut pending = String::new();
    for line in block.lines() {
        let line = strip_comment(line);
        let line = line.trim();
        if line.is_empty() && pending.is_empty() {
            continue;
        }
        match line.strip_suffix('\\') {
            Some(start) => {
                pending.push_str(start.trim_end());
                pending.push(' ');
            }
            None => {
                pending.push_str(line);
                let command = std::mem::take(&mut pending).trim().to_string();
                if !command.is_empty() {
                    commands.push(command);
                }
            }
        }
    }
    commands
}

/// A line without its `# comment` (a `#` at the start or after a space; none are quoted here).
fn strip_comment(line: &str) -> &str {
    if line.trim_start().starts_with('#') {
        return "";
    }
    match line.find(" #") {
        Some(at) => &line[..at],
        None => line,
    }
}

/// Files the README names as the user's own (placeholders no data folder holds).
const USERS_FILES: [&str; 13] = [
    "path/to/",
    "ct_series/",
    "seg.nii.gz",
    "ct.nii.gz",
    "pet.nii.gz",
    "brain.nii.gz",
    "seg.seg.nrrd",
    "seg.dcm",
    "labels.txt",
    "liver_only.txt",
    "hot.ron",
    "my_graph.ron",
    "cells.nii",
];

/// Why `command` cannot run from an empty folder here, if it cannot.
fn why_not(command: &str, have_dot: bool) -> Option<String> {
    if command.starts_with("cargo ") || command.starts_with("mpirun ") {
        return Some("builds or runs in the source tree (MPI: tests/distributed_mpi.rs runs it)".into());
    }
    if command.starts_with("sh bench/") || command.starts_with("bench/") {
        return Some("a script of the source tree's bench/ folder".into());
    }
    if command.starts_with("volgraph view") {
        return Some("opens a window (tests/viewer_window.rs drives the viewer under Xvfb)".into());
    }
    if command.starts_with("volgraph bench") || command.starts_with("volgraph sweep") {
        return Some(
            "a benchmark: minutes (tests/from_any_folder.rs runs a preset and a sweep from an empty folder)".into(),
        );
    }
    if let Some(file) = USERS_FILES.iter().find(|f| command.contains(*f)) {
        return Some(format!("names the user's own file ({file})"));
    }
    if command.contains("| dot ") && !have_dot {
        return Some("needs Graphviz's dot, which is optional and not installed here".into());
    }
    None
}

/// Whether `program` is on PATH.
fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(program).is_file()))
}

#[test]
fn every_readme_command_runs_from_an_empty_folder() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).expect("README");
    let commands = readme_commands(&readme);
    assert!(commands.len() > 40, "the block was read: {} commands", commands.len());
    let s = support::sandbox("readme");
    let Some(stock) = s.stock.clone() else {
        eprintln!("note: volgraph was not built beside volgraph-bench; the README's commands need both");
        return;
    };
    let data = volgraph_accel::data_dir::data_dir();
    if !data.join("volumes").is_dir() {
        assert!(!volgraph_accel::data_dir::is_ci(), "under CI the data folder {} must exist", data.display());
        eprintln!("note: no data folder at {}: the README's datasets are missing; nothing run", data.display());
        return;
    }
    let bin: PathBuf = stock.parent().expect("bin/").to_path_buf();
    let path = std::env::join_paths(
        std::iter::once(bin).chain(std::env::var_os("PATH").iter().flat_map(std::env::split_paths)),
    )
    .expect("a PATH");
    let have_dot = on_path("dot");
    let (mut ran, mut skipped) = (Vec::new(), Vec::new());
    for command in &commands {
        if let Some(reason) = why_not(command, have_dot) {
            skipped.push(format!("{command}\n    not run: {reason}"));
            continue;
        }
        let started = std::time::Instant::now();
        let output = Command::new("sh")
            .arg("-c")
            .arg(command)
            .current_dir(&s.work)
            .env("PATH", &path)
            .env("VOLGRAPH_DATA", &data)
            .output()
            .expect("sh runs");
        assert!(
            output.status.success(),
            "`{command}` failed from an empty folder ({}):\n{}\n{}",
            output.status,
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        ran.push(format!("{command} ({:.1} s)", started.elapsed().as_secs_f64()));
    }
    eprintln!("ran {} commands:\n  {}", ran.len(), ran.join("\n  "));
    eprintln!("not run, {}:\n  {}", skipped.len(), skipped.join("\n  "));
    assert!(ran.len() >= 25, "only {} of the README's commands ran", ran.len());
    // What they wrote is there: an image of each -o, the exported graph the set edited.
    let edited = std::fs::read_to_string(s.work.join("modern/fastest.ron")).expect("graphs --export wrote it");
    assert!(edited.contains("\"step_voxels\": 0.25"), "set edited the exported graph");
    for image in ["lobster.png", "rc_b.png", "shaded.png", "engine_cut.png", "cinematic.png", "out.exr"] {
        let bytes = std::fs::read(s.work.join(image)).unwrap_or_else(|e| panic!("{image}: {e}"));
        assert!(bytes.len() > 100, "{image} is written");
    }
}

#[test]
fn the_block_is_read_as_commands() {
    let text =
        "## Using it\n\n```sh\n# a comment\nvolgraph info lobster\nvolgraph render a \\\n    --b c   # note\n\n```\n";
    assert_eq!(readme_commands(text), ["volgraph info lobster", "volgraph render a --b c"]);
    assert!(why_not("volgraph view x", false).is_some());
    assert!(why_not("volgraph info seg.nii.gz --labels", false).is_some_and(|r| r.contains("seg.nii.gz")));
    assert_eq!(why_not("volgraph render rc_b -o x.png", false), None);
}
