//! The shader library: each module assembled once through [`crate::shader_source`] (imports
//! inlined, the files it read recorded), validated by naga (for reflection and readable errors,
//! located in the file a developer edits), compiled by wgpu, and cached until one of its files
//! changes ([`ShaderLibrary::invalidate`]).

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::gpu::Gpu;
use crate::shader_source::{ShaderSource, ShaderSources, assemble};

/// A loaded shader: the wgpu module, naga's module and analysis, and the files it came from.
pub struct LoadedShader {
    /// Relative name, `raycast.wgsl`.
    pub file: String,
    /// The assembled source.
    pub source: ShaderSource,
    /// Hash of the assembled text: part of every pipeline key built from this module.
    pub hash: u64,
    /// naga's IR.
    pub module: naga::Module,
    /// naga's analysis (global uses per entry point).
    pub info: naga::valid::ModuleInfo,
    /// The compiled module.
    pub wgpu: wgpu::ShaderModule,
}

/// Loads and caches shader modules by relative name.
pub struct ShaderLibrary {
    sources: ShaderSources,
    cache: Mutex<HashMap<String, Arc<LoadedShader>>>,
}

/// `path:line:col: message` for a naga error at `location` of the assembled text, pointing at
/// the original file through the import map, followed by naga's report.
fn located(
    source: &ShaderSource,
    file: &str,
    location: Option<naga::SourceLocation>,
    message: &str,
    report: String,
) -> String {
    match location.and_then(|l| source.origin_of_line(l.line_number as usize).map(|o| (o, l.line_position))) {
        Some(((path, line), col)) => format!("{}:{line}:{col}: {message}\n{report}", path.display()),
        None => format!("{file}: {message}\n{report}"),
    }
}

/// Parses and validates WGSL with naga; the error names the original file and line (through
/// `#import`) and carries naga's full report.
pub fn parse_and_validate_source(
    file: &str,
    source: &ShaderSource,
) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let text = &source.text;
    let module = naga::front::wgsl::parse_str(text)
        .map_err(|e| located(source, file, e.location(text), e.message(), e.emit_to_string_with_path(text, file)))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| {
            located(source, file, e.location(text), &e.as_inner().to_string(), e.emit_to_string_with_path(text, file))
        })?;
    Ok((module, info))
}

/// Parses and validates WGSL text with naga (no import map); the error is naga's full report.
pub fn parse_and_validate(file: &str, text: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(text).map_err(|e| e.emit_to_string_with_path(text, file))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string_with_path(text, file))?;
    Ok((module, info))
}

impl ShaderLibrary {
    /// A library over `sources`.
    pub fn new(sources: ShaderSources) -> Self {
        Self { sources, cache: Mutex::new(HashMap::new()) }
    }

    /// A library reading the folder `root` only.
    pub fn from_dir(root: PathBuf) -> Self {
        Self::new(ShaderSources::new().with_disk(root))
    }

    /// Where files come from.
    pub fn sources(&self) -> &ShaderSources {
        &self.sources
    }

    /// Forgets every cached module (the next [`Self::get`] reads the files again).
    pub fn clear(&self) {
        if let Ok(mut c) = self.cache.lock() {
            c.clear();
        }
    }

    /// Forgets the modules built from any of `changed` (disk paths; imports count) and returns
    /// their relative names: the pipelines of exactly these modules must be rebuilt.
    pub fn invalidate(&self, changed: &[PathBuf]) -> Vec<String> {
        let same = |a: &Path, b: &Path| {
            a == b || (a.canonicalize().ok().is_some() && a.canonicalize().ok() == b.canonicalize().ok())
        };
        let Ok(mut cache) = self.cache.lock() else { return Vec::new() };
        let stale: Vec<String> = cache
            .iter()
            .filter(|(_, s)| s.source.disk_paths().iter().any(|p| changed.iter().any(|c| same(p, c))))
            .map(|(name, _)| name.clone())
            .collect();
        for name in &stale {
            cache.remove(name);
        }
        stale
    }

    /// Every disk file the cached modules were read from (what a watcher follows).
    pub fn watched_files(&self) -> Vec<PathBuf> {
        let Ok(cache) = self.cache.lock() else { return Vec::new() };
        let mut files: Vec<PathBuf> = cache.values().flat_map(|s| s.source.disk_paths()).collect();
        files.sort();
        files.dedup();
        files
    }

    /// The cached module `file`, if loaded.
    pub fn cached(&self, file: &str) -> Option<Arc<LoadedShader>> {
        self.cache.lock().ok().and_then(|c| c.get(file).cloned())
    }

    /// The module for `file`, loading and compiling it on first use.
    pub fn get(&self, gpu: &Gpu, file: &str) -> Result<Arc<LoadedShader>, String> {
        if let Some(s) = self.cached(file) {
            return Ok(s);
        }
        let source = assemble(&self.sources, file).map_err(|e| e.to_string())?;
        let (module, info) = parse_and_validate_source(file, &source)?;
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        source.text.hash(&mut hasher);
        let hash = hasher.finish();
        let wgpu = gpu
            .checked(
                || format!("compiling shader {file}"),
                || {
                    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(file),
                        source: wgpu::ShaderSource::Wgsl(source.text.clone().into()),
                    })
                },
            )
            .map_err(|e| e.to_string())?;
        let loaded = Arc::new(LoadedShader { file: file.to_string(), source, hash, module, info, wgpu });
        if let Ok(mut c) = self.cache.lock() {
            c.insert(file.to_string(), loaded.clone());
        }
        Ok(loaded)
    }
}
