//! WGSL source loading with the project's one way to share code: `#import "path.wgsl"`.
//!
//! A line that is exactly `#import "common/frame.wgsl"` (leading whitespace allowed) is replaced
//! by that file's text. Each file is pulled in once per module however often it is imported,
//! imports nest, and cycles are an error. naga never sees the `#import` lines.
//!
//! Files come from [`ShaderSources`]: folders on disk first (what a developer edits and the
//! viewer watches), then tables compiled into the binary (`volgraph_passes::EMBEDDED_SHADERS`),
//! so an installed binary works from any directory. An external plugin crate puts its own
//! folder or table first and still imports `common/frame.wgsl` from volgraph's.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Why a shader source could not be assembled.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum ShaderSourceError {
    /// No layer has the file.
    #[error("{file}: no such shader (searched: {searched})")]
    NotFound {
        /// The relative name.
        file: String,
        /// The layers searched.
        searched: String,
    },
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

/// A table of shader files compiled into a binary: `(relative name, text)`.
pub type EmbeddedShaders = &'static [(&'static str, &'static str)];

/// One place shader files are looked up.
#[derive(Clone, Debug)]
pub enum SourceLayer {
    /// A folder on disk: read on every (re)load, so edits show up.
    Disk(PathBuf),
    /// Files compiled into the binary.
    Embedded(EmbeddedShaders),
}

/// Where shader files come from, searched in order.
#[derive(Clone, Debug, Default)]
pub struct ShaderSources {
    layers: Vec<SourceLayer>,
}

/// One file as read: its relative name and, for files on disk, its path (what a watcher follows).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct SourceFile {
    /// Relative name, `common/frame.wgsl`.
    pub name: String,
    /// The file on disk, when it came from a folder.
    pub path: Option<PathBuf>,
}

impl SourceFile {
    /// The path for messages: the disk path, or `<embedded>/name`.
    pub fn display_path(&self) -> PathBuf {
        self.path.clone().unwrap_or_else(|| Path::new("<embedded>").join(&self.name))
    }
}

impl ShaderSources {
    /// No layers.
    pub fn new() -> Self {
        Self::default()
    }

    /// Searches `dir` after the layers already added.
    pub fn with_disk(mut self, dir: impl Into<PathBuf>) -> Self {
        self.layers.push(SourceLayer::Disk(dir.into()));
        self
    }

    /// Searches `table` after the layers already added.
    pub fn with_embedded(mut self, table: EmbeddedShaders) -> Self {
        self.layers.push(SourceLayer::Embedded(table));
        self
    }

    /// Searches `dir` before every layer already added.
    pub fn prepend_disk(mut self, dir: impl Into<PathBuf>) -> Self {
        self.layers.insert(0, SourceLayer::Disk(dir.into()));
        self
    }

    /// The layers, in search order.
    pub fn layers(&self) -> &[SourceLayer] {
        &self.layers
    }

    /// The disk folders, in search order.
    pub fn disk_roots(&self) -> Vec<&Path> {
        self.layers
            .iter()
            .filter_map(|l| match l {
                SourceLayer::Disk(p) => Some(p.as_path()),
                SourceLayer::Embedded(_) => None,
            })
            .collect()
    }

    fn describe(&self) -> String {
        let parts: Vec<String> = self
            .layers
            .iter()
            .map(|l| match l {
                SourceLayer::Disk(p) => p.display().to_string(),
                SourceLayer::Embedded(t) => format!("{} embedded files", t.len()),
            })
            .collect();
        if parts.is_empty() { "no layers".to_string() } else { parts.join(", ") }
    }

    /// The text of `relative` from the first layer that has it.
    pub fn read(&self, relative: &str) -> Result<(SourceFile, String), ShaderSourceError> {
        for layer in &self.layers {
            match layer {
                SourceLayer::Disk(root) => {
                    let path = root.join(relative);
                    if path.is_file() {
                        let text = std::fs::read_to_string(&path)
                            .map_err(|e| ShaderSourceError::Read { path: path.clone(), reason: e.to_string() })?;
                        return Ok((SourceFile { name: relative.to_string(), path: Some(path) }, text));
                    }
                }
                SourceLayer::Embedded(table) => {
                    if let Some((_, text)) = table.iter().find(|(name, _)| *name == relative) {
                        return Ok((SourceFile { name: relative.to_string(), path: None }, text.to_string()));
                    }
                }
            }
        }
        Err(ShaderSourceError::NotFound { file: relative.to_string(), searched: self.describe() })
    }
}

/// A shader module's assembled text and the files it came from.
#[derive(Clone, Debug)]
pub struct ShaderSource {
    /// The WGSL text with every import inlined.
    pub text: String,
    /// Every file read, the root file first: relative names, and disk paths where on disk (what a
    /// hot-reload watcher follows).
    pub files: Vec<SourceFile>,
    /// For each line of `text` (0-based): the file (index into `files`) and 1-based line it came
    /// from, so compiler messages can point at the file a developer edits.
    pub line_origins: Vec<(usize, usize)>,
}

impl ShaderSource {
    /// The disk paths among [`Self::files`].
    pub fn disk_paths(&self) -> Vec<PathBuf> {
        self.files.iter().filter_map(|f| f.path.clone()).collect()
    }

    /// Where 1-based line `line` of the assembled text came from: `(file path for messages, line)`.
    pub fn origin_of_line(&self, line: usize) -> Option<(PathBuf, usize)> {
        let (file, at) = *self.line_origins.get(line.checked_sub(1)?)?;
        Some((self.files.get(file)?.display_path(), at))
    }
}

/// The default shader folder of a source checkout: `shaders/` at the workspace root, or
/// `VOLGRAPH_SHADERS` if set. Binaries should not depend on it; it exists for tests and tools
/// that read shader files as files.
pub fn default_shader_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("VOLGRAPH_SHADERS") {
        return PathBuf::from(dir);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders")
}

/// Loads `relative` (e.g. `raycast.wgsl`) under `root`, inlining imports.
pub fn load_shader(root: &Path, relative: &str) -> Result<ShaderSource, ShaderSourceError> {
    assemble(&ShaderSources::new().with_disk(root), relative)
}

/// Assembles `relative` from `sources`, resolving every import through the same layers.
pub fn assemble(sources: &ShaderSources, relative: &str) -> Result<ShaderSource, ShaderSourceError> {
    let mut out = ShaderSource { text: String::new(), files: Vec::new(), line_origins: Vec::new() };
    let mut included = BTreeSet::new();
    let mut stack = Vec::new();
    append(sources, relative, &mut out, &mut included, &mut stack)?;
    Ok(out)
}

fn append(
    sources: &ShaderSources,
    relative: &str,
    out: &mut ShaderSource,
    included: &mut BTreeSet<String>,
    stack: &mut Vec<String>,
) -> Result<(), ShaderSourceError> {
    if stack.iter().any(|s| s == relative) {
        let mut chain = stack.clone();
        chain.push(relative.to_string());
        return Err(ShaderSourceError::ImportCycle { path: PathBuf::from(relative), chain: chain.join(" → ") });
    }
    if !included.insert(relative.to_string()) {
        return Ok(());
    }
    let (file, text) = sources.read(relative)?;
    let path = file.display_path();
    let index = out.files.len();
    out.files.push(file);
    stack.push(relative.to_string());
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix("#import") {
            let target = rest.trim().strip_prefix('"').and_then(|r| r.strip_suffix('"'));
            match target {
                Some(t) if !t.is_empty() => append(sources, t, out, included, stack)?,
                _ => return Err(ShaderSourceError::MalformedImport { path, line: i + 1 }),
            }
        } else {
            out.text.push_str(line);
            out.text.push('\n');
            out.line_origins.push((index, i + 1));
        }
    }
    stack.pop();
    Ok(())
}
