//! The shader library: each module assembled once through [`crate::shader_source`] (imports
//! inlined, the files it read recorded), validated by naga (for reflection and readable errors,
//! located in the file a developer edits), compiled by wgpu, and cached until one of its files
//! changes ([`ShaderLibrary::invalidate`]).

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::gpu::Gpu;
use crate::shader_source::{ShaderSource, ShaderSources, assemble_with};
pub use volgraph_compiler::shader_check::{parse_and_validate, parse_and_validate_source};

/// A loaded shader: the wgpu module, naga's module and analysis, and the files it came from.
pub struct LoadedShader {
    /// Relative name, `raycast.wgsl`.
    pub file: String,
    /// The `#if` names it was assembled with (sorted).
    pub defines: Vec<String>,
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

/// The cache key of `file` assembled with `defines`: `raycast.wgsl` or `raycast.wgsl#SHADING,TRICUBIC`.
fn module_key(file: &str, defines: &[String]) -> String {
    if defines.is_empty() { file.to_string() } else { format!("{file}#{}", defines.join(",")) }
}

/// The file of a module key.
fn file_of_key(key: &str) -> &str {
    key.split_once('#').map_or(key, |(file, _)| file)
}

/// The compiled modules of a [`ShaderLibrary`] at one moment ([`ShaderLibrary::snapshot`]).
#[derive(Clone, Default)]
pub struct ShaderSnapshot(HashMap<String, Arc<LoadedShader>>);

/// Loads and caches shader modules by relative name and defines.
pub struct ShaderLibrary {
    sources: ShaderSources,
    cache: Mutex<HashMap<String, Arc<LoadedShader>>>,
    /// Modules invalidated and not loaded again since (a broken edit): name → the disk files
    /// they were last read from, still watched so that fixing any of them reloads the module.
    unloaded: Mutex<HashMap<String, Vec<PathBuf>>>,
}

impl ShaderLibrary {
    /// A library over `sources`.
    pub fn new(sources: ShaderSources) -> Self {
        Self { sources, cache: Mutex::new(HashMap::new()), unloaded: Mutex::new(HashMap::new()) }
    }

    /// A library reading the folder `root` only.
    pub fn from_dir(root: PathBuf) -> Self {
        Self::new(ShaderSources::new().with_disk(root))
    }

    /// Where files come from.
    pub fn sources(&self) -> &ShaderSources {
        &self.sources
    }

    /// The compiled modules now loaded: what [`Self::restore`] puts back when a shader edit that
    /// naga accepted is rejected by the GPU (the files on disk then hold the bad edit, so the
    /// last good graph must not read them again).
    pub fn snapshot(&self) -> ShaderSnapshot {
        ShaderSnapshot(self.cache.lock().map(|c| c.clone()).unwrap_or_default())
    }

    /// Puts the modules of `snapshot` back in place of what is loaded now; returns the names of
    /// the modules that differ (their pipelines must be rebuilt). The restored modules stay until
    /// one of their files changes again.
    pub fn restore(&self, snapshot: &ShaderSnapshot) -> Vec<String> {
        let Ok(mut cache) = self.cache.lock() else { return Vec::new() };
        let mut changed: Vec<String> = cache
            .iter()
            .filter(|(k, s)| snapshot.0.get(*k).is_none_or(|old| old.hash != s.hash))
            .chain(snapshot.0.iter().filter(|(k, _)| !cache.contains_key(*k)))
            .map(|(k, _)| file_of_key(k).to_string())
            .collect();
        *cache = snapshot.0.clone();
        if let Ok(mut unloaded) = self.unloaded.lock() {
            unloaded.retain(|name, _| !cache.keys().any(|k| file_of_key(k) == name));
        }
        changed.sort();
        changed.dedup();
        changed
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
        let same =
            |a: &Path, b: &Path| a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
        let touches = |files: &[PathBuf]| files.iter().any(|p| changed.iter().any(|c| same(p, c)));
        let (Ok(mut cache), Ok(mut unloaded)) = (self.cache.lock(), self.unloaded.lock()) else { return Vec::new() };
        let keys: Vec<String> =
            cache.iter().filter(|(_, s)| touches(&s.source.disk_paths())).map(|(key, _)| key.clone()).collect();
        let mut stale: Vec<String> = Vec::new();
        for key in &keys {
            if let Some(s) = cache.remove(key) {
                unloaded.insert(file_of_key(key).to_string(), s.source.disk_paths());
            }
            stale.push(file_of_key(key).to_string());
        }
        // Modules a broken edit left unloaded: a change to their files is what fixes them.
        let broken: Vec<String> =
            unloaded.iter().filter(|(n, files)| !stale.contains(n) && touches(files)).map(|(n, _)| n.clone()).collect();
        stale.extend(broken);
        stale.sort();
        stale.dedup();
        stale
    }

    /// Every disk file the loaded modules were read from, and the files of modules a broken
    /// edit left unloaded (what a watcher follows).
    pub fn watched_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = match self.cache.lock() {
            Ok(cache) => cache.values().flat_map(|s| s.source.disk_paths()).collect(),
            Err(_) => Vec::new(),
        };
        if let Ok(unloaded) = self.unloaded.lock() {
            files.extend(unloaded.values().flatten().cloned());
        }
        files.sort();
        files.dedup();
        files
    }

    /// The cached module `file` (assembled without defines), if loaded.
    pub fn cached(&self, file: &str) -> Option<Arc<LoadedShader>> {
        self.cache.lock().ok().and_then(|c| c.get(file).cloned())
    }

    /// The module for `file` without defines, loading and compiling it on first use.
    pub fn get(&self, gpu: &Gpu, file: &str) -> Result<Arc<LoadedShader>, String> {
        self.get_with(gpu, file, &[])
    }

    /// The module for `file` assembled with the `#if` names `defines` (order and repeats do not
    /// matter), loading and compiling it on first use; each define set is its own module.
    pub fn get_with(&self, gpu: &Gpu, file: &str, defines: &[&str]) -> Result<Arc<LoadedShader>, String> {
        let set: std::collections::BTreeSet<String> = defines.iter().map(|d| d.to_string()).collect();
        let defines: Vec<String> = set.iter().cloned().collect();
        let key = module_key(file, &defines);
        if let Some(s) = self.cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return Ok(s);
        }
        let source = assemble_with(&self.sources, file, &set).map_err(|e| e.to_string())?;
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
        let loaded = Arc::new(LoadedShader { file: file.to_string(), defines, source, hash, module, info, wgpu });
        if let Ok(mut c) = self.cache.lock() {
            c.insert(key, loaded.clone());
        }
        if let Ok(mut u) = self.unloaded.lock() {
            u.remove(file);
        }
        Ok(loaded)
    }
}
