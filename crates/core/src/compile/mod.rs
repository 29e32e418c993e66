//! Compiling a graph: a pure function of (graph text, registry, viewport, scene features,
//! scene values) → [`Plan`], cheap enough to rerun on every keystroke of a hot-reloading
//! viewer. [`check`] validates and resolves every reference, reporting all problems at once;
//! [`schedule`] unrolls repeat groups, orders the passes, culls what no output needs and pools
//! transient targets by descriptor across non-overlapping lifetimes.

mod check;
mod schedule;

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use crate::diagnostic::Diagnostics;
use crate::plan::Plan;
use crate::plugin::Registry;

/// What a graph is compiled for.
#[derive(Clone, Debug)]
pub struct CompileOptions {
    /// Viewport in pixels.
    pub viewport: (u32, u32),
    /// Scene features that are on (`"shading"`, `"antialias"`, ...).
    pub features: BTreeSet<String>,
    /// Scene values overriding graph `Scalar` inputs and feeding repeat counts.
    pub scalars: BTreeMap<String, f64>,
    /// Parameter values overriding the graph file's, keyed `"<pass id>.<param>"` (benchmark
    /// sweeps, viewer sliders). Checked like values written in the file.
    pub param_overrides: BTreeMap<String, ron::Value>,
}

impl Default for CompileOptions {
    fn default() -> Self {
        Self {
            viewport: (256, 256),
            features: BTreeSet::new(),
            scalars: BTreeMap::new(),
            param_overrides: BTreeMap::new(),
        }
    }
}

impl CompileOptions {
    /// Options for a viewport with no features.
    pub fn new(width: u32, height: u32) -> Self {
        Self { viewport: (width, height), ..Self::default() }
    }

    /// Adds features.
    pub fn with_features<S: Into<String>>(mut self, features: impl IntoIterator<Item = S>) -> Self {
        self.features.extend(features.into_iter().map(Into::into));
        self
    }

    /// Overrides parameter `param` of pass `pass`.
    pub fn with_param(mut self, pass: &str, param: &str, value: impl Into<ron::Value>) -> Self {
        self.param_overrides.insert(format!("{pass}.{param}"), value.into());
        self
    }

    /// Sets a scene value.
    pub fn with_scalar(mut self, name: &str, value: f64) -> Self {
        self.scalars.insert(name.to_string(), value);
        self
    }
}

/// Compiles graph text named `file` (used in messages) into a plan.
pub fn compile(file: &str, source: &str, registry: &Registry, options: &CompileOptions) -> Result<Plan, Diagnostics> {
    let fail = |items| Diagnostics { file: file.to_string(), text: Arc::from(source), items };
    let doc = crate::graph::parse_graph(source).map_err(|d| fail(vec![d]))?;
    let checked = check::check(&doc, source, registry, options).map_err(fail)?;
    schedule::schedule(&doc, checked, options).map_err(fail)
}
