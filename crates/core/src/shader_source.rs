//! WGSL source loading with the project's one way to share code: `#import "path.wgsl"`.
//!
//! A line that is exactly `#import "common/frame.wgsl"` (leading whitespace allowed) is replaced
//! by that file's text, resolved relative to the shader root (`shaders/`). Each file is pulled in
//! once per module however often it is imported, imports nest, and cycles are an error. naga never
//! sees the `#import` lines. Hot reload watches every file listed in [`ShaderSource::files`].

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Why a shader source could not be assembled.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ShaderSourceError {
    /// A file could not be read.
    #[error("{path}: cannot read shader source: {reason}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error text.
        reason: String,
    },
    /// An `#import` line is not of the form `#import "relative/path.wgsl"`.
    #[error("{path}:{line}: malformed import; write it as #import \"common/frame.wgsl\"")]
    MalformedImport {
        /// The importing file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
    },
    /// Files import each other in a cycle.
    #[error("{path}: import cycle: {chain}")]
    ImportCycle {
        /// The file that closes the cycle.
        path: PathBuf,
        /// The chain of imports, `a.wgsl → b.wgsl → a.wgsl`.
        chain: String,
    },
}

/// A shader module's assembled text and the files it came from.
#[derive(Clone, Debug)]
pub struct ShaderSource {
    /// The WGSL text with every import inlined.
    pub text: String,
    /// Every file read, the root file first (what a hot-reload watcher follows).
    pub files: Vec<PathBuf>,
}

/// The default shader root: `shaders/` at the workspace root, or `VOLGRAPH_SHADERS` if set.
pub fn default_shader_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("VOLGRAPH_SHADERS") {
        return PathBuf::from(dir);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders")
}

/// Loads `relative` (e.g. `raycast.wgsl`) under `root`, inlining imports.
pub fn load_shader(root: &Path, relative: &str) -> Result<ShaderSource, ShaderSourceError> {
    load_shader_from(&[root.to_path_buf()], relative)
}

/// Loads `relative` from the first of `roots` that has it, resolving every import the same way:
/// an external plugin crate puts its own shader folder first and still imports
/// `common/frame.wgsl` from volgraph's.
pub fn load_shader_from(roots: &[PathBuf], relative: &str) -> Result<ShaderSource, ShaderSourceError> {
    let mut out = ShaderSource { text: String::new(), files: Vec::new() };
    let mut included = BTreeSet::new();
    let mut stack = Vec::new();
    append(roots, relative, &mut out, &mut included, &mut stack)?;
    Ok(out)
}

fn append(
    roots: &[PathBuf],
    relative: &str,
    out: &mut ShaderSource,
    included: &mut BTreeSet<String>,
    stack: &mut Vec<String>,
) -> Result<(), ShaderSourceError> {
    let path = roots
        .iter()
        .map(|r| r.join(relative))
        .find(|p| p.is_file())
        .unwrap_or_else(|| roots.first().map_or_else(|| PathBuf::from(relative), |r| r.join(relative)));
    if stack.iter().any(|s| s == relative) {
        let mut chain = stack.clone();
        chain.push(relative.to_string());
        return Err(ShaderSourceError::ImportCycle { path, chain: chain.join(" → ") });
    }
    if !included.insert(relative.to_string()) {
        return Ok(());
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| ShaderSourceError::Read { path: path.clone(), reason: e.to_string() })?;
    out.files.push(path.clone());
    stack.push(relative.to_string());
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix("#import") {
            let target = rest.trim().strip_prefix('"').and_then(|r| r.strip_suffix('"'));
            match target {
                Some(t) if !t.is_empty() => append(roots, t, out, included, stack)?,
                _ => return Err(ShaderSourceError::MalformedImport { path, line: i + 1 }),
            }
        } else {
            out.text.push_str(line);
            out.text.push('\n');
        }
    }
    stack.pop();
    Ok(())
}
