//! volgraph's spine: the RON graph format, validation with located diagnostics, the scheduler
//! that orders passes, culls what no output needs and pools transient targets, the pass-plugin
//! API, and the live wgpu runtime. It knows graphs, ports and scheduling, never a technique.
//!
//! Data flow: graph text → [`graph::parse_graph`] → [`compile::compile`] (validation, then
//! scheduling) → [`plan::Plan`] → [`runtime::Runtime::apply`] → frames submitted by the runtime.

pub mod compile;
pub mod declare;
pub mod diagnostic;
pub mod format;
pub mod graph;
pub mod params;
pub mod plan;
mod plan_dot;
pub mod plugin;
pub mod runtime;
pub mod shader_source;
pub mod suggest;
pub mod terminal;
pub mod wgsl_pass;

pub use compile::{CompileOptions, check_plan_bindings, compile};
pub use diagnostic::{Diagnostic, Diagnostics, Location};
pub use format::{Precision, TargetFormat, TargetSize};
pub use params::{ParamSpec, ParamValue, Params};
pub use plan::Plan;
pub use plugin::{Access, PassNode, PassPlugin, PortKind, PortSpec, Registry, Rerun};
