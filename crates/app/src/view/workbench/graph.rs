//! The graph being worked on: its file, the text that runs, and the compile options over it —
//! the panel's parameter overrides and scalars, the scene features, the viewport, the level of
//! detail's step. Every change is a new set of options; the session compiles and applies them,
//! and only once they run does this model take them. Checking a typed assignment and writing the
//! edits back into the graph file need no device either: compiling is a pure function.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use volgraph_accel::cuts::Cuts;
use volgraph_accel::volume::Volume;
use volgraph_core::graph::ast::InputKind;
use volgraph_core::graph::edit::{SetTarget, apply as apply_edits, edit_for};
use volgraph_core::{CompileOptions, Plan, Registry, cut_effects};

use super::same_file;
use super::step::{StepRequest, StepWidening};
use crate::inputs;

/// A graph file, the text of it that runs, and the options it runs with.
pub struct GraphEdits {
    path: PathBuf,
    /// The file's name as messages show it.
    name: String,
    /// The text of the graph that is running.
    source: String,
    options: CompileOptions,
    registry: Registry,
    /// The volume's scene values (its longest ray, its value range), which every compile gets.
    scene_values: BTreeMap<String, f64>,
    step: StepWidening,
}

impl GraphEdits {
    /// The graph file `path` whose text is `source`, run with `options` over `volume`, its kinds
    /// from `registry`.
    pub fn new(path: &Path, source: String, options: CompileOptions, registry: Registry, volume: &Volume) -> Self {
        // Computed in one place, `volgraph_core::runtime::scene_values_of`.
        let mut scene_values = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(volume));
        scene_values.extend(inputs::data_scene_values(volume));
        Self {
            path: path.to_path_buf(),
            name: path.display().to_string(),
            source,
            options,
            registry,
            scene_values,
            step: StepWidening::default(),
        }
    }

    /// The volume is streamed: its box is `desc`'s (the finest level), not the coarsest level's
    /// the session holds in memory — rays are as long as the finest level's voxels count them.
    pub fn set_volume_box(&mut self, desc: &volgraph_core::runtime::VolumeDesc) {
        self.scene_values.extend(volgraph_core::runtime::scene_values_of(desc));
    }

    /// The graph file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The graph file's name, as messages show it.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The text of the graph that is running.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The options it runs with (features, scalars, parameter overrides, viewport).
    pub fn options(&self) -> &CompileOptions {
        &self.options
    }

    /// The registry (the kinds, their parameter specs).
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// Compiles `source` with `options` and the volume's scene values.
    pub fn compile(&self, source: &str, options: &CompileOptions) -> Result<Plan, volgraph_core::Diagnostics> {
        let mut options = options.clone();
        options.scene = self.scene_values.clone();
        volgraph_core::compile(&self.name, source, &self.registry, &options)
    }

    /// [`Self::compile`], with the names the user gave (features, scalars) checked against the
    /// plan; the error as the panel shows it.
    pub fn plan_for(&self, source: &str, options: &CompileOptions) -> Result<Plan, String> {
        let plan = self.compile(source, options).map_err(|d| d.to_string())?;
        crate::cli::check_user_names(&plan, options).map_err(|e| match e {
            crate::cli::CliError::Graph(d) => d.to_string(),
            crate::cli::CliError::Other(e) => e.to_string(),
        })?;
        Ok(plan)
    }

    /// The options with pass parameter `pass.param` set to `value` (a slider).
    pub fn with_param(&self, pass: &str, param: &str, value: &ron::Value) -> CompileOptions {
        let mut options = self.options.clone();
        options.param_overrides.insert(format!("{pass}.{param}"), value.clone());
        options
    }

    /// The options with scene scalar (Scalar graph input) `name` set to `value`.
    pub fn with_scalar(&self, name: &str, value: f64) -> CompileOptions {
        let mut options = self.options.clone();
        options.scalars.insert(name.to_string(), value);
        options
    }

    /// The options with scene feature `name` on or off.
    pub fn with_feature(&self, name: &str, on: bool) -> CompileOptions {
        let mut options = self.options.clone();
        if on {
            options.features.insert(name.to_string());
        } else {
            options.features.remove(name);
        }
        options
    }

    /// The options with the features of `cuts` (a crop box, clip planes) in place of the
    /// features of the cuts before.
    pub fn with_cuts(&self, cuts: &Cuts) -> CompileOptions {
        let mut options = self.options.clone();
        options.features.retain(|f| !cut_effects::is_cut_feature(f));
        options.features.extend(cut_effects::features_of(cuts));
        options
    }

    /// The options at viewport `size`.
    pub fn with_viewport(&self, size: (u32, u32)) -> CompileOptions {
        let mut options = self.options.clone();
        options.viewport = size;
        options
    }

    /// `options` (from [`Self::with_param`]) run: parameter `pass.param` is now `value`, also
    /// once the level of detail's step ends.
    pub fn param_set(&mut self, pass: &str, param: &str, value: &ron::Value, options: CompileOptions) {
        self.options = options;
        self.step.param_set(&format!("{pass}.{param}"), value);
    }

    /// `options` (from [`Self::with_scalar`]) run: scalar `name` is now `value`, also once the
    /// level of detail's step ends.
    pub fn scalar_set(&mut self, name: &str, value: f64, options: CompileOptions) {
        self.options = options;
        self.step.scalar_set(name, value);
    }

    /// `options` run now (a feature, the cuts, the viewport).
    pub fn set_options(&mut self, options: CompileOptions) {
        self.options = options;
    }

    /// `source` (the graph file's new text) runs now.
    pub fn set_source(&mut self, source: String) {
        self.source = source;
    }

    /// The panel's "set" field: `PASS.PARAM=VALUE` or `input.NAME=VALUE`, checked as `volgraph
    /// set` checks it — the graph text with the value written in must compile, so a bad value or
    /// an unknown name is refused with its located message (and a "did you mean").
    pub fn check_assignment(&self, text: &str) -> Result<(SetTarget, ron::Value), String> {
        let Some((target, value)) = text.split_once('=') else {
            return Err(format!("\"{}\": expected PASS.PARAM=VALUE or input.NAME=VALUE", text.trim()));
        };
        let target = SetTarget::parse(target.trim())?;
        let edits = edit_for(&self.source, &target, value)?;
        let edited = apply_edits(&self.source, &edits);
        // The panel's own value for this name would hide the one being checked.
        let mut options = self.options.clone();
        match &target {
            SetTarget::Param { pass, param } => options.param_overrides.remove(&format!("{pass}.{param}")),
            SetTarget::Input(name) => options.scalars.remove(name).map(ron::Value::from),
        };
        self.compile(&edited, &options).map_err(|d| d.to_string())?;
        let value = ron::from_str::<ron::Value>(value.trim()).map_err(|e| format!("{}: {e}", value.trim()))?;
        Ok((target, value))
    }

    /// What "write to graph file" writes: `PASS.PARAM=VALUE` per parameter override and
    /// `input.NAME=VALUE` per scalar that is one of the graph's `inputs` (`volgraph set`'s
    /// syntax).
    pub fn write_back_assignments(&self, inputs: &BTreeMap<String, InputKind>) -> anyhow::Result<Vec<String>> {
        let mut assignments: Vec<String> = Vec::new();
        for (key, value) in &self.options.param_overrides {
            let text = ron::to_string(value).map_err(|e| anyhow!("{key}: {e}"))?;
            assignments.push(format!("{key}={text}"));
        }
        for (name, value) in &self.options.scalars {
            if inputs.contains_key(name) {
                assignments.push(format!("input.{name}={value:?}"));
            }
        }
        Ok(assignments)
    }

    /// Writes the parameters and graph inputs changed in the panel into the graph file at their
    /// place (`volgraph set`'s code: only the values' text changes), then runs from the file: the
    /// overrides are cleared, as the file now says what they said. `inputs` are the running
    /// plan's. Returns one line per value written; an error (a built-in graph, an unwritable
    /// file) changes nothing. The level of detail's wider step must have ended first.
    pub fn write_back(&mut self, inputs: &BTreeMap<String, InputKind>) -> anyhow::Result<Vec<String>> {
        let assignments = self.write_back_assignments(inputs)?;
        if assignments.is_empty() {
            return Ok(Vec::new());
        }
        let lines =
            crate::set_cmd::run(&self.path, &assignments).map_err(|e| anyhow!("{}", crate::cli::error_text(&e)))?;
        self.source = inputs::read_graph(&self.path)?;
        self.options.param_overrides.clear();
        self.options.scalars.retain(|name, _| !inputs.contains_key(name));
        Ok(lines.lines().map(str::to_string).collect())
    }

    /// Whether files `changed` on disk ask for the graph to be reloaded: the graph file is among
    /// them and its text is not the running one (the viewer's own write-back), unless the last
    /// change `failed` (then the same text is the fix, and reloading it recovers).
    pub fn needs_reload(&self, changed: &[PathBuf], failed: bool) -> bool {
        changed.iter().any(|c| same_file(c, &self.path))
            // (Read without blocking: a FIFO swapped in for the graph must not freeze the viewer.)
            && (failed
                || volgraph_accel::input_file::read_text(&self.path, "graph file").map_or(true, |text| text != self.source))
    }

    /// The factor the level of detail's step is widened by now (1: the graph's own).
    pub fn step_factor(&self) -> f64 {
        self.step.factor()
    }

    /// What widening the step by `factor` takes of the graph running `plan`.
    pub fn step_request(&self, factor: f64, plan: Option<&Plan>) -> StepRequest {
        self.step.request(factor, &self.source, &self.options, plan)
    }

    /// The options of a [`StepRequest::Apply`] run now.
    pub fn step_applied(&mut self, change: super::step::StepChange) {
        self.options = change.options.clone();
        self.step.applied(change);
    }
}
