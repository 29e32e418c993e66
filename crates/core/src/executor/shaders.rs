//! Shader modules: loaded through [`crate::shader_source`] (imports inlined), validated by naga
//! (for reflection and readable errors), and compiled by wgpu once per file.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use super::gpu::Gpu;
use crate::shader_source::{ShaderSource, load_shader_from};

/// A loaded shader: the wgpu module, naga's module and analysis, and the files it came from.
pub struct LoadedShader {
    /// File name under the shader root.
    pub file: String,
    /// The assembled source.
    pub source: ShaderSource,
    /// naga's IR.
    pub module: naga::Module,
    /// naga's analysis (global uses per entry point).
    pub info: naga::valid::ModuleInfo,
    /// The compiled module.
    pub wgpu: wgpu::ShaderModule,
}

/// Loads and caches shader modules by file name.
pub struct ShaderLibrary {
    roots: Vec<PathBuf>,
    cache: Mutex<HashMap<String, Arc<LoadedShader>>>,
}

/// Parses and validates WGSL with naga; the error is naga's full report with source excerpt.
pub fn parse_and_validate(file: &str, text: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(text).map_err(|e| e.emit_to_string_with_path(text, file))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string_with_path(text, file))?;
    Ok((module, info))
}

impl ShaderLibrary {
    /// A library reading from `root` (usually [`crate::shader_source::default_shader_root`]).
    pub fn new(root: PathBuf) -> Self {
        Self::with_roots(vec![root])
    }

    /// A library searching `roots` in order for every file and import (an external plugin's
    /// shader folder first, then volgraph's).
    pub fn with_roots(roots: Vec<PathBuf>) -> Self {
        Self { roots, cache: Mutex::new(HashMap::new()) }
    }

    /// The shader roots, searched in order.
    pub fn roots(&self) -> &[PathBuf] {
        &self.roots
    }

    /// Forgets every cached module (hot reload: the next [`Self::get`] reads the files again).
    pub fn clear(&self) {
        if let Ok(mut c) = self.cache.lock() {
            c.clear();
        }
    }

    /// The module for `file`, loading and compiling it on first use.
    pub fn get(&self, gpu: &Gpu, file: &str) -> Result<Arc<LoadedShader>, String> {
        if let Some(s) = self.cache.lock().ok().and_then(|c| c.get(file).cloned()) {
            return Ok(s);
        }
        let source = load_shader_from(&self.roots, file).map_err(|e| e.to_string())?;
        let (module, info) = parse_and_validate(file, &source.text)?;
        let wgpu = gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(file),
            source: wgpu::ShaderSource::Wgsl(source.text.clone().into()),
        });
        let loaded = Arc::new(LoadedShader { file: file.to_string(), source, module, info, wgpu });
        if let Ok(mut c) = self.cache.lock() {
            c.insert(file.to_string(), loaded.clone());
        }
        Ok(loaded)
    }
}
