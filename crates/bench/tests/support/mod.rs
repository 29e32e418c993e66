//! The binaries copied away from the source tree (issue 20; the README's commands, issue 45
//! item 4): a sandbox of `bin/` (volgraph-bench, and the stock volgraph built beside it), an
//! empty working folder `work/` and a data folder `data/`, removed when dropped.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh folder under the system's temporary folder.
pub fn fresh(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-anywhere-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The binaries copied into `bin/`, the working folder `work/` and the data folder `data/`;
/// removed when dropped (the copies are hundreds of MB).
pub struct Sandbox {
    /// The sandbox itself.
    pub root: PathBuf,
    /// The copied volgraph-bench.
    pub bench: PathBuf,
    /// The copied stock volgraph, where it was built beside volgraph-bench.
    pub stock: Option<PathBuf>,
    /// The empty working folder.
    pub work: PathBuf,
    /// The empty data folder.
    pub data: PathBuf,
}

/// Copies the binaries into a fresh sandbox called `name`.
pub fn sandbox(name: &str) -> Sandbox {
    let root = fresh(name);
    let (bin, work, data) = (root.join("bin"), root.join("work"), root.join("data"));
    for d in [&bin, &work, &data] {
        std::fs::create_dir_all(d).expect("folders");
    }
    let built = PathBuf::from(env!("CARGO_BIN_EXE_volgraph-bench"));
    let bench = bin.join(built.file_name().expect("a file name"));
    std::fs::copy(&built, &bench).expect("copy volgraph-bench");
    let stock_built = built.with_file_name(format!("volgraph{}", std::env::consts::EXE_SUFFIX));
    let stock = stock_built.is_file().then(|| {
        let to = bin.join(stock_built.file_name().expect("a file name"));
        std::fs::copy(&stock_built, &to).expect("copy volgraph");
        to
    });
    if stock.is_none() && std::env::var_os("CI").is_some() {
        panic!("{} was not built beside volgraph-bench; CI runs cargo test --workspace", stock_built.display());
    }
    Sandbox { root, bench, stock, work, data }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

impl Sandbox {
    /// Runs `program` in the working folder with the empty data folder, no VOLGRAPH_DATA.
    pub fn run(&self, program: &Path, args: &[&str]) -> Output {
        let output = Command::new(program)
            .current_dir(&self.work)
            .env_remove("VOLGRAPH_DATA")
            .arg("--data")
            .arg(&self.data)
            .args(args)
            .output()
            .expect("runs");
        assert!(
            output.status.success(),
            "{} {args:?} failed ({}):\n{}",
            program.display(),
            output.status,
            String::from_utf8_lossy(&output.stderr)
        );
        output
    }
}
