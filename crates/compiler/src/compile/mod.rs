//! Compiling a graph: a pure function of (graph text, registry, viewport, scene features,
//! scene values) → [`Plan`], cheap enough to rerun on every keystroke of a hot-reloading
//! viewer. `check` validates and resolves every reference, reporting all problems at once;
//! `schedule` unrolls repeat groups, orders the passes, culls what no output needs and pools
//! transient targets by descriptor across non-overlapping lifetimes.

mod bindings;
mod check;
mod schedule;

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use crate::decl::KindLookup;
use crate::diagnostic::Diagnostics;
use crate::plan::Plan;

/// The most iterations one repeat group may have: a bound, so that a typo such as
/// `Fixed(1000000)` is a located error rather than a hang. Krüger–Westermann's loop on a 4096-voxel
/// diagonal at half-voxel steps with M = 2 still fits.
pub const MAX_REPEAT_ITERATIONS: u32 = 4096;

/// The most pass instances a compiled plan may hold (repeat groups unrolled).
pub const MAX_PLAN_STEPS: usize = 16384;

/// What a graph is compiled for.
#[derive(Clone, Debug)]
pub struct CompileOptions {
    /// Viewport in pixels.
    pub viewport: (u32, u32),
    /// Scene features that are on (`"shading"`, `"antialias"`, ...).
    pub features: BTreeSet<String>,
    /// Values the user sets: they override graph `Scalar` inputs and feed repeat counts (a name
    /// the graph does not read is a warning).
    pub scalars: BTreeMap<String, f64>,
    /// Values derived from the scene by the runtime (the bound volume's
    /// `longest_ray_voxels`): read like `scalars`, which win over them; a graph that does not read
    /// one is not warned about it.
    pub scene: BTreeMap<String, f64>,
    /// Parameter values overriding the graph file's, keyed `"<pass id>.<param>"` (benchmark
    /// sweeps, viewer sliders). Checked like values written in the file.
    pub param_overrides: BTreeMap<String, ron::Value>,
    /// The scene's float precision: every RGBA float target (colour, accumulation and, through
    /// them, history) whose pass can write it takes this format instead of its default or
    /// declared one. `None`: the graph's formats.
    pub precision: Option<crate::format::Precision>,
}

impl Default for CompileOptions {
    fn default() -> Self {
        Self {
            viewport: (256, 256),
            features: BTreeSet::new(),
            scalars: BTreeMap::new(),
            scene: BTreeMap::new(),
            param_overrides: BTreeMap::new(),
            precision: None,
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

pub use bindings::check_plan_bindings;

/// Compiles graph text named `file` (used in messages) into a plan.
pub fn compile(
    file: &str,
    source: &str,
    registry: &dyn KindLookup,
    options: &CompileOptions,
) -> Result<Plan, Diagnostics> {
    // A UTF-8 byte-order mark (some Windows editors write one) is not part of the graph.
    let source = source.strip_prefix('\u{feff}').unwrap_or(source);
    let fail = |items| Diagnostics { file: file.to_string(), text: Arc::from(source), items };
    let doc = crate::graph::parse_graph(source).map_err(|d| fail(vec![d]))?;
    // Pass kinds the graph declares itself join the registry for this graph only.
    let extended;
    let registry: &dyn KindLookup = if doc.kinds.is_empty() {
        registry
    } else {
        let problems = crate::wgsl_kind::check_kinds_in(&doc.kinds, registry, source);
        if !problems.is_empty() {
            return Err(fail(problems));
        }
        extended = crate::wgsl_kind::with_graph_kinds(registry, &doc.kinds);
        &extended
    };
    let checked = check::check(&doc, source, registry, options).map_err(fail)?;
    let mut warnings = checked.warnings.clone();
    let mut plan = schedule::schedule(&doc, checked, options).map_err(fail)?;
    let cut_problems = passes_that_cannot_cut(&plan, registry);
    if !cut_problems.is_empty() {
        return Err(fail(cut_problems));
    }
    warnings.extend(unused_option_warnings(&plan, options));
    plan.warnings = fail(warnings);
    Ok(plan)
}

/// A scene that crops or clips (`crate::cut_effects`) needs every pass to take only the samples
/// the cuts keep: a pass that does not (`PassDecl::takes_cuts`) would draw the
/// cut-away part — a silent wrong image — so it is an error naming the pass.
fn passes_that_cannot_cut(plan: &Plan, registry: &dyn KindLookup) -> Vec<crate::diagnostic::Diagnostic> {
    use crate::diagnostic::{Diagnostic, Location};
    let cuts: Vec<&String> = plan.features.iter().filter(|f| crate::cut_effects::is_cut_feature(f)).collect();
    if cuts.is_empty() {
        return Vec::new();
    }
    let mut seen = std::collections::BTreeSet::new();
    plan.steps
        .iter()
        .filter(|s| seen.insert(s.pass_id.clone()))
        .filter(|s| registry.decl(&s.kind).is_some_and(|d| !d.takes_cuts()))
        .map(|s| {
            let names: Vec<&str> = cuts.iter().map(|f| f.as_str()).collect();
            Diagnostic::new(
                Location::File,
                format!("pass \"{}\" ({}) cannot {}: it samples the volume its own way", s.pass_id, s.kind, names.join(" or ")),
            )
            .with_help(
                "crop boxes and clip planes work with the raycasters (raycast, raycast_compute, raycast_segment, raycast_bricks) and the path tracer (path_trace); render this graph without --crop/--clip"
                    .to_string(),
            )
        })
        .collect()
}

/// Scene features and values the options set that this graph never reads: named, with a
/// "did you mean" where a known name is close. Applications that take them from a user (the
/// CLI's `--features` and `--scalar`) treat them as errors.
fn unused_option_warnings(plan: &Plan, options: &CompileOptions) -> Vec<crate::diagnostic::Diagnostic> {
    use crate::diagnostic::{Diagnostic, Location};
    use crate::suggest::{comma_list, guess_then};
    let mut out = Vec::new();
    let known: Vec<&str> = plan.known_features.iter().map(String::as_str).collect();
    for f in options.features.iter().filter(|f| !plan.known_features.contains(*f)) {
        let help = format!(
            "this graph's features are: {}",
            if known.is_empty() { "none".to_string() } else { comma_list(&known) }
        );
        out.push(
            Diagnostic::new(Location::File, format!("feature \"{f}\" is not used by graph \"{}\"", plan.name))
                .with_help(guess_then(f, known.iter().copied(), "", help)),
        );
    }
    let known: Vec<&str> = plan.known_scalars.iter().map(String::as_str).collect();
    for name in options.scalars.keys().filter(|n| !plan.known_scalars.contains(*n)) {
        let help = format!(
            "this graph's scalars are: {}",
            if known.is_empty() { "none".to_string() } else { comma_list(&known) }
        );
        out.push(
            Diagnostic::new(Location::File, format!("scalar \"{name}\" is not read by graph \"{}\"", plan.name))
                .with_help(guess_then(name, known.iter().copied(), "", help)),
        );
    }
    out
}
