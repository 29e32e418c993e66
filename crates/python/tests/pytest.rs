//! The Python package's tests (`tests/test_*.py`) in the README's test command: a virtual
//! environment under the target folder (made once, with [`REQUIREMENTS`] from PyPI), the
//! package built into it by `maturin develop` (the dev profile, sharing the workspace's target
//! folder), then pytest, with `VOLGRAPH_BIN` the workspace's `volgraph` binary for the
//! comparisons with the command line. Without Python 3 it says so and passes — except under CI,
//! where a missing Python is a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

/// What the tests need besides the package: the build, the test runner, the notebook's kernel
/// and plots, the widget's frame buffer, and the libraries users' NIfTI, DICOM and OME-Zarr files
/// come from.
const REQUIREMENTS: &[&str] = &[
    "maturin>=1.5,<2",
    "numpy",
    "pytest",
    "jupyter_rfb",
    "ipywidgets",
    "nbclient",
    "nbformat",
    "ipykernel",
    "matplotlib",
    "nibabel",
    "pydicom",
    "ome-zarr",
];

fn run(what: &str, command: &mut Command) {
    let status = command.status().unwrap_or_else(|e| panic!("{what}: cannot run: {e}"));
    assert!(status.success(), "{what} failed ({status})");
}

/// The workspace's target folder (this test runs from `target/<profile>/deps/`).
fn target_profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    exe.parent().and_then(Path::parent).expect("target/<profile>").to_path_buf()
}

#[test]
fn the_python_package_passes_its_tests() {
    let python = std::env::var("VOLGRAPH_PYTHON").unwrap_or_else(|_| "python3".to_string());
    let found = Command::new(&python).arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        assert!(std::env::var_os("CI").is_none(), "{python} is missing: the Python package cannot be tested");
        eprintln!("note: {python} not found; the Python package's tests are skipped (CI fails here)");
        return;
    }
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let profile = target_profile_dir();
    let venv = profile.join("python-venv");
    let bin = venv.join("bin");
    // The list installed is written beside the venv: a changed list installs again.
    let installed = venv.join("volgraph-requirements.txt");
    let wanted = REQUIREMENTS.join("\n");
    if std::fs::read_to_string(&installed).ok().as_deref() != Some(wanted.as_str()) {
        if !bin.join("python").exists() {
            run("python3 -m venv", Command::new(&python).args(["-m", "venv"]).arg(&venv));
        }
        run(
            "pip install (the tests' requirements)",
            Command::new(bin.join("python")).args(["-m", "pip", "install", "-q"]).args(REQUIREMENTS),
        );
        std::fs::write(&installed, &wanted).expect("write the venv's requirements list");
    }
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    run(
        "maturin develop",
        Command::new(bin.join("maturin"))
            .args(["develop", "--quiet", "--manifest-path"])
            .arg(crate_dir.join("Cargo.toml"))
            .env("VIRTUAL_ENV", &venv)
            .env("PATH", &path),
    );
    run(
        "pytest",
        Command::new(bin.join("python"))
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(crate_dir.join("tests"))
            .env("VOLGRAPH_BIN", profile.join("volgraph"))
            .env("PATH", &path),
    );
}
