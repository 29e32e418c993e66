//! Step widening, the level of detail's second lever: while the camera moves every pass that
//! declares a sample spacing samples `factor` times further apart, and a multipass graph's
//! segments get `factor` times longer; at factor 1 the graph's own values (and the user's
//! overrides from before) come back. Only compile options change here: the session compiles and
//! applies them, and a graph that refuses the wider step (a parameter range) keeps its own.

use std::collections::{BTreeMap, BTreeSet};

use volgraph_core::graph::ast::{InputKind, NodeDoc};
use volgraph_core::{CompileOptions, Plan};

/// The sample spacings the level of detail widens in every pass that declares one: a
/// raycaster's step, a slicer's slice distance.
const STEP_PARAMS: [&str; 2] = ["step_voxels", "slice_voxels"];

/// The parameters the level of detail widens where a graph input feeds them: the step, and a
/// multipass raycaster's segment length (Krüger & Westermann 2003 §3's M), whose pass count —
/// and so the per-pass fixed cost that dominates a small coarse image — falls with it.
const WIDENED_PARAMS: [&str; 2] = ["step_voxels", "segment_steps"];

/// What the widened step replaces: the parameter overrides and graph scalars from before it,
/// and the graph's own spacing of each pass it widens by parameter (`PASS.PARAM`, taken from
/// the plan at factor 1, so a ×2 → ×4 change widens the graph's value, not ×2's).
#[derive(Clone, Debug)]
pub struct StepBase {
    params: BTreeMap<String, ron::Value>,
    scalars: BTreeMap<String, f64>,
    steps: Vec<(String, f64)>,
}

/// The step factor now, and what it replaced while it is not 1.
#[derive(Clone, Debug, Default)]
pub struct StepWidening {
    coarse: Option<(f64, StepBase)>,
}

/// What a step factor asks of the graph.
#[derive(Debug)]
pub enum StepRequest {
    /// The step is at that factor already.
    Unchanged,
    /// There is no plan to read the graph's spacings from: the step cannot change.
    NoPlan,
    /// Compile and apply [`StepChange::options`]; [`StepWidening::applied`] once they run.
    Apply(StepChange),
}

/// Compile options with the step widened (or restored), and the state they put in place.
#[derive(Debug)]
pub struct StepChange {
    /// The options to compile.
    pub options: CompileOptions,
    factor: f64,
    base: StepBase,
}

/// The graph inputs wired into a parameter of [`WIDENED_PARAMS`] (`"step_voxels":
/// "input.NAME"`), and the ids of the passes whose `step_voxels` they feed. Widening such an
/// input, not each pass's parameter, also shortens what is computed from it — a
/// Krüger–Westermann repeat group's segment count.
pub fn step_inputs(source: &str) -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut inputs, mut passes) = (BTreeSet::new(), BTreeSet::new());
    let Ok(doc) = volgraph_core::graph::parse_graph(source) else { return (inputs, passes) };
    let all = doc.passes.iter().flat_map(|node| match node {
        NodeDoc::Pass(p) => std::slice::from_ref(p).iter(),
        NodeDoc::Repeat(r) => r.body.iter(),
    });
    for pass in all {
        for param in WIDENED_PARAMS {
            if let Some(ron::Value::String(wire)) = pass.params.get(param)
                && let Some(name) = wire.strip_prefix("input.")
            {
                inputs.insert(name.to_string());
                if param == "step_voxels" {
                    passes.insert(pass.id.clone());
                }
            }
        }
    }
    (inputs, passes)
}

impl StepWidening {
    /// The factor the step is widened by now (1: the graph's own).
    pub fn factor(&self) -> f64 {
        self.coarse.as_ref().map_or(1.0, |(f, _)| *f)
    }

    /// What widening the step of graph `source` (running `plan` under `options`) by `factor`
    /// takes: every pass's declared spacing and every input feeding one times `factor`, over the
    /// overrides from before the widening began.
    pub fn request(&self, factor: f64, source: &str, options: &CompileOptions, plan: Option<&Plan>) -> StepRequest {
        if factor == self.factor() {
            return StepRequest::Unchanged;
        }
        let (inputs, fed) = step_inputs(source);
        let base = match &self.coarse {
            Some((_, base)) => base.clone(),
            None => {
                // At factor 1: the plan holds the graph's own (or the user's) spacings.
                let Some(plan) = plan else { return StepRequest::NoPlan };
                let mut steps: Vec<(String, f64)> = Vec::new();
                for step in &plan.steps {
                    for param in STEP_PARAMS {
                        let key = format!("{}.{param}", step.pass_id);
                        let fed_by_input = param == "step_voxels" && fed.contains(&step.pass_id);
                        if step.params.declares(param)
                            && (!fed_by_input || options.param_overrides.contains_key(&key))
                            && !steps.iter().any(|(k, _)| *k == key)
                        {
                            steps.push((key, step.params.float(param)));
                        }
                    }
                }
                StepBase { params: options.param_overrides.clone(), scalars: options.scalars.clone(), steps }
            }
        };
        let mut options = options.clone();
        options.param_overrides = base.params.clone();
        options.scalars = base.scalars.clone();
        if factor != 1.0 {
            let Some(plan) = plan else { return StepRequest::NoPlan };
            for name in &inputs {
                let own = match plan.inputs.get(name) {
                    Some(InputKind::Scalar(default)) => *default,
                    _ => continue,
                };
                let step = base.scalars.get(name).copied().unwrap_or(own);
                options.scalars.insert(name.clone(), step * factor);
            }
            for (key, own) in &base.steps {
                options
                    .param_overrides
                    .insert(key.clone(), ron::Value::Number(ron::value::Number::F64((own * factor).into())));
            }
        }
        StepRequest::Apply(StepChange { options, factor, base })
    }

    /// The options of `change` run now.
    pub fn applied(&mut self, change: StepChange) {
        self.coarse = (change.factor != 1.0).then_some((change.factor, change.base));
    }

    /// The user set parameter `key` while the step is widened: kept when the widening ends, and
    /// a spacing the user sets is the new own one.
    pub fn param_set(&mut self, key: &str, value: &ron::Value) {
        if let Some((_, base)) = &mut self.coarse {
            if let (Some(entry), ron::Value::Number(n)) = (base.steps.iter_mut().find(|(k, _)| k == key), value) {
                entry.1 = n.into_f64();
            }
            base.params.insert(key.to_string(), value.clone());
        }
    }

    /// The user set graph input `name` while the step is widened: kept when the widening ends.
    pub fn scalar_set(&mut self, name: &str, value: f64) {
        if let Some((_, base)) = &mut self.coarse {
            base.scalars.insert(name.to_string(), value);
        }
    }
}
