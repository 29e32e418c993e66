//! The binding rules every pass's shaders obey, shared by `volgraph plan` (no GPU) and node
//! creation in the runtime: what a port is once the plan resolved it ([`PortInfo`],
//! [`port_infos`]) and how the globals an entry point uses must match the ports, the system
//! bindings and the names a node binds itself ([`check_bindings`]).

use wgpu_types as wgpu;

use crate::decl::{Access, PortKind};
use crate::plan::{Binding, Plan, ResourceDesc, ResourceId};
use crate::reflect::{BindingKind, ReflectedBinding};

/// Names the runtime binds itself, in every pass that declares them: the frame uniforms, the
/// two samplers and the scene's environment map (`Runtime::set_environment`).
pub const SYSTEM_BINDINGS: [&str; 4] = ["frame", "linear_clamp", "nearest_clamp", "environment_map"];

/// Whether the system binding `name` filters: `linear_clamp` does; `nearest_clamp` binds as
/// non-filtering, so a shader may read any float texture through it, filterable or not (the
/// empty-space grids by texel centre, common/block_grid.wgsl); `environment_map` is an
/// `Rgba32Float` texture read with `textureLoad`, bound as unfilterable. `None` for other names.
pub fn system_sampler_filters(name: &str) -> Option<bool> {
    match name {
        "linear_clamp" => Some(true),
        "nearest_clamp" | "environment_map" => Some(false),
        _ => None,
    }
}

/// What a port of a pass is, as the runtime resolved it.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PortInfo {
    /// Port name.
    pub name: String,
    /// Read, write or modify.
    pub access: Access,
    /// Texture format, when known at build time (targets; graph inputs are filterable formats).
    pub format: Option<wgpu::TextureFormat>,
    /// A texture another pass owns (a min/max grid): bound as unfilterable float, read by texel
    /// (`textureLoad`, or `nearest_clamp` at texel centres), so 32-bit float grids need no
    /// FLOAT32_FILTERABLE. True for an Owned port
    /// whether or not it is wired (see `bound`).
    pub owned: bool,
    /// A storage buffer (counters, point lists) rather than a texture.
    pub buffer: bool,
    /// Whether the graph wires this port (optional inputs may be left unwired; a node binds a
    /// stand-in or picks a variant without it).
    pub bound: bool,
    /// The texture dimension the port binds, where its kind fixes one (targets and the TF are
    /// 2D, the volume 3D); `None` for owned resources and buffers.
    pub dim: Option<wgpu::TextureViewDimension>,
    /// An input a graph's bypass may clear to zeros for a frame (its producer left out): a
    /// node may build a variant that does without it (`RecordContext::reads_zeros`).
    pub may_read_zeros: bool,
}

/// Names a texture dimension as WGSL writes it.
fn wgsl_dim(dim: wgpu::TextureViewDimension) -> &'static str {
    match dim {
        wgpu::TextureViewDimension::D1 => "texture_1d",
        wgpu::TextureViewDimension::D2 => "texture_2d",
        wgpu::TextureViewDimension::D2Array => "texture_2d_array",
        wgpu::TextureViewDimension::Cube => "texture_cube",
        wgpu::TextureViewDimension::CubeArray => "texture_cube_array",
        wgpu::TextureViewDimension::D3 => "texture_3d",
    }
}

/// The ports of `step` as the runtime resolves them (formats from the plan's resources): what
/// a plugin's `create` sees in the runtime, also for tools that create nodes outside one.
pub fn port_infos(plan: &Plan, step: &crate::plan::Step, specs: &[crate::decl::PortSpec]) -> Vec<PortInfo> {
    step.ports
        .iter()
        .map(|bp| {
            let desc_format = |rid: ResourceId| match &plan.resources[rid].desc {
                ResourceDesc::Target { format, .. } => Some(format.wgpu()),
                ResourceDesc::Buffer { .. } | ResourceDesc::Owned(_) => None,
            };
            let format = match &bp.binding {
                Binding::Resource { id, .. } => desc_format(*id),
                Binding::History(name) => plan.history.get(name).and_then(|h| desc_format(h.source)),
                _ => specs.iter().find(|s| s.name == bp.port).and_then(|s| match &s.kind {
                    PortKind::Target { formats, .. } => formats.first().map(|f| f.wgpu()),
                    _ => None,
                }),
            };
            let desc = match &bp.binding {
                Binding::Resource { id, .. } => Some(&plan.resources[*id].desc),
                _ => None,
            };
            let declared = specs.iter().find(|s| s.name == bp.port).map(|s| &s.kind);
            let owned = matches!(desc, Some(ResourceDesc::Owned(_))) || matches!(declared, Some(PortKind::Owned(_)));
            let buffer = matches!(desc, Some(ResourceDesc::Buffer { .. }))
                || (matches!(bp.binding, Binding::Unbound)
                    && specs.iter().any(|s| s.name == bp.port && matches!(s.kind, PortKind::Buffer { .. })));
            let bound = !matches!(bp.binding, Binding::Unbound);
            let dim = match (desc, declared) {
                (Some(ResourceDesc::Target { .. }), _) => Some(wgpu::TextureViewDimension::D2),
                (Some(_), _) => None,
                (None, Some(PortKind::Target { .. })) => Some(wgpu::TextureViewDimension::D2),
                (None, Some(PortKind::TransferFunction)) => Some(wgpu::TextureViewDimension::D1),
                (None, Some(PortKind::LabelTable)) => Some(wgpu::TextureViewDimension::D2),
                (None, Some(PortKind::Volume)) => Some(wgpu::TextureViewDimension::D3),
                _ => None,
            };
            let may_read_zeros = match &bp.binding {
                Binding::Resource { id, .. } => plan.bypass.iter().any(|b| b.clears.contains(id)),
                _ => false,
            };
            PortInfo { name: bp.port.clone(), access: bp.access, format, owned, buffer, bound, dim, may_read_zeros }
        })
        .collect()
}

/// Checks the globals an entry point uses (`bindings`, reflected from `shader`) against a pass's
/// ports, the system bindings and the names the node binds itself (`extra`): every global must
/// be one of them, in `@group(0)`, a storage buffer exactly where the port is a buffer, a
/// storage texture only for an output (of the port's format when `formats` is set), and no
/// sampled output. Used when a node is created and by `volgraph plan` without a GPU.
pub fn check_bindings(
    shader: &str,
    bindings: &[ReflectedBinding],
    extra: &[&str],
    ports: &[PortInfo],
    formats: bool,
) -> Result<(), String> {
    for b in bindings {
        if b.group != 0 {
            return Err(format!(
                "{shader}: global \"{}\" is in @group({}); volgraph binds everything in @group(0)",
                b.name, b.group
            ));
        }
        if SYSTEM_BINDINGS.contains(&b.name.as_str()) || extra.contains(&b.name.as_str()) {
            continue;
        }
        let Some(p) = ports.iter().find(|p| p.name == b.name) else {
            let ports: Vec<&str> = ports.iter().map(|p| p.name.as_str()).collect();
            return Err(format!(
                "{shader}: global \"{}\" is neither a port of this pass (ports: {}) nor a system binding ({}) \
                 nor one the pass binds itself ({}); rename it to the port it stands for, or, when the node \
                 binds it itself, declare it in the pass's ShaderUse (`.uniform(..)` for a uniform block, else \
                 `.binds(&[\"{}\"])`)",
                b.name,
                ports.join(", "),
                SYSTEM_BINDINGS.join(", "),
                if extra.is_empty() { "none".to_string() } else { extra.join(", ") },
                b.name
            ));
        };
        let shader_dim = match &b.ty {
            BindingKind::Texture { dim, .. } | BindingKind::StorageTexture { dim, .. } => Some(*dim),
            _ => None,
        };
        if let (Some(have), Some(want)) = (shader_dim, p.dim)
            && have != want
        {
            return Err(format!(
                "{shader}: global \"{}\" is a {} but port \"{}\" binds a {} texture; declare it {}",
                b.name,
                wgsl_dim(have),
                b.name,
                match want {
                    wgpu::TextureViewDimension::D1 => "1D",
                    wgpu::TextureViewDimension::D3 => "3D",
                    _ => "2D",
                },
                wgsl_dim(want),
            ));
        }
        match &b.ty {
            BindingKind::Storage { read_only } => {
                if !p.buffer {
                    return Err(format!(
                        "{shader}: global \"{}\" is a storage buffer but port \"{}\" is a texture",
                        b.name, b.name
                    ));
                }
                if !*read_only && p.access == Access::Read {
                    return Err(format!(
                        "{shader}: storage buffer \"{}\" is read_write but the port is an input; declare it \
                         var<storage, read>",
                        b.name
                    ));
                }
            }
            _ if p.buffer => {
                return Err(format!(
                    "{shader}: global \"{}\" is not a storage buffer but port \"{}\" is a buffer; declare it \
                     var<storage, read> or var<storage, read_write>",
                    b.name, b.name
                ));
            }
            BindingKind::StorageTexture { format, .. } => {
                if p.access == Access::Read {
                    return Err(format!(
                        "{shader}: storage texture \"{}\" is an input port; storage textures are outputs",
                        b.name
                    ));
                }
                if formats
                    && let Some(port_format) = p.format
                    && *format != Some(port_format)
                {
                    let declared = format.map_or("an unsupported format".to_string(), |f| format!("{f:?}"));
                    return Err(format!(
                        "{shader}: storage texture \"{}\" is declared {declared} but the port's target is \
                         {port_format:?}; declare the output with the shader's format",
                        b.name
                    ));
                }
            }
            _ if p.access == Access::Write => {
                return Err(format!(
                    "{shader}: global \"{}\" samples output port \"{}\"; outputs are written, not read",
                    b.name, b.name
                ));
            }
            _ => {}
        }
    }
    Ok(())
}
