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

/// Everything of a session the user edits: the graph and the transfer functions.
pub struct Workbench {
    /// The graph text, its overrides and the level of detail's step.
    pub graph: GraphEdits,
    /// The frame volume's transfer function (every TF input not bound by name) and its file.
    pub tf: TfEdits,
    /// The transfer functions bound by name or of another volume (`pet_tf` of `pet`), by
    /// input: one editor each (issue "several volumes", item 5).
    pub named_tfs: Vec<(String, TfEdits)>,
    /// The TF the editor edits: `None` the frame volume's, else the named input's.
    pub tf_target: Option<String>,
}

impl Workbench {
    /// The transfer function the editor edits.
    pub fn edited_tf(&self) -> &TfEdits {
        let named = self.tf_target.as_ref().and_then(|t| self.named_tfs.iter().find(|(n, _)| n == t));
        named.map_or(&self.tf, |(_, e)| e)
    }

    /// [`Self::edited_tf`], to change.
    pub fn edited_tf_mut(&mut self) -> &mut TfEdits {
        let at = self.tf_target.as_ref().and_then(|t| self.named_tfs.iter().position(|(n, _)| n == t));
        match at {
            Some(i) => &mut self.named_tfs[i].1,
            None => &mut self.tf,
        }
    }
}

/// Whether `a` and `b` name the same file (the same path, or the same file once resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}
