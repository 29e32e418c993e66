//! The viewer's workbench: what `volgraph view` lets the user change, as plain data that no
//! device is needed to drive. [`GraphEdits`] holds the graph text and the options over it (the
//! panel's parameter edits and scalars, features, the viewport, the level of detail's widened
//! step: `step.rs`) and writes the edits back into the graph file; [`TfEdits`] holds the transfer
//! function being edited and where it is saved; [`FramePolicy`] decides, before each frame, when
//! to lower the level of detail and when to measure the view's accuracy.
//!
//! The live session (`session.rs`) holds a [`Workbench`] beside the runtime: it asks the model
//! for the options a change needs, compiles and applies them, and tells the model once they run.
//! The window (`window.rs`) dispatches events and asks the [`FramePolicy`] what to do.

mod frame;
mod graph;
mod step;
mod tf;

#[cfg(test)]
mod tests;

use std::path::Path;

pub use frame::{FramePolicy, LodTarget, MEASURE_AFTER};
pub use graph::GraphEdits;
pub use step::{StepChange, StepRequest, StepWidening, step_inputs};
pub use tf::{HISTOGRAM_BINS, SAVED_TF, TfEdits};

/// Everything of a session the user edits: the graph and the transfer function.
pub struct Workbench {
    /// The graph text, its overrides and the level of detail's step.
    pub graph: GraphEdits,
    /// The transfer function on screen and its file.
    pub tf: TfEdits,
}

/// Whether `a` and `b` name the same file (the same path, or the same file once resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}
