//! Shader reflection with naga: which globals an entry point uses, with their group, binding
//! and type, and the names of its fragment outputs. The executor binds resources **by global
//! variable name** (a port's name, or a system name like `frame`), never by declaration order,
//! and checks at graph load that every binding has a meaning.

use naga::{AddressSpace, ImageClass, ImageDimension, TypeInner};
use wgpu_types as wgpu;

/// One resource binding an entry point uses.
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectedBinding {
    /// WGSL global name.
    pub name: String,
    /// `@group`.
    pub group: u32,
    /// `@binding`.
    pub binding: u32,
    /// What it is.
    pub ty: BindingKind,
    /// Bytes the shader reads through it: a uniform's type size (`None` for everything else).
    pub uniform_size: Option<u64>,
}

/// The kinds of bindings volgraph shaders use.
#[derive(Clone, Debug, PartialEq)]
pub enum BindingKind {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>` or `read_write`.
    Storage {
        /// True for `read`.
        read_only: bool,
    },
    /// A sampled float texture.
    Texture {
        /// `texture_2d`, `texture_3d`, ...
        dim: wgpu::TextureViewDimension,
        /// Depth textures are `texture_depth_2d`.
        depth: bool,
        /// Unsigned-integer texture (`texture_2d<u32>`).
        uint: bool,
    },
    /// A storage texture.
    StorageTexture {
        /// Its declared format.
        format: Option<wgpu::TextureFormat>,
        /// `write`, `read`, `read_write`.
        access: wgpu::StorageTextureAccess,
        /// Dimension.
        dim: wgpu::TextureViewDimension,
    },
    /// A sampler.
    Sampler {
        /// Comparison sampler.
        comparison: bool,
    },
}

/// What reflection found for a set of entry points of one module.
#[derive(Clone, Debug, Default)]
pub struct Reflection {
    /// Bindings used by any of the entry points, sorted by (group, binding).
    pub bindings: Vec<ReflectedBinding>,
    /// Fragment outputs `(name, location)`, for a fragment entry point.
    pub fragment_outputs: Vec<(String, u32)>,
    /// True when a fragment entry point can `discard` (itself or a function it calls): the
    /// fragments it runs for may leave their pixels unwritten.
    pub may_discard: bool,
}

/// Reflects `entry_points` of a parsed and validated module.
pub fn reflect(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    entry_points: &[&str],
) -> Result<Reflection, String> {
    let mut out = Reflection::default();
    for name in entry_points {
        let Some(index) = module.entry_points.iter().position(|e| e.name == *name) else {
            let names: Vec<&str> = module.entry_points.iter().map(|e| e.name.as_str()).collect();
            return Err(format!("has no entry point \"{name}\" (it has: {})", names.join(", ")));
        };
        let ep = &module.entry_points[index];
        let fi = info.get_entry_point(index);
        for (handle, var) in module.global_variables.iter() {
            if fi[handle].is_empty() {
                continue;
            }
            let Some(rb) = &var.binding else { continue };
            let var_name = var.name.clone().unwrap_or_default();
            if out.bindings.iter().any(|b| b.name == var_name) {
                continue;
            }
            let ty = binding_kind(module, var)?;
            let uniform_size = (var.space == AddressSpace::Uniform)
                .then(|| u64::from(module.types[var.ty].inner.size(module.to_ctx())));
            out.bindings.push(ReflectedBinding {
                name: var_name,
                group: rb.group,
                binding: rb.binding,
                ty,
                uniform_size,
            });
        }
        if ep.stage == naga::ShaderStage::Fragment {
            out.may_discard |= block_may_discard(module, &ep.function.body);
        }
        if ep.stage == naga::ShaderStage::Fragment
            && let Some(result) = &ep.function.result
        {
            match (&module.types[result.ty].inner, &result.binding) {
                (TypeInner::Struct { members, .. }, _) => {
                    for m in members {
                        if let Some(naga::Binding::Location { location, .. }) = m.binding {
                            out.fragment_outputs.push((m.name.clone().unwrap_or_default(), location));
                        }
                    }
                }
                (_, Some(naga::Binding::Location { location, .. })) => {
                    out.fragment_outputs.push((String::new(), *location));
                }
                _ => {}
            }
        }
    }
    out.bindings.sort_by_key(|b| (b.group, b.binding));
    Ok(out)
}

/// Whether `block`, or a function it calls, contains a `discard` (naga's `Kill`).
fn block_may_discard(module: &naga::Module, block: &naga::Block) -> bool {
    use naga::Statement;
    block.iter().any(|statement| match statement {
        Statement::Kill => true,
        Statement::Block(inner) => block_may_discard(module, inner),
        Statement::If { accept, reject, .. } => block_may_discard(module, accept) || block_may_discard(module, reject),
        Statement::Switch { cases, .. } => cases.iter().any(|c| block_may_discard(module, &c.body)),
        Statement::Loop { body, continuing, .. } => {
            block_may_discard(module, body) || block_may_discard(module, continuing)
        }
        Statement::Call { function, .. } => block_may_discard(module, &module.functions[*function].body),
        _ => false,
    })
}

fn binding_kind(module: &naga::Module, var: &naga::GlobalVariable) -> Result<BindingKind, String> {
    let name = var.name.as_deref().unwrap_or("?");
    match var.space {
        AddressSpace::Uniform => return Ok(BindingKind::Uniform),
        AddressSpace::Storage { access } => {
            return Ok(BindingKind::Storage { read_only: !access.contains(naga::StorageAccess::STORE) });
        }
        _ => {}
    }
    let inner = match &module.types[var.ty].inner {
        TypeInner::BindingArray { base, .. } => &module.types[*base].inner,
        other => other,
    };
    match inner {
        TypeInner::Sampler { comparison } => Ok(BindingKind::Sampler { comparison: *comparison }),
        TypeInner::Image { dim, arrayed, class } => {
            let dim = view_dim(*dim, *arrayed);
            match class {
                ImageClass::Sampled { kind, .. } => {
                    Ok(BindingKind::Texture { dim, depth: false, uint: matches!(kind, naga::ScalarKind::Uint) })
                }
                ImageClass::Depth { .. } => Ok(BindingKind::Texture { dim, depth: true, uint: false }),
                ImageClass::Storage { format, access } => {
                    let access = if access.contains(naga::StorageAccess::LOAD | naga::StorageAccess::STORE) {
                        wgpu::StorageTextureAccess::ReadWrite
                    } else if access.contains(naga::StorageAccess::STORE) {
                        wgpu::StorageTextureAccess::WriteOnly
                    } else {
                        wgpu::StorageTextureAccess::ReadOnly
                    };
                    Ok(BindingKind::StorageTexture { format: storage_format(*format), access, dim })
                }
                ImageClass::External => {
                    Err(format!("global \"{name}\" is an external texture, which volgraph does not bind"))
                }
            }
        }
        _ => Err(format!("global \"{name}\" has a type volgraph cannot bind")),
    }
}

fn view_dim(dim: ImageDimension, arrayed: bool) -> wgpu::TextureViewDimension {
    use wgpu::TextureViewDimension as V;
    match (dim, arrayed) {
        (ImageDimension::D1, _) => V::D1,
        (ImageDimension::D2, false) => V::D2,
        (ImageDimension::D2, true) => V::D2Array,
        (ImageDimension::D3, _) => V::D3,
        (ImageDimension::Cube, false) => V::Cube,
        (ImageDimension::Cube, true) => V::CubeArray,
    }
}

fn storage_format(f: naga::StorageFormat) -> Option<wgpu::TextureFormat> {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as T;
    Some(match f {
        S::Rgba16Float => T::Rgba16Float,
        S::Rgba32Float => T::Rgba32Float,
        S::R32Float => T::R32Float,
        S::Rg32Float => T::Rg32Float,
        S::Rgba8Unorm => T::Rgba8Unorm,
        S::R32Uint => T::R32Uint,
        S::R8Unorm => T::R8Unorm,
        _ => return None,
    })
}

/// The wgpu layout entry for a reflected binding. `filterable` says whether a sampled float
/// texture's bound format can be linearly filtered.
pub fn layout_entry(
    b: &ReflectedBinding,
    visibility: wgpu::ShaderStages,
    filterable: bool,
) -> wgpu::BindGroupLayoutEntry {
    let ty = match &b.ty {
        BindingKind::Uniform => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        BindingKind::Storage { read_only } => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: *read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        BindingKind::Texture { dim, depth, uint } => wgpu::BindingType::Texture {
            sample_type: if *depth {
                wgpu::TextureSampleType::Depth
            } else if *uint {
                wgpu::TextureSampleType::Uint
            } else {
                wgpu::TextureSampleType::Float { filterable }
            },
            view_dimension: *dim,
            multisampled: false,
        },
        BindingKind::StorageTexture { format, access, dim } => wgpu::BindingType::StorageTexture {
            access: *access,
            format: format.unwrap_or(wgpu::TextureFormat::Rgba32Float),
            view_dimension: *dim,
        },
        BindingKind::Sampler { comparison } => wgpu::BindingType::Sampler(if *comparison {
            wgpu::SamplerBindingType::Comparison
        } else if filterable {
            wgpu::SamplerBindingType::Filtering
        } else {
            wgpu::SamplerBindingType::NonFiltering
        }),
    };
    wgpu::BindGroupLayoutEntry { binding: b.binding, visibility, ty, count: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn may_discard(source: &str, entry: &str) -> bool {
        let module = naga::front::wgsl::parse_str(source).expect("parses");
        let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
            .validate(&module)
            .expect("validates");
        reflect(&module, &info, &[entry]).expect("reflects").may_discard
    }

    const SHADER: &str = r#"
        fn maybe(x: f32) { if (x < 0.5) { loop { if (x < 0.25) { discard; } break; } } }
        @fragment fn direct(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
            if (p.x < 1.0) { discard; }
            return vec4<f32>(1.0);
        }
        @fragment fn called(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
            maybe(p.x);
            return vec4<f32>(1.0);
        }
        @fragment fn never(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
            return vec4<f32>(p.x);
        }
    "#;

    /// A `discard` anywhere a fragment stage can reach (nested in a loop of a called function)
    /// means it may leave pixels unwritten.
    #[test]
    fn a_fragment_stage_that_can_discard_is_found() {
        assert!(may_discard(SHADER, "direct"));
        assert!(may_discard(SHADER, "called"));
        assert!(!may_discard(SHADER, "never"));
    }
}
