//! volgraph's spine: the live wgpu runtime that makes a compiled plan run, and the pass-plugin
//! API's device half ([`PassPlugin::create`], [`PassNode`]). The graph format, validation, the
//! scheduler and pass declarations are the compiler's (`volgraph_compiler`, no GPU stack),
//! re-exported here under the same paths so a plugin crate depends on this crate alone. It
//! knows graphs, ports and scheduling, never a technique.
//!
//! Data flow: graph text → [`graph::parse_graph`] → [`compile::compile`] (validation, then
//! scheduling) → [`plan::Plan`] → [`runtime::Runtime::apply`] → frames submitted by the runtime.

pub use volgraph_compiler::{
    binding_rules, block, compile, cut_effects, declare, diagnostic, format, graph, param_choice, params, pass_params,
    plan, reflect, shader_check, shader_source, suggest, terminal,
};
pub mod plugin;
pub mod runtime;
pub mod wgsl_pass;

pub use compile::{CompileOptions, check_plan_bindings};
pub use diagnostic::{Diagnostic, Diagnostics, Location};
pub use format::{Precision, TargetFormat, TargetSize};
pub use params::{ParamSpec, ParamValue, Params};
pub use plan::Plan;
pub use plugin::{
    Access, KindLookup, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, Registry, Rerun, UniformLayout,
};
