//! Shader bindings checked at plan time, without a GPU: every scheduled pass's declared shader
//! uses ([`crate::decl::PassDecl::shaders`]) are assembled with the pass's `#if` names,
//! parsed and validated with naga, and each entry point's globals are checked against the
//! pass's ports, the system bindings and the names the node binds itself
//! ([`crate::decl::ShaderUse::extra`]) — the same rules node creation enforces
//! ([`crate::binding_rules::check_bindings`]), except storage texture formats, which depend
//! on the target formats a node picks its shader variant by. A misnamed port, a buffer bound
//! as a texture, a sampled output or an entry point the shader does not have is reported by
//! `volgraph plan` instead of at the first frame. So is a uniform block whose WGSL struct
//! disagrees with the layout the pass uploads ([`crate::decl::ShaderUse::uniforms`]).

use std::collections::{BTreeSet, HashSet};

use crate::binding_rules::port_infos;
use crate::binding_rules::{PortInfo, check_bindings};
use crate::decl::KindLookup;
use crate::declare::check_uniform_layouts;
use crate::diagnostic::{Diagnostic, Location};
use crate::plan::Plan;
use crate::reflect::reflect;
use crate::shader_check::parse_and_validate_source;
use crate::shader_source::{ShaderSources, assemble_with};

/// The binding problems of `plan`'s passes, one per pass and shader use, each naming them.
pub fn check_plan_bindings(plan: &Plan, registry: &dyn KindLookup, sources: &ShaderSources) -> Vec<Diagnostic> {
    let registry = crate::wgsl_kind::with_graph_kinds(registry, &plan.kinds);
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    for step in &plan.steps {
        // Repeat-group instances of one pass share its shaders.
        if !seen.insert(step.pass_id.clone()) {
            continue;
        }
        let Some(plugin) = registry.decl(&step.kind) else { continue };
        let ports: Vec<PortInfo> = port_infos(plan, step, &plugin.ports(&step.params));
        let wired = step.wired_ports();
        let cuts = crate::cut_effects::defines_of(&plan.features);
        let defines: BTreeSet<String> = plugin
            .shader_defines(&step.params)
            .into_iter()
            .chain(crate::cut_effects::defines_for_pass(plugin.as_ref(), &cuts))
            .map(str::to_string)
            .collect();
        for shader in plugin.shaders_wired(&step.params, &wired) {
            let problem = |message: String| {
                Diagnostic::new(Location::File, format!("pass \"{}\" ({}): {message}", step.pass_id, step.kind))
            };
            let mut defines = defines.clone();
            defines.extend(shader.defines.iter().map(|d| d.to_string()));
            let source = match assemble_with(sources, shader.file, &defines) {
                Ok(s) => s,
                Err(e) => {
                    out.push(problem(e.to_string()));
                    continue;
                }
            };
            let (module, info) = match parse_and_validate_source(shader.file, &source) {
                Ok(m) => m,
                Err(e) => {
                    out.push(problem(e));
                    continue;
                }
            };
            let reflection = match reflect(&module, &info, &[shader.entry_point]) {
                Ok(r) => r,
                Err(e) => {
                    out.push(
                        problem(format!("{} {e}", shader.file))
                            .with_help("the pass declares an entry point its shader does not have".to_string()),
                    );
                    continue;
                }
            };
            if let Err(e) = check_bindings(shader.file, &reflection.bindings, &shader.node_bindings(), &ports, false) {
                out.push(problem(e));
            }
            if let Err(e) = check_uniform_layouts(&module, &shader.uniforms) {
                out.push(problem(format!("{}: {e}", shader.file)));
            }
            if let Err(e) = plugin.check_module(&step.params, &shader, &module) {
                out.push(problem(e));
            }
        }
    }
    out
}
