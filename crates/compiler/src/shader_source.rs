//! WGSL source loading with the project's one way to share code: `#import "path.wgsl"`.
//!
//! A line that is exactly `#import "common/frame.wgsl"` (leading whitespace allowed) is replaced
//! by that file's text. Each file is pulled in once per module however often it is imported,
//! imports nest, and cycles are an error. naga never sees the `#import` lines.
//!
//! Effects a scene may leave off are written between `#if NAME` (or `#if !NAME`), optional
//! `#else`, and `#endif` lines, which nest and must close in the file that opens them. A module
//! is assembled for a set of defines (`assemble_with`): lines in inactive branches — imports
//! included — are dropped, so an unused effect's code is not in the module at all (not merely
//! unreachable), and naga, the pipeline and the GPU never see it.
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
    #[error(
        "{file}: no such shader (searched: {searched}); a graph's own shaders (WGSL-only kinds) go in a shaders/ folder beside the graph file or its parent"
    )]
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
    /// An `#if`/`#else`/`#endif` line that does not match, or an `#if` left open.
    #[error("{path}:{line}: {problem}; write #if NAME (or #if !NAME), #else and #endif, closed in the same file")]
    MalformedDirective {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        problem: String,
    },
    /// A shader name that would reach outside the shader roots (absolute, `..`), or a file that
    /// is not WGSL. Its text is never read, so a mistaken `#import "/etc/passwd"` shows nothing of
    /// the file.
    #[error("{file}: {reason}; shaders are named relative to a shader folder, e.g. \"common/frame.wgsl\"")]
    OutsideRoots {
        /// The name as written.
        file: String,
        /// What is wrong with it.
        reason: &'static str,
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
    /// Files generated from Rust declarations: the WGSL struct of each `pass_params!` block,
    /// under `params/NAME.wgsl` ([`crate::declare`]), so a shader imports the struct its pass
    /// uploads instead of restating it.
    Generated(std::sync::Arc<Vec<(String, String)>>),
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

    /// Searches `table` before every layer already added (a plugin program's own shaders).
    pub fn prepend_embedded(mut self, table: EmbeddedShaders) -> Self {
        self.layers.insert(0, SourceLayer::Embedded(table));
        self
    }

    /// Searches the generated files `files` (`(relative name, text)`; the `wgsl_import()` of
    /// `pass_params!` blocks) after the layers already added.
    pub fn with_generated(mut self, files: Vec<(String, String)>) -> Self {
        self.layers.push(SourceLayer::Generated(std::sync::Arc::new(files)));
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
                SourceLayer::Embedded(_) | SourceLayer::Generated(_) => None,
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
                SourceLayer::Generated(t) => format!("{} generated files", t.len()),
            })
            .collect();
        if parts.is_empty() { "no layers".to_string() } else { parts.join(", ") }
    }

    /// The text of `relative` from the first layer that has it. The name must stay inside the
    /// roots ([`check_shader_name`]); on disk, a link that leads out of its root is refused too.
    pub fn read(&self, relative: &str) -> Result<(SourceFile, String), ShaderSourceError> {
        check_shader_name(relative)
            .map_err(|reason| ShaderSourceError::OutsideRoots { file: relative.into(), reason })?;
        for layer in &self.layers {
            match layer {
                SourceLayer::Disk(root) => {
                    let path = root.join(relative);
                    if path.is_file() {
                        let inside = match (root.canonicalize(), path.canonicalize()) {
                            (Ok(r), Ok(p)) => p.starts_with(r),
                            _ => false,
                        };
                        if !inside {
                            return Err(ShaderSourceError::OutsideRoots {
                                file: relative.into(),
                                reason: "it is a link that leads out of its shader folder",
                            });
                        }
                        let text = volgraph_base::input_file::read_text(&path, "WGSL shader")
                            .map_err(|e| ShaderSourceError::Read { path: path.clone(), reason: e.to_string() })?;
                        return Ok((SourceFile { name: relative.to_string(), path: Some(path) }, text));
                    }
                }
                SourceLayer::Embedded(table) => {
                    if let Some((_, text)) = table.iter().find(|(name, _)| *name == relative) {
                        return Ok((SourceFile { name: relative.to_string(), path: None }, text.to_string()));
                    }
                }
                SourceLayer::Generated(files) => {
                    if let Some((_, text)) = files.iter().find(|(name, _)| name == relative) {
                        return Ok((SourceFile { name: relative.to_string(), path: None }, text.clone()));
                    }
                }
            }
        }
        Err(ShaderSourceError::NotFound { file: relative.to_string(), searched: self.describe() })
    }
}

/// Whether `name` may name a shader: a relative path of plain components (no root, no drive,
/// no `..` or `.`, no backslash) ending in `.wgsl` — resolved inside a shader root, as
/// librashader and web servers resolve theirs. `Err` says what is wrong.
pub fn check_shader_name(name: &str) -> Result<(), &'static str> {
    use std::path::Component;
    if name.chars().any(char::is_control) {
        return Err("the name holds control characters");
    }
    if name.contains('\\') {
        return Err("the name holds a backslash; separate folders with /");
    }
    let path = Path::new(name);
    if path.is_absolute() || name.starts_with('/') {
        return Err("an absolute path reaches outside the shader folders");
    }
    // `Path::components` drops inner `.` and empty segments; the name itself is the import's
    // identity (each file is inlined once), so it must be written one way only.
    for segment in name.split('/') {
        match segment {
            ".." => return Err("\"..\" climbs out of the shader folders"),
            "." => return Err("write the name without \"./\""),
            "" => return Err("the name has an empty folder (\"//\")"),
            _ => {}
        }
    }
    for component in path.components() {
        match component {
            Component::Normal(_) => {}
            Component::ParentDir => return Err("\"..\" climbs out of the shader folders"),
            Component::CurDir => return Err("write the name without \"./\""),
            Component::RootDir | Component::Prefix(_) => {
                return Err("an absolute path reaches outside the shader folders");
            }
        }
    }
    if !name.ends_with(".wgsl") {
        return Err("only .wgsl files are shaders");
    }
    Ok(())
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

/// Assembles `relative` from `sources`, resolving every import through the same layers, with no
/// defines (every `#if NAME` branch off).
pub fn assemble(sources: &ShaderSources, relative: &str) -> Result<ShaderSource, ShaderSourceError> {
    assemble_with(sources, relative, &BTreeSet::new())
}

/// Assembles `relative` with `defines` on: `#if NAME` branches for names in the set are kept.
pub fn assemble_with(
    sources: &ShaderSources,
    relative: &str,
    defines: &BTreeSet<String>,
) -> Result<ShaderSource, ShaderSourceError> {
    let mut out = ShaderSource { text: String::new(), files: Vec::new(), line_origins: Vec::new() };
    let mut included = BTreeSet::new();
    let mut stack = Vec::new();
    append(sources, relative, defines, &mut out, &mut included, &mut stack)?;
    out.text = number_auto_bindings(&out.text);
    Ok(out)
}

/// Binding numbers assigned from declarations: every `@binding(auto)` of the assembled module
/// (all files, imports included) gets the lowest `@group(0)` number no other declaration uses,
/// in order of appearance. volgraph binds resources by global name, so the numbers only have to
/// be distinct; a shader (or a WGSL-only pass) need not coordinate them across `#import`ed
/// files. Line structure is unchanged, so error locations stay exact.
pub fn number_auto_bindings(text: &str) -> String {
    const AUTO: &str = "@binding(auto)";
    if !text.contains(AUTO) {
        return text.to_string();
    }
    let mut used = BTreeSet::new();
    let mut rest = text;
    while let Some(at) = rest.find("@binding(") {
        let after = &rest[at + "@binding(".len()..];
        if let Some(end) = after.find(')')
            && let Ok(n) = after[..end].trim().parse::<u32>()
        {
            used.insert(n);
        }
        rest = after;
    }
    let mut out = String::with_capacity(text.len());
    let mut next = 0u32;
    let mut rest = text;
    while let Some(at) = rest.find(AUTO) {
        while used.contains(&next) {
            next += 1;
        }
        out.push_str(&rest[..at]);
        out.push_str(&format!("@binding({next})"));
        used.insert(next);
        rest = &rest[at + AUTO.len()..];
    }
    out.push_str(rest);
    out
}

/// One open `#if`: whether its current branch is kept, whether the enclosing one is, and whether
/// `#else` was seen.
struct OpenIf {
    line: usize,
    active: bool,
    parent_active: bool,
    in_else: bool,
}

/// A conditional directive on `line`, if it is one: `Some(Ok((keyword, argument)))`.
fn directive(line: &str) -> Option<(&str, &str)> {
    let t = line.trim();
    let rest = t.strip_prefix('#')?;
    let (keyword, argument) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
    matches!(keyword, "if" | "else" | "endif").then_some((keyword, argument.trim()))
}

fn append(
    sources: &ShaderSources,
    relative: &str,
    defines: &BTreeSet<String>,
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
    let mut open: Vec<OpenIf> = Vec::new();
    let malformed = |line: usize, problem: &str| ShaderSourceError::MalformedDirective {
        path: path.clone(),
        line,
        problem: problem.to_string(),
    };
    for (i, line) in text.lines().enumerate() {
        let active = open.last().is_none_or(|o| o.active);
        if let Some((keyword, argument)) = directive(line) {
            match keyword {
                "if" => {
                    let (negated, name) = match argument.strip_prefix('!') {
                        Some(n) => (true, n.trim()),
                        None => (false, argument),
                    };
                    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                        return Err(malformed(i + 1, "#if needs one NAME (letters, digits, _)"));
                    }
                    let on = defines.contains(name) != negated;
                    open.push(OpenIf { line: i + 1, active: active && on, parent_active: active, in_else: false });
                }
                "else" => match open.last_mut() {
                    Some(o) if !o.in_else => {
                        o.in_else = true;
                        o.active = o.parent_active && !o.active;
                    }
                    Some(_) => return Err(malformed(i + 1, "a second #else for one #if")),
                    None => return Err(malformed(i + 1, "#else without #if")),
                },
                _ => {
                    if open.pop().is_none() {
                        return Err(malformed(i + 1, "#endif without #if"));
                    }
                }
            }
            continue;
        }
        if !active {
            continue;
        }
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix("#import") {
            let target = rest.trim().strip_prefix('"').and_then(|r| r.strip_suffix('"'));
            match target {
                Some(t) if !t.is_empty() => append(sources, t, defines, out, included, stack)?,
                _ => return Err(ShaderSourceError::MalformedImport { path: path.clone(), line: i + 1 }),
            }
        } else {
            out.text.push_str(line);
            out.text.push('\n');
            out.line_origins.push((index, i + 1));
        }
    }
    if let Some(o) = open.last() {
        return Err(malformed(o.line, "#if without #endif"));
    }
    stack.pop();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: EmbeddedShaders = &[
        (
            "main.wgsl",
            "a\n#if SHADING\n#import \"lit.wgsl\"\nb\n#if !TRICUBIC\nc\n#else\nd\n#endif\n#else\ne\n#endif\nf\n",
        ),
        ("lit.wgsl", "lit\n"),
        ("open.wgsl", "#if X\na\n"),
        ("stray.wgsl", "a\n#endif\n"),
        ("twice.wgsl", "#if X\n#else\n#else\n#endif\n"),
    ];

    /// `@binding(auto)` takes the lowest numbers nobody declares, across imported files, and
    /// the result is valid WGSL naga accepts with distinct bindings.
    #[test]
    fn auto_bindings_get_distinct_numbers_across_imports() {
        const FILES: EmbeddedShaders = &[
            (
                "pass.wgsl",
                "#import \"lib.wgsl\"\n@group(0) @binding(auto) var<uniform> k: f32;\n@group(0) @binding(auto) var t: texture_2d<f32>;\n@compute @workgroup_size(1) fn main() { let a = k + f(); let b = textureLoad(t, vec2<i32>(0), 0); }\n",
            ),
            (
                "lib.wgsl",
                "@group(0) @binding(1) var<uniform> fixed: f32;\n@group(0) @binding(auto) var<uniform> shared_value: f32;\nfn f() -> f32 { return fixed + shared_value; }\n",
            ),
        ];
        let s = assemble(&ShaderSources::new().with_embedded(FILES), "pass.wgsl").expect("assembles");
        assert!(!s.text.contains("auto"), "{}", s.text);
        let (module, _) = crate::shader_check::parse_and_validate("pass.wgsl", &s.text).expect("valid WGSL");
        let mut numbers: Vec<(String, u32)> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| Some((g.name.clone()?, g.binding.as_ref()?.binding)))
            .collect();
        numbers.sort();
        assert_eq!(
            numbers,
            [("fixed".to_string(), 1), ("k".to_string(), 2), ("shared_value".to_string(), 0), ("t".to_string(), 3)]
        );
        assert_eq!(s.text.lines().count(), s.line_origins.len(), "lines unchanged");
    }

    fn lines(defines: &[&str]) -> Vec<String> {
        let sources = ShaderSources::new().with_embedded(TABLE);
        let defines: BTreeSet<String> = defines.iter().map(|d| d.to_string()).collect();
        let s = assemble_with(&sources, "main.wgsl", &defines).expect("assembles");
        s.text.lines().map(str::to_string).collect()
    }

    #[test]
    fn conditional_branches_follow_the_defines_and_skip_their_imports() {
        assert_eq!(lines(&[]), ["a", "e", "f"]);
        assert_eq!(lines(&["SHADING"]), ["a", "lit", "b", "c", "f"]);
        assert_eq!(lines(&["SHADING", "TRICUBIC"]), ["a", "lit", "b", "d", "f"]);
        assert_eq!(lines(&["TRICUBIC"]), ["a", "e", "f"]);
    }

    #[test]
    fn unbalanced_directives_are_located() {
        let sources = ShaderSources::new().with_embedded(TABLE);
        for (file, line, problem) in [
            ("open.wgsl", 1, "#if without #endif"),
            ("stray.wgsl", 2, "#endif without #if"),
            ("twice.wgsl", 3, "a second #else"),
        ] {
            let err = assemble(&sources, file).expect_err("malformed").to_string();
            assert!(err.contains(&format!("{file}:{line}: {problem}")), "{err}");
        }
    }

    /// Issue 19: `#import` accepted absolute paths, `..` and non-WGSL files, and the error
    /// printed the file's lines (`/etc/passwd` in the terminal). Names stay inside the roots
    /// and a file is read only when it is a `.wgsl` file there.
    #[test]
    fn imports_stay_inside_the_shader_roots() {
        let root = std::env::temp_dir().join(format!("volgraph-roots-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("shaders")).expect("temp dir");
        std::fs::write(root.join("secret.wgsl"), "SECRET LINE\n").expect("write");
        std::fs::write(root.join("shaders/notes.txt"), "SECRET LINE\n").expect("write");
        let sources = ShaderSources::new().with_disk(root.join("shaders"));
        for (target, reason) in [
            ("/etc/passwd", "an absolute path"),
            ("../secret.wgsl", "climbs out of the shader folders"),
            ("common/../../secret.wgsl", "climbs out of the shader folders"),
            ("notes.txt", "only .wgsl files are shaders"),
            ("./a.wgsl", "without \"./\""),
            ("common/./a.wgsl", "without \"./\""),
            ("common//a.wgsl", "an empty folder"),
        ] {
            std::fs::write(root.join("shaders/main.wgsl"), format!("#import \"{target}\"\n")).expect("write");
            let err = assemble(&sources, "main.wgsl").expect_err(target).to_string();
            assert!(err.contains(reason), "{target}: {err}");
            assert!(!err.contains("SECRET"), "{target}: the file's text is never shown: {err}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(root.join("secret.wgsl"), root.join("shaders/link.wgsl")).expect("symlink");
            std::fs::write(root.join("shaders/main.wgsl"), "#import \"link.wgsl\"\n").expect("write");
            let err = assemble(&sources, "main.wgsl").expect_err("a link out of the root").to_string();
            assert!(err.contains("leads out of its shader folder") && !err.contains("SECRET"), "{err}");
        }
        let _ = std::fs::remove_dir_all(&root);
    }
}
