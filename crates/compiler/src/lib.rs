//! volgraph's graph compiler: the RON graph format, validation with located diagnostics, the
//! scheduler that orders passes, culls what no output needs and pools transient targets, what a
//! pass kind declares ([`decl::PassDecl`]) and the plan-time shader binding checks. It has no
//! GPU stack (naga and wgpu-types only): compiling is a pure function that `volgraph plan`, the
//! golden-plan tests and a hot-reloading viewer run without a device. The runtime that makes a
//! plan live is `volgraph_core`.
//!
//! Data flow: graph text → [`graph::parse_graph`] → [`compile::compile`] (validation, then
//! scheduling) → [`plan::Plan`] → [`compile::check_plan_bindings`] (shaders against ports).

pub mod binding_rules;
pub mod block;
pub mod compile;
pub mod cut_effects;
pub mod decl;
pub mod declare;
pub mod diagnostic;
pub mod format;
pub mod graph;
pub mod params;
pub mod plan;
mod plan_dot;
pub mod reflect;
pub mod shader_check;
pub mod shader_source;
pub mod suggest;
pub mod terminal;
pub mod wgsl_kind;

pub use compile::{CompileOptions, check_plan_bindings, compile};
pub use decl::{Access, KindLookup, Kinds, PassDecl, PortKind, PortSpec, Rerun, ShaderUse, UniformLayout};
pub use diagnostic::{Diagnostic, Diagnostics, Location};
pub use format::{Precision, TargetFormat, TargetSize};
pub use params::{ParamSpec, ParamValue, Params};
pub use plan::Plan;
