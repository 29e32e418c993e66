//! Pass kinds implemented by a WGSL file alone, declared in a graph's `kinds:` block
//! ([`crate::graph::ast::WgslKindDoc`]). [`with_graph_kinds`] puts a [`WgslKind`] declaration
//! for each beside the registry's kinds, so the compiler checks and schedules such a pass like a
//! built-in; the runtime (`volgraph_core`) creates, times and hot-reloads it like one.

use std::collections::{BTreeMap, HashSet};
use std::sync::{Arc, Mutex, OnceLock};

use crate::decl::{KindLookup, PassDecl, PortKind, PortSpec, ShaderUse};
use crate::diagnostic::{Diagnostic, Location};
use crate::graph::ast::{WgslForm, WgslInput, WgslKindDoc};
use crate::params::{ParamSpec, Params};

/// A string that lives as long as the program. Plugin declarations are `&'static str`; names a
/// graph declares are interned once each, so reloading a graph does not grow memory.
pub fn intern(s: &str) -> &'static str {
    static STRINGS: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut set = STRINGS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some(found) = set.get(s) {
        return found;
    }
    let leaked: &'static str = Box::leak(s.to_string().into_boxed_str());
    set.insert(leaked);
    leaked
}

/// Problems with a graph's `kinds:` block, each naming the kind and field with the fix.
pub fn check_kinds(kinds: &BTreeMap<String, WgslKindDoc>, registry: &dyn KindLookup) -> Vec<Diagnostic> {
    check_kinds_in(kinds, registry, "")
}

/// [`check_kinds`] for the graph text `source`: each problem points at the field's line and
/// column (the kind's name where no one field is to blame).
pub fn check_kinds_in(
    kinds: &BTreeMap<String, WgslKindDoc>,
    registry: &dyn KindLookup,
    source: &str,
) -> Vec<Diagnostic> {
    let locator = crate::graph::locate::Locator::new(source);
    let mut out = Vec::new();
    let mut err = |kind: &str, field: &str, message: String, help: &str| {
        let at = match field {
            "" => locator.top_entry("kinds", kind, true),
            f => locator.top_entry_field("kinds", kind, f),
        };
        let at = match at {
            Location::Field { .. } => Location::File,
            span => span,
        };
        out.push(Diagnostic::new(at, format!("kind \"{kind}\": {message}")).with_help(help.to_string()));
    };
    for (name, k) in kinds {
        if registry.decl(name).is_some() {
            err(name, "", "is already a registered pass kind".into(), "give the WGSL kind a name of its own");
        }
        if !k.shader.ends_with(".wgsl") {
            err(
                name,
                "shader",
                format!("shader \"{}\" is not a .wgsl file", k.shader),
                "name the WGSL file, e.g. \"my_pass.wgsl\"",
            );
        } else if let Err(reason) = crate::shader_source::check_shader_name(&k.shader) {
            err(
                name,
                "shader",
                format!("shader \"{}\": {reason}", k.shader),
                "name the file relative to the graph's shaders/ folder, e.g. \"my_pass.wgsl\"",
            );
        }
        if k.outputs.is_empty() {
            err(
                name,
                "outputs",
                "declares no outputs".into(),
                "add outputs: {\"out\": Rgba16Float} (the storage texture it writes)",
            );
        }
        if k.form == WgslForm::Fragment && k.outputs.values().any(|f| matches!(f, crate::TargetFormat::Depth32Float)) {
            err(name, "form", "a fragment-form kind writes colour outputs only".into(), "declare colour formats");
        }
        if k.workgroup.0 == 0 || k.workgroup.1 == 0 || u64::from(k.workgroup.0) * u64::from(k.workgroup.1) > 1024 {
            err(
                name,
                "workgroup",
                format!("workgroup {:?} is not a valid workgroup size", k.workgroup),
                "use the shader's @workgroup_size(x, y), e.g. (8, 8)",
            );
        }
        let mut seen = HashSet::new();
        for p in &k.params {
            if !seen.insert(p.name.as_str()) {
                err(
                    name,
                    "params",
                    format!("parameter \"{}\" is declared twice", p.name),
                    "give each parameter its own name",
                );
            }
            if [p.min, p.default, p.max].iter().any(|v| !v.is_finite() || v.abs() > f32::MAX as f64) {
                err(
                    name,
                    "params",
                    format!("parameter \"{}\": min, default and max must be finite 32-bit floats", p.name),
                    "the shader reads them as f32 (at most ±3.4e38)",
                );
            } else if !(p.min <= p.default && p.default <= p.max) {
                err(
                    name,
                    "params",
                    format!("parameter \"{}\": default {} is outside [{}, {}]", p.name, p.default, p.min, p.max),
                    "make min <= default <= max",
                );
            }
            if k.inputs.contains_key(&p.name) || k.outputs.contains_key(&p.name) || p.name == "params" {
                err(name, "params", format!("parameter \"{}\" has the name of a port", p.name), "rename the parameter");
            }
        }
        for port in k.inputs.keys().filter(|p| k.outputs.contains_key(*p)) {
            err(name, "outputs", format!("\"{port}\" is both an input and an output"), "name the output differently");
        }
    }
    out
}

/// `registry` with a [`WgslKind`] for each WGSL-only kind of `kinds` added (a graph's own kinds
/// win over nothing: [`check_kinds`] refuses a name the registry already has).
pub fn with_graph_kinds<'a>(registry: &'a dyn KindLookup, kinds: &BTreeMap<String, WgslKindDoc>) -> GraphKinds<'a> {
    let own = kinds.iter().map(|(name, doc)| (intern(name), Arc::new(WgslKind::new(name, doc.clone())))).collect();
    GraphKinds { registry, own }
}

/// A registry's kinds and one graph's WGSL-only kinds ([`with_graph_kinds`]).
pub struct GraphKinds<'a> {
    registry: &'a dyn KindLookup,
    own: BTreeMap<&'static str, Arc<WgslKind>>,
}

impl KindLookup for GraphKinds<'_> {
    fn decl(&self, kind: &str) -> Option<Arc<dyn PassDecl>> {
        match self.own.get(kind) {
            Some(k) => Some(Arc::clone(k) as Arc<dyn PassDecl>),
            None => self.registry.decl(kind),
        }
    }

    fn kind_names(&self) -> Vec<&'static str> {
        let mut names = self.registry.kind_names();
        names.extend(self.own.keys().copied());
        names.sort_unstable();
        names.dedup();
        names
    }
}

/// The declaration of one WGSL-only kind.
#[derive(Clone, Debug)]
pub struct WgslKind {
    kind: &'static str,
    doc: WgslKindDoc,
}

impl WgslKind {
    /// The kind `name` as `doc` declares it.
    pub fn new(name: &str, doc: WgslKindDoc) -> Self {
        Self { kind: intern(name), doc }
    }

    /// What the graph declared.
    pub fn doc(&self) -> &WgslKindDoc {
        &self.doc
    }

    /// Checks a module against the declaration ([`PassDecl::check_module`]).
    pub fn check_module_against(&self, module: &naga::Module) -> Result<(), String> {
        check_module_against(&self.doc, module)
    }

    /// Bytes of the `params` uniform block.
    pub fn param_block_size(&self) -> u64 {
        param_block_size(self.doc.params.len())
    }

    /// The parameter values as the shader's `Params` struct: one f32 each, in declaration order.
    pub fn param_block(&self, params: &Params) -> Vec<u8> {
        param_block(&self.doc, params)
    }

    /// The first declared output, which sizes a compute dispatch.
    pub fn first_output(&self) -> &'static str {
        self.doc.outputs.keys().next().map(|n| intern(n)).unwrap_or("out")
    }
}

/// Float formats a target input may have.
const READABLE: [crate::TargetFormat; 4] = [
    crate::TargetFormat::Rgba16Float,
    crate::TargetFormat::Rgba32Float,
    crate::TargetFormat::Rgba8Unorm,
    crate::TargetFormat::R32Float,
];

impl PassDecl for WgslKind {
    fn kind(&self) -> &'static str {
        self.kind
    }

    fn summary(&self) -> &'static str {
        if self.doc.summary.is_empty() {
            intern(&format!("WGSL-only pass ({})", self.doc.shader))
        } else {
            intern(&self.doc.summary)
        }
    }

    fn params(&self) -> Vec<ParamSpec> {
        self.doc
            .params
            .iter()
            .map(|p| ParamSpec::float(intern(&p.name), p.default, p.min, p.max, intern(&p.doc)))
            .collect()
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        let mut ports: Vec<PortSpec> = self
            .doc
            .inputs
            .iter()
            .map(|(name, input)| {
                let kind = match input {
                    WgslInput::Target => PortKind::target(&READABLE),
                    WgslInput::Volume => PortKind::Volume,
                    WgslInput::TransferFunction => PortKind::TransferFunction,
                };
                PortSpec::read(intern(name), kind)
            })
            .collect();
        ports.extend(
            self.doc.outputs.iter().map(|(name, format)| PortSpec::write(intern(name), PortKind::target(&[*format]))),
        );
        ports
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        let extra: &'static [&'static str] = if self.doc.params.is_empty() { &[] } else { &["params"] };
        vec![ShaderUse::new(intern(&self.doc.shader), intern(self.doc.entry_point())).binds(extra)]
    }

    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }

    fn check_module(&self, _params: &Params, _shader: &ShaderUse, module: &naga::Module) -> Result<(), String> {
        check_module_against(&self.doc, module)
    }
}

/// What a WGSL-only kind's declaration promises about its shader, checked against the module:
/// a compute entry point's `@workgroup_size` is the declared `workgroup` (the dispatch is sized
/// by it: a smaller one writes a fraction of the image), and the `params` uniform is a struct
/// of one `f32` per declared parameter with the same names in the same order (the block is
/// filled by position: a swapped or misnamed member would read another parameter's value).
fn check_module_against(doc: &WgslKindDoc, module: &naga::Module) -> Result<(), String> {
    let file = &doc.shader;
    if doc.form == WgslForm::Compute
        && let Some(entry) = module.entry_points.iter().find(|e| e.name == doc.entry_point())
        && entry.workgroup_size_overrides.is_none()
    {
        let [x, y, z] = entry.workgroup_size;
        if (x, y, z) != (doc.workgroup.0, doc.workgroup.1, 1) {
            return Err(format!(
                "{file}: {} has @workgroup_size({x}, {y}, {z}) but the kind declares workgroup: ({}, {}); \
                 write workgroup: ({x}, {y}) (a 2D size, z = 1)",
                doc.entry_point(),
                doc.workgroup.0,
                doc.workgroup.1
            ));
        }
    }
    let params = module.global_variables.iter().find(|(_, g)| g.name.as_deref() == Some("params"));
    let Some((_, global)) = params else { return Ok(()) };
    let declared: Vec<&str> = doc.params.iter().map(|p| p.name.as_str()).collect();
    let naga::TypeInner::Struct { members, span } = &module.types[global.ty].inner else {
        return Err(format!(
            "{file}: global \"params\" is not a struct; declare struct Params {{ {} }}",
            declared.iter().map(|n| format!("{n}: f32")).collect::<Vec<_>>().join(", ")
        ));
    };
    let names: Vec<&str> = members.iter().map(|m| m.name.as_deref().unwrap_or("")).collect();
    let all_f32 = members.iter().all(|m| {
        matches!(
            module.types[m.ty].inner,
            naga::TypeInner::Scalar(naga::Scalar { kind: naga::ScalarKind::Float, width: 4 })
        )
    });
    // The declared parameters first, in order; after them only padding members (`_pad…`).
    let padding = |n: &&str| n.starts_with('_');
    let named_ok = names.len() >= declared.len()
        && names[..declared.len()] == declared[..]
        && names[declared.len()..].iter().all(padding);
    if !named_ok || !all_f32 {
        return Err(format!(
            "{file}: the \"params\" struct has members ({}) but the kind declares the parameters ({}); \
             the block is filled by position, one f32 each: declare struct Params {{ {} }} (members \
             named _pad… may follow as padding)",
            members
                .iter()
                .map(|m| format!("{}: {}", m.name.as_deref().unwrap_or("?"), type_name(module, m.ty)))
                .collect::<Vec<_>>()
                .join(", "),
            declared.join(", "),
            declared.iter().map(|n| format!("{n}: f32")).collect::<Vec<_>>().join(", ")
        ));
    }
    let block = param_block_size(doc.params.len());
    if u64::from(*span) > block {
        return Err(format!(
            "{file}: the \"params\" struct is {span} bytes but the block volgraph fills for {} parameters is {block}; \
             remove padding members past {block} bytes",
            doc.params.len()
        ));
    }
    Ok(())
}

/// A short WGSL-like name of a type, for messages.
fn type_name(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let t = &module.types[ty];
    if let Some(name) = &t.name {
        return name.clone();
    }
    match &t.inner {
        naga::TypeInner::Scalar(s) => match (s.kind, s.width) {
            (naga::ScalarKind::Float, 4) => "f32".into(),
            (naga::ScalarKind::Float, 2) => "f16".into(),
            (naga::ScalarKind::Sint, 4) => "i32".into(),
            (naga::ScalarKind::Uint, 4) => "u32".into(),
            (naga::ScalarKind::Bool, _) => "bool".into(),
            _ => "a scalar".into(),
        },
        naga::TypeInner::Vector { size, scalar } => {
            format!("vec{}<{}>", *size as u8, if scalar.kind == naga::ScalarKind::Float { "f32" } else { "…" })
        }
        _ => "a compound type".into(),
    }
}

/// Bytes of the uniform block of `n` f32 parameters (a multiple of 16).
fn param_block_size(n: usize) -> u64 {
    ((4 * n as u64).div_ceil(16) * 16).max(16)
}

/// The parameter values as the shader's `Params` struct: one f32 each, in declaration order.
fn param_block(doc: &WgslKindDoc, params: &Params) -> Vec<u8> {
    let mut bytes = vec![0u8; param_block_size(doc.params.len()) as usize];
    for (i, p) in doc.params.iter().enumerate() {
        bytes[4 * i..4 * i + 4].copy_from_slice(&(params.float(&p.name) as f32).to_le_bytes());
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> BTreeMap<String, WgslKindDoc> {
        ron::from_str(text).expect("parses")
    }

    /// Each mistake in a `kinds:` block is reported with the kind, the field and the fix.
    #[test]
    fn bad_declarations_name_the_kind_and_the_fix() {
        let bad = kinds(
            r#"{
                "blur": WgslKind(shader: "blur.glsl", outputs: {}, workgroup: (0, 8),
                    inputs: {"color": Target},
                    params: [(name: "r", default: 9.0, min: 0.0, max: 4.0),
                             (name: "r", default: 1.0, min: 0.0, max: 4.0),
                             (name: "color", default: 1.0, min: 0.0, max: 4.0)]),
            }"#,
        );
        let mut registry = crate::decl::Kinds::new();
        registry.register(WgslKind::new("present", bad["blur"].clone()));
        let clash = kinds(r#"{"present": WgslKind(shader: "p.wgsl", outputs: {"out": Rgba16Float})}"#);
        let messages: Vec<String> = check_kinds(&bad, &registry)
            .into_iter()
            .chain(check_kinds(&clash, &registry))
            .map(|d| format!("{} / {}", d.message, d.help.unwrap_or_default()))
            .collect();
        let all = messages.join("\n");
        for expected in [
            "kind \"blur\": shader \"blur.glsl\" is not a .wgsl file",
            "kind \"blur\": declares no outputs",
            "kind \"blur\": workgroup (0, 8) is not a valid workgroup size",
            "kind \"blur\": parameter \"r\": default 9 is outside [0, 4]",
            "kind \"blur\": parameter \"r\" is declared twice",
            "kind \"blur\": parameter \"color\" has the name of a port",
            "kind \"present\": is already a registered pass kind",
        ] {
            assert!(all.contains(expected), "missing {expected:?} in\n{all}");
        }
    }

    /// The parameter block: one f32 per parameter in declaration order, padded to 16 bytes.
    #[test]
    fn the_parameter_block_follows_the_declaration_order() {
        let doc = &kinds(
            r#"{"k": WgslKind(shader: "k.wgsl", outputs: {"out": Rgba16Float},
                params: [(name: "b", default: 2.0, min: 0.0, max: 9.0), (name: "a", default: 1.0, min: 0.0, max: 9.0)])}"#,
        )["k"];
        let plugin = WgslKind::new("k", doc.clone());
        let params = Params::defaults(&plugin.params());
        let block = param_block(doc, &params);
        assert_eq!(block.len(), 16);
        assert_eq!(&block[0..4], &2.0f32.to_le_bytes());
        assert_eq!(&block[4..8], &1.0f32.to_le_bytes());
    }

    /// Issue 19: a WGSL-only kind's `shader:` could be absolute or climb out with `..`, a
    /// workgroup of 65536 × 65536 overflowed u32, and a parameter beyond f32 became inf.
    #[test]
    fn shader_paths_workgroups_and_parameters_are_bounded() {
        let registry = crate::decl::Kinds::new();
        let text = r#"{
            "a": WgslKind(shader: "/etc/a.wgsl", outputs: {"out": Rgba16Float}),
            "b": WgslKind(shader: "../../b.wgsl", outputs: {"out": Rgba16Float}, workgroup: (65536, 65536)),
            "c": WgslKind(shader: "c.wgsl", outputs: {"out": Rgba16Float},
                params: [(name: "k", default: 1e39, min: 0.0, max: 1e40)]),
        }"#;
        let all: Vec<String> = check_kinds(&kinds(text), &registry).into_iter().map(|d| d.message).collect();
        let all = all.join("\n");
        for expected in [
            "kind \"a\": shader \"/etc/a.wgsl\": an absolute path reaches outside the shader folders",
            "kind \"b\": shader \"../../b.wgsl\": \"..\" climbs out of the shader folders",
            "kind \"b\": workgroup (65536, 65536) is not a valid workgroup size",
            "kind \"c\": parameter \"k\": min, default and max must be finite 32-bit floats",
        ] {
            assert!(all.contains(expected), "missing {expected:?} in\n{all}");
        }
    }

    /// Issue 19: a shader whose `@workgroup_size` differs from the declared `workgroup` wrote
    /// part of the image; `params` members in another order than declared read each other's
    /// values. Both are errors before anything runs.
    #[test]
    fn the_module_must_match_the_declaration() {
        let doc = &kinds(
            r#"{"k": WgslKind(shader: "k.wgsl", outputs: {"out": Rgba16Float}, workgroup: (8, 8),
                params: [(name: "gain", default: 1.0, min: 0.0, max: 9.0), (name: "bias", default: 0.0, min: 0.0, max: 9.0)])}"#,
        )["k"];
        let module = |params: &str, size: &str| {
            let text = format!(
                "struct Params {{ {params} }}\n@group(0) @binding(0) var<uniform> params: Params;\n\
                 @compute @workgroup_size({size}) fn cs_main() {{ let g = params; }}"
            );
            naga::front::wgsl::parse_str(&text).expect("parses")
        };
        check_module_against(doc, &module("gain: f32, bias: f32, _pad0: f32", "8, 8")).expect("as declared");
        let err = check_module_against(doc, &module("gain: f32, bias: f32", "16, 16")).expect_err("size");
        assert!(err.contains("@workgroup_size(16, 16, 1) but the kind declares workgroup: (8, 8)"), "{err}");
        let err = check_module_against(doc, &module("bias: f32, gain: f32", "8, 8")).expect_err("order");
        assert!(
            err.contains("has members (bias: f32, gain: f32) but the kind declares the parameters (gain, bias)"),
            "{err}"
        );
        let err = check_module_against(doc, &module("gain: f32, bias: vec4<f32>", "8, 8")).expect_err("types");
        assert!(err.contains("bias: vec4<f32>"), "{err}");
    }
}
