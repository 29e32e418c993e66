//! Nodes: collecting passes and repeat groups, with their ids, kinds, repeat counts and the
//! scalar values those counts read.

use std::collections::{BTreeMap, HashMap};

use super::{Checker, GroupInfo, Item, PassInfo};
use crate::compile::MAX_REPEAT_ITERATIONS;
use crate::diagnostic::{Diagnostic, Location};
use crate::graph::ast::{InputKind, NodeDoc, PassDoc, RepeatCount};
use crate::graph::locate::PassPath;
use crate::params::Params;
use crate::suggest::{comma_list, guess_then};

impl Checker<'_> {
    pub(super) fn collect_nodes(&mut self) -> Vec<Item> {
        let mut order = Vec::new();
        let mut first = HashMap::new();
        for (top, node) in self.doc.passes.iter().enumerate() {
            match node {
                NodeDoc::Pass(p) => {
                    let path = PassPath { top, body: None };
                    let idx = self.add_pass(p, path, None, &mut first);
                    order.push(Item::Pass(idx));
                }
                NodeDoc::Repeat(r) => {
                    let path = PassPath { top, body: None };
                    let gi = self.groups.len();
                    if self.claim_id(&r.id, self.loc.pass_field(path, &r.id, "id"), &mut first) {
                        self.group_by_id.insert(r.id.clone(), gi);
                    }
                    let count = self.repeat_count(&r.id, path, &r.count);
                    self.groups.push(GroupInfo {
                        id: r.id.clone(),
                        count,
                        members: Vec::new(),
                        carry: BTreeMap::new(),
                    });
                    if r.body.is_empty() {
                        self.err(
                            self.loc.pass_field(path, &r.id, "body"),
                            format!("repeat group \"{}\" has an empty body", r.id),
                            Some("add the passes of one iteration to body: [...]".to_string()),
                        );
                    }
                    if r.carry.is_empty() {
                        self.err(
                            self.loc.pass_field(path, &r.id, "carry"),
                            format!("repeat group \"{}\" carries nothing from one iteration to the next", r.id),
                            Some(
                                "add carry: {\"<name>\": (init: \"<pass>.<output>\", next: \"<body pass>.<output>\")}; \
                                 without feedback every iteration computes the same thing"
                                    .to_string(),
                            ),
                        );
                    }
                    for (i, p) in r.body.iter().enumerate() {
                        let idx = self.add_pass(p, PassPath { top, body: Some(i) }, Some(gi), &mut first);
                        self.groups[gi].members.push(idx);
                    }
                    order.push(Item::Group(gi));
                }
            }
        }
        order
    }

    /// The value of Scalar graph input `name`: the scene's (CompileOptions::scalars) or the
    /// declared default.
    pub(super) fn scalar_value(&self, name: &str) -> Option<f64> {
        match self.doc.inputs.get(name) {
            Some(InputKind::Scalar(default)) => Some(self.option_value(name).unwrap_or(*default)),
            Some(InputKind::Data(default)) => Some(self.data_value(name, *default)),
            _ => None,
        }
    }

    /// A `Data` input, normalized: the user's value or the default in data units over the
    /// scene's data range, or the scene's automatic value.
    fn data_value(&self, name: &str, default: crate::graph::ast::DataValue) -> f64 {
        use crate::graph::ast::{DATA_AUTO_ISO, DATA_HIGH, DATA_LOW, DataValue};
        let scene = |key: &str| self.options.scene.get(key).copied();
        let normalize = |v: f64| match (scene(DATA_LOW), scene(DATA_HIGH)) {
            (Some(lo), Some(hi)) if hi > lo => (v - lo) / (hi - lo),
            _ => v,
        };
        match (self.options.scalars.get(name).copied(), default) {
            (Some(v), _) | (None, DataValue::Value(v)) => normalize(v),
            (None, DataValue::Auto) => scene(DATA_AUTO_ISO).unwrap_or(0.5),
        }
    }

    /// The value the application gives `name`: the user's, else the scene's.
    fn option_value(&self, name: &str) -> Option<f64> {
        self.options.scalars.get(name).or_else(|| self.options.scene.get(name)).copied()
    }

    fn repeat_count(&mut self, id: &str, path: PassPath, count: &RepeatCount) -> u32 {
        match count {
            RepeatCount::Fixed(0) => {
                self.err(
                    self.loc.pass_field(path, id, "count"),
                    format!("repeat group \"{id}\" has count 0"),
                    Some("a repeat group runs at least once; remove the group or use Fixed(1)".to_string()),
                );
                1
            }
            RepeatCount::Fixed(n) if *n > MAX_REPEAT_ITERATIONS => {
                self.err(
                    self.loc.pass_field(path, id, "count"),
                    format!(
                        "repeat group \"{id}\" has count {n}, over the limit of {MAX_REPEAT_ITERATIONS} iterations per group"
                    ),
                    Some(format!(
                        "use at most Fixed({MAX_REPEAT_ITERATIONS}) and do more work per iteration \
                         (volgraph_compiler::compile::MAX_REPEAT_ITERATIONS)"
                    )),
                );
                1
            }
            RepeatCount::Fixed(n) => *n,
            RepeatCount::Scene { max, .. } if *max == 0 || *max > MAX_REPEAT_ITERATIONS => {
                self.err(
                    self.loc.pass_field(path, id, "count"),
                    format!(
                        "repeat group \"{id}\" has max: {max}; it must be 1..={MAX_REPEAT_ITERATIONS} \
                         (a group runs at least once, and at most {MAX_REPEAT_ITERATIONS} iterations)"
                    ),
                    Some(format!("write max: N with 1 <= N <= {MAX_REPEAT_ITERATIONS}, or leave it out (default 256)")),
                );
                1
            }
            RepeatCount::Scene { name, divide_by, divide_by_input, divide_by_inputs, max } => {
                let mut divisor = *divide_by;
                for input in divide_by_input.iter().chain(divide_by_inputs) {
                    match self.scalar_value(input) {
                        Some(v) => divisor *= v,
                        None => {
                            self.err(
                                self.loc.pass_field(path, id, "count"),
                                format!(
                                    "repeat group \"{id}\" divides by \"{input}\", which is not a Scalar graph input"
                                ),
                                Some(format!("declare inputs: {{\"{input}\": Scalar(<default>)}}")),
                            );
                            return 1;
                        }
                    }
                }
                let divide_by = &divisor;
                let by_inputs: Vec<&String> = divide_by_input.iter().chain(divide_by_inputs).collect();
                let value = self.option_value(name).or_else(|| match self.doc.inputs.get(name) {
                    Some(InputKind::Scalar(v)) => Some(*v),
                    _ => None,
                });
                let Some(value) = value else {
                    let mut known: Vec<&str> = self
                        .doc
                        .inputs
                        .iter()
                        .filter(|(_, k)| matches!(k, InputKind::Scalar(_)))
                        .map(|(n, _)| n.as_str())
                        .collect();
                    known.extend(self.options.scalars.keys().map(String::as_str));
                    known.extend(self.options.scene.keys().map(String::as_str));
                    let mut help = format!(
                        "declare inputs: {{\"{name}\": Scalar(<default>)}}; known scalars: {}",
                        comma_list(&known)
                    );
                    help = guess_then(name, known.iter().copied(), "", help);
                    self.err(
                        self.loc.pass_field(path, id, "count"),
                        format!("repeat group \"{id}\" counts iterations from \"{name}\", which is neither a Scalar graph input nor a scene value"),
                        Some(help),
                    );
                    return 1;
                };
                if !divide_by.is_finite() || *divide_by <= 0.0 || !value.is_finite() || value < 0.0 {
                    self.err(
                        self.loc.pass_field(path, id, "count"),
                        format!("repeat group \"{id}\" divides \"{name}\" ({value}) by {divide_by}"),
                        Some(format!(
                            "divide_by must be a positive number and \"{name}\" a finite length of zero or more (a \
                             negative ray length would silently run one iteration)"
                        )),
                    );
                    return 1;
                }
                let wanted = (value / divide_by).ceil().max(1.0);
                if wanted > *max as f64 {
                    let by = if by_inputs.is_empty() {
                        divide_by.to_string()
                    } else {
                        let names: Vec<String> = by_inputs.iter().map(|i| format!("\"{i}\"")).collect();
                        format!("{} ({divide_by})", names.join(" × "))
                    };
                    self.warnings.push(
                        Diagnostic::new(
                            self.loc.pass_field(path, id, "count"),
                            format!(
                                "repeat group \"{id}\" needs {wanted} iterations (\"{name}\" = {value} divided by {by}) \
                                 but is capped at max: {max}; the work past iteration {max} is not done"
                            ),
                        )
                        .with_help(format!(
                            "raise max (up to {MAX_REPEAT_ITERATIONS}) or do more per iteration (a larger divisor)"
                        )),
                    );
                }
                wanted.min(*max as f64) as u32
            }
        }
    }

    fn add_pass(
        &mut self,
        p: &PassDoc,
        path: PassPath,
        group: Option<usize>,
        first: &mut HashMap<String, Location>,
    ) -> usize {
        let idx = self.passes.len();
        if self.claim_id(&p.id, self.loc.pass_field(path, &p.id, "id"), first) {
            self.pass_by_id.insert(p.id.clone(), idx);
        }
        let plugin = self.registry.decl(&p.kind);
        let mut info = PassInfo {
            id: p.id.clone(),
            kind: p.kind.clone(),
            path,
            group,
            plugin: plugin.clone(),
            params: Params::default(),
            ports: Vec::new(),
            outputs: BTreeMap::new(),
            inputs: BTreeMap::new(),
            enabled: true,
            needs: p.when.clone(),
            when_count: p.when.len(),
            otherwise: BTreeMap::new(),
        };
        let Some(plugin) = plugin else {
            let kinds = self.registry.kind_names();
            let mut help = format!(
                "known kinds: {}; a kind written in Rust by another crate (such as examples/radiology's \"mip\") \
                 is known only to that crate's program, which registers it (docs/writing_a_pass.md), and a WGSL-only \
                 kind is declared in the graph's kinds: block",
                comma_list(&kinds)
            );
            help = guess_then(&p.kind, kinds.iter().copied(), "", help);
            self.err(
                self.loc.pass_field(path, &p.id, "kind"),
                format!("pass \"{}\" has unknown kind \"{}\"", p.id, p.kind),
                Some(help),
            );
            self.passes.push(info);
            return idx;
        };
        let errors_before = self.diags.len();
        info.params = self.check_params(p, path, plugin.as_ref());
        let params_ok = self.diags.len() == errors_before;
        info.ports = plugin.ports(&info.params);
        for f in plugin.features() {
            if !info.needs.iter().any(|n| n == f) {
                info.needs.push(f.to_string());
            }
        }
        info.enabled = info.needs.iter().all(|f| self.options.features.contains(f));
        // A parameter that picks the ports (`fusion`, `overlay`) and was refused leaves them at
        // its default: the wiring's errors would only echo the parameter's.
        if params_ok {
            self.check_port_names(p, path, &info);
        }
        info.outputs = self.output_descs(p, path, &info);
        self.passes.push(info);
        idx
    }
}
