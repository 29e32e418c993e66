//! volgraph's spine: the RON graph format, validation with located diagnostics, the scheduler
//! that orders passes, culls what no output needs and pools transient targets, the pass-plugin
//! API, and the wgpu executor. It knows graphs, ports and scheduling, never a technique.

pub mod shader_source;
