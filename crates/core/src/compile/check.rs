//! Validation: every problem of a graph file, located, with a fix, all at once.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use petgraph::graph::{DiGraph, NodeIndex};

use super::{CompileOptions, MAX_REPEAT_ITERATIONS};
use crate::diagnostic::{Diagnostic, Location};
use crate::format::{TargetFormat, TargetSize};
use crate::graph::ast::{GraphDoc, HistoryInitial, InputKind, NodeDoc, PassDoc, RepeatCount};
use crate::graph::locate::{Locator, PassPath};
use crate::params::{ParamKind, ParamProblem, Params, check_param};
use crate::plugin::{Access, PassPlugin, PortKind, PortSpec, Registry, SizeRule};
use crate::suggest::{closest, comma_list, guess_then, quoted_list};

/// A resolved reference to a value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Ref {
    Input(String),
    History(String),
    Carry { group: usize, name: String },
    Output { pass: usize, port: String },
}

/// What a value is, for type checks.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ValueDesc {
    Target { format: TargetFormat, size: TargetSize },
    Buffer { bytes: u64, bytes_per_pixel: u64 },
    Owned(String),
    Volume,
    TransferFunction,
    Scalar,
}

impl ValueDesc {
    fn describe(&self) -> String {
        match self {
            ValueDesc::Target { format, size } => format!("{format} {size}"),
            ValueDesc::Buffer { .. } => "a storage buffer".to_string(),
            ValueDesc::Owned(t) => format!("a {t}"),
            ValueDesc::Volume => "the volume".to_string(),
            ValueDesc::TransferFunction => "the transfer function".to_string(),
            ValueDesc::Scalar => "a scalar".to_string(),
        }
    }
}

pub(crate) struct PassInfo {
    pub id: String,
    pub kind: String,
    pub path: PassPath,
    pub group: Option<usize>,
    pub plugin: Option<Arc<dyn PassPlugin>>,
    pub params: Params,
    pub ports: Vec<PortSpec>,
    pub outputs: BTreeMap<String, ValueDesc>,
    pub inputs: BTreeMap<String, Ref>,
    pub enabled: bool,
    pub needs: Vec<String>,
    pub otherwise: BTreeMap<String, Ref>,
}

pub(crate) struct GroupInfo {
    pub id: String,
    pub count: u32,
    pub members: Vec<usize>,
    pub carry: BTreeMap<String, (Ref, Ref)>,
}

pub(crate) enum Item {
    Pass(usize),
    Group(usize),
}

pub(crate) struct Checked {
    pub passes: Vec<PassInfo>,
    pub groups: Vec<GroupInfo>,
    pub order: Vec<Item>,
    pub outputs: BTreeMap<String, Ref>,
    pub history: BTreeMap<String, (Ref, HistoryInitial)>,
    pub inputs: BTreeMap<String, InputKind>,
    /// Problems that do not stop compiling (a repeat count capped by its max).
    pub warnings: Vec<Diagnostic>,
    /// Scene values a repeat count reads that the graph does not declare as Scalar inputs.
    pub scene_values: Vec<String>,
}

const RESERVED: [&str; 2] = ["input", "history"];

struct Checker<'a> {
    doc: &'a GraphDoc,
    source: &'a str,
    loc: Locator,
    registry: &'a Registry,
    options: &'a CompileOptions,
    diags: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    passes: Vec<PassInfo>,
    groups: Vec<GroupInfo>,
    pass_by_id: HashMap<String, usize>,
    group_by_id: HashMap<String, usize>,
}

pub(crate) fn check(
    doc: &GraphDoc,
    source: &str,
    registry: &Registry,
    options: &CompileOptions,
) -> Result<Checked, Vec<Diagnostic>> {
    let mut c = Checker {
        doc,
        source,
        loc: Locator::new(source),
        registry,
        options,
        diags: Vec::new(),
        warnings: Vec::new(),
        passes: Vec::new(),
        groups: Vec::new(),
        pass_by_id: HashMap::new(),
        group_by_id: HashMap::new(),
    };
    let order = c.collect_nodes();
    for key in options.param_overrides.keys() {
        let pass = key.split_once('.').map_or(key.as_str(), |(p, _)| p);
        if !c.pass_by_id.contains_key(pass) {
            let mut ids: Vec<&str> = c.pass_by_id.keys().map(String::as_str).collect();
            ids.sort_unstable();
            c.diags.push(
                Diagnostic::new(Location::File, format!("parameter override \"{key}\" names no pass of this graph"))
                    .with_help(format!("write \"<pass>.<param>\"; passes are: {}", comma_list(&ids))),
            );
        }
    }
    c.check_references();
    let outputs = c.check_graph_outputs();
    let history = c.check_history();
    if c.diags.is_empty() {
        c.check_cycles();
    }
    if c.diags.is_empty() {
        let scene_values = doc
            .passes
            .iter()
            .filter_map(|n| match n {
                NodeDoc::Repeat(r) => match &r.count {
                    RepeatCount::Scene { name, .. } if !doc.inputs.contains_key(name) => Some(name.clone()),
                    _ => None,
                },
                NodeDoc::Pass(_) => None,
            })
            .collect();
        Ok(Checked {
            passes: c.passes,
            groups: c.groups,
            order,
            outputs,
            history,
            inputs: doc.inputs.clone(),
            warnings: c.warnings,
            scene_values,
        })
    } else {
        Err(c.diags)
    }
}

impl Checker<'_> {
    fn err(&mut self, location: Location, message: String, help: Option<String>) {
        let mut d = Diagnostic::new(location, message);
        if let Some(h) = help {
            d = d.with_help(h);
        }
        self.diags.push(d);
    }

    fn claim_id(&mut self, id: &str, location: Location, first: &mut HashMap<String, Location>) -> bool {
        if RESERVED.contains(&id) {
            self.err(
                location,
                format!("id \"{id}\" is reserved"),
                Some(format!("\"{id}.<name>\" refers to graph {id}s; choose another id")),
            );
            return false;
        }
        if id.is_empty() || id.contains('.') || id.contains('/') || id.contains('[') {
            self.err(
                location,
                format!("id \"{id}\" is not a valid id"),
                Some("use letters, digits and underscores".to_string()),
            );
            return false;
        }
        if let Some(prev) = first.get(id) {
            let at = match prev {
                Location::Span(s) => {
                    let (line, _) = crate::graph::spans::line_col(self.loc_source(), s.start);
                    format!(" (first used on line {line})")
                }
                _ => String::new(),
            };
            self.err(
                location,
                format!("duplicate id \"{id}\"{at}"),
                Some("ids must be unique; rename one of them".to_string()),
            );
            return false;
        }
        first.insert(id.to_string(), location);
        true
    }

    fn loc_source(&self) -> &str {
        self.source
    }

    fn collect_nodes(&mut self) -> Vec<Item> {
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
    fn scalar_value(&self, name: &str) -> Option<f64> {
        match self.doc.inputs.get(name) {
            Some(InputKind::Scalar(default)) => Some(self.option_value(name).unwrap_or(*default)),
            _ => None,
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
                         (volgraph_core::compile::MAX_REPEAT_ITERATIONS)"
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
                if !divide_by.is_finite() || *divide_by <= 0.0 || !value.is_finite() {
                    self.err(
                        self.loc.pass_field(path, id, "count"),
                        format!("repeat group \"{id}\" divides \"{name}\" ({value}) by {divide_by}"),
                        Some("divide_by must be a positive number and the scene value finite".to_string()),
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
        let plugin = self.registry.get(&p.kind).cloned();
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
            otherwise: BTreeMap::new(),
        };
        let Some(plugin) = plugin else {
            let kinds = self.registry.kinds();
            let mut help = format!("known kinds: {}", comma_list(&kinds));
            help = guess_then(&p.kind, kinds.iter().copied(), "", help);
            self.err(
                self.loc.pass_field(path, &p.id, "kind"),
                format!("pass \"{}\" has unknown kind \"{}\"", p.id, p.kind),
                Some(help),
            );
            self.passes.push(info);
            return idx;
        };
        info.params = self.check_params(p, path, plugin.as_ref());
        info.ports = plugin.ports(&info.params);
        for f in plugin.features() {
            if !info.needs.iter().any(|n| n == f) {
                info.needs.push(f.to_string());
            }
        }
        info.enabled = info.needs.iter().all(|f| self.options.features.contains(f));
        self.check_port_names(p, path, &info);
        info.outputs = self.output_descs(p, path, &info);
        self.passes.push(info);
        idx
    }

    fn check_params(&mut self, p: &PassDoc, path: PassPath, plugin: &dyn PassPlugin) -> Params {
        let specs = plugin.params();
        let mut params = Params::defaults(&specs);
        let mut values: Vec<(String, ron::Value)> = p.params.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        let prefix = format!("{}.", p.id);
        for (key, value) in &self.options.param_overrides {
            if let Some(name) = key.strip_prefix(&prefix) {
                values.retain(|(k, _)| k != name);
                values.push((name.to_string(), value.clone()));
            }
        }
        for (name, written) in &values {
            // `"input.NAME"` stands for the value of a Scalar graph input (the scene's value
            // when the application sets one), shared by every pass that names it.
            let value = match written {
                ron::Value::String(text) if text.starts_with("input.") => {
                    let input = &text["input.".len()..];
                    match self.scalar_value(input) {
                        Some(v) => ron::Value::from(v),
                        None => {
                            self.err(
                                self.loc.pass_entry(path, &p.id, "params", name, false),
                                format!("parameter \"{name}\" of pass \"{}\" reads \"{text}\", which is not a Scalar graph input", p.id),
                                Some(format!("declare inputs: {{\"{input}\": Scalar(<default>)}}, or write the value itself")),
                            );
                            continue;
                        }
                    }
                }
                other => other.clone(),
            };
            let value = &value;
            let Some(spec) = specs.iter().find(|s| s.name == name) else {
                let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
                let mut help = format!("its parameters are: {}", comma_list(&names));
                help = guess_then(name, names.iter().copied(), "", help);
                self.err(
                    self.loc.pass_entry(path, &p.id, "params", name, true),
                    format!("pass \"{}\" ({}) has no parameter \"{name}\"", p.id, p.kind),
                    Some(help),
                );
                continue;
            };
            let range = match &spec.kind {
                ParamKind::Float { default, min, max } => format!("default {default}, range {min} to {max}"),
                ParamKind::UInt { default, min, max } => format!("default {default}, range {min} to {max}"),
                ParamKind::Bool { default } => format!("default {default}"),
                ParamKind::Choice { default, options } => {
                    format!("default \"{default}\", one of {}", quoted_list(options))
                }
            };
            let location = self.loc.pass_entry(path, &p.id, "params", name, false);
            match check_param(spec, value) {
                Ok(v) => params.set(name, v),
                Err(ParamProblem::WrongType { found }) => self.err(
                    location,
                    format!(
                        "parameter \"{name}\" of pass \"{}\" must be {}, found {found}",
                        p.id,
                        spec.kind.type_name()
                    ),
                    Some(format!("{} ({range})", spec.doc)),
                ),
                Err(ParamProblem::OutOfRange { value }) => self.err(
                    location,
                    format!("parameter \"{name}\" of pass \"{}\" is {value}, outside its range", p.id),
                    Some(format!("{} ({range})", spec.doc)),
                ),
                Err(ParamProblem::UnknownChoice { value }) => self.err(
                    location,
                    format!("parameter \"{name}\" of pass \"{}\" is \"{value}\", which is not a valid choice", p.id),
                    Some(format!("{} ({range})", spec.doc)),
                ),
            }
        }
        params
    }

    fn check_port_names(&mut self, p: &PassDoc, path: PassPath, info: &PassInfo) {
        let input_names: Vec<&str> = info.ports.iter().filter(|s| s.is_input()).map(|s| s.name).collect();
        let output_names: Vec<&str> = info.ports.iter().filter(|s| s.is_output()).map(|s| s.name).collect();
        // A misspelt input is one mistake: report the unknown name with its suggestion, not
        // also the port it was meant for as missing.
        let mut meant: Vec<&str> = Vec::new();
        for name in p.inputs.keys() {
            if !input_names.contains(&name.as_str()) {
                let mut help = format!("its inputs are: {}", comma_list(&input_names));
                if let Some(best) = closest(name, input_names.iter().copied()) {
                    help = format!("did you mean \"{best}\"? {help}");
                    meant.push(best);
                }
                self.err(
                    self.loc.pass_entry(path, &p.id, "inputs", name, true),
                    format!("pass \"{}\" ({}) has no input \"{name}\"", p.id, p.kind),
                    Some(help),
                );
            }
        }
        for port in info.ports.iter().filter(|s| s.is_input() && s.required) {
            if !p.inputs.contains_key(port.name) && !meant.contains(&port.name) {
                self.err(
                    self.loc.pass_field(path, &p.id, "inputs"),
                    format!("pass \"{}\" ({}) needs input \"{}\" ({})", p.id, p.kind, port.name, port.kind.describe()),
                    Some(format!("wire it: inputs: {{\"{}\": \"<pass>.<output>\"}}", port.name)),
                );
            }
        }
        for name in p.outputs.keys().chain(p.otherwise.keys()) {
            if !output_names.contains(&name.as_str()) {
                let mut help = format!("its outputs are: {}", comma_list(&output_names));
                help = guess_then(name, output_names.iter().copied(), "", help);
                let map = if p.outputs.contains_key(name) { "outputs" } else { "otherwise" };
                self.err(
                    self.loc.pass_entry(path, &p.id, map, name, true),
                    format!("pass \"{}\" ({}) has no output \"{name}\"", p.id, p.kind),
                    Some(help),
                );
            }
        }
    }

    fn output_descs(&mut self, p: &PassDoc, path: PassPath, info: &PassInfo) -> BTreeMap<String, ValueDesc> {
        let mut out = BTreeMap::new();
        for port in info.ports.iter().filter(|s| s.access == Access::Write) {
            let decl = p.outputs.get(port.name).cloned().unwrap_or_default();
            let desc = match &port.kind {
                PortKind::Target { formats, .. } => {
                    let default = formats.first().copied().unwrap_or(TargetFormat::Rgba32Float);
                    let format = decl.format.unwrap_or(default);
                    if !formats.contains(&format) {
                        let names: Vec<&str> = formats.iter().map(|f| f.name()).collect();
                        self.err(
                            self.loc.pass_entry(path, &p.id, "outputs", port.name, false),
                            format!("output \"{}\" of pass \"{}\" cannot be {format}", port.name, p.id),
                            Some(format!("{} writes {}", p.kind, names.join(" or "))),
                        );
                    }
                    let size = decl.size.unwrap_or_default();
                    let bad_size = match size {
                        TargetSize::Viewport(s) => !(s.is_finite() && s > 0.0 && s <= 16.0),
                        TargetSize::Absolute(w, h) => w == 0 || h == 0 || w > 16384 || h > 16384,
                    };
                    if bad_size {
                        self.err(
                            self.loc.pass_entry(path, &p.id, "outputs", port.name, false),
                            format!("output \"{}\" of pass \"{}\" has size {size}", port.name, p.id),
                            Some(
                                "use Viewport(scale) with 0 < scale <= 16, or Absolute(w, h) with 1..=16384 pixels"
                                    .to_string(),
                            ),
                        );
                    }
                    ValueDesc::Target { format, size }
                }
                PortKind::Buffer { bytes, bytes_per_pixel } => {
                    ValueDesc::Buffer { bytes: *bytes, bytes_per_pixel: *bytes_per_pixel }
                }
                PortKind::Owned(t) => ValueDesc::Owned((*t).to_string()),
                PortKind::Volume => ValueDesc::Volume,
                PortKind::TransferFunction => ValueDesc::TransferFunction,
            };
            out.insert(port.name.to_string(), desc);
        }
        out
    }

    /// Parses `text` as a reference in the context of `group` (the group of the reader).
    fn parse_ref(&mut self, text: &str, reader_group: Option<usize>, context: &str, location: Location) -> Option<Ref> {
        let Some((head, tail)) = text.split_once('.') else {
            self.err(
                location,
                format!("{context} refers to \"{text}\", which is not of the form \"<pass>.<output>\""),
                Some("write \"<pass>.<output>\", \"input.<name>\" or \"history.<name>\"".to_string()),
            );
            return None;
        };
        match head {
            "input" => {
                if !self.doc.inputs.contains_key(tail) {
                    let names: Vec<&str> = self.doc.inputs.keys().map(String::as_str).collect();
                    let mut help = format!("declare it under inputs, or use one of: {}", comma_list(&names));
                    help = guess_then(tail, names.iter().copied(), "input.", help);
                    self.err(
                        location,
                        format!("{context} reads \"{text}\", but the graph has no input \"{tail}\""),
                        Some(help),
                    );
                    return None;
                }
                Some(Ref::Input(tail.to_string()))
            }
            "history" => {
                if !self.doc.history.contains_key(tail) {
                    let names: Vec<&str> = self.doc.history.keys().map(String::as_str).collect();
                    self.err(
                        location,
                        format!("{context} reads \"{text}\", but the graph declares no history \"{tail}\""),
                        Some(format!(
                            "declare history: {{\"{tail}\": (of: \"<pass>.<output>\")}}; declared: {}",
                            comma_list(&names)
                        )),
                    );
                    return None;
                }
                Some(Ref::History(tail.to_string()))
            }
            _ => {
                if let Some(&gi) = self.group_by_id.get(head) {
                    let carried: Vec<String> =
                        self.doc_group(gi).map(|r| r.carry.keys().cloned().collect()).unwrap_or_default();
                    if !carried.iter().any(|c| c == tail) {
                        self.err(
                            location,
                            format!("{context} reads \"{text}\", but repeat group \"{head}\" carries no \"{tail}\" (it carries: {})", comma_list(&carried)),
                            Some("read a carried value of the group, or add it to its carry".to_string()),
                        );
                        return None;
                    }
                    return Some(Ref::Carry { group: gi, name: tail.to_string() });
                }
                let Some(&pi) = self.pass_by_id.get(head) else {
                    let mut ids: Vec<&str> = self.pass_by_id.keys().map(String::as_str).collect();
                    ids.sort_unstable();
                    let mut help = format!("passes are: {}", comma_list(&ids));
                    help = guess_then(head, ids.iter().copied(), "", help);
                    self.err(
                        location,
                        format!("{context} reads \"{text}\", but there is no pass \"{head}\""),
                        Some(help),
                    );
                    return None;
                };
                let producer = &self.passes[pi];
                producer.plugin.as_ref()?;
                let outputs: Vec<&str> = producer.ports.iter().filter(|p| p.is_output()).map(|p| p.name).collect();
                if !outputs.contains(&tail) {
                    let full: Vec<String> = outputs.iter().map(|o| format!("{head}.{o}")).collect();
                    let help = match closest(tail, outputs.iter().copied()) {
                        Some(best) => Some(format!("did you mean \"{head}.{best}\"?")),
                        None => Some(format!("read one of {}", quoted_list(&full))),
                    };
                    self.err(
                        location,
                        format!(
                            "{context} reads \"{text}\", but pass \"{head}\" has no output \"{tail}\" (it has: {})",
                            comma_list(&outputs)
                        ),
                        help,
                    );
                    return None;
                }
                if let Some(g) = producer.group
                    && reader_group != Some(g)
                {
                    let gid = self.groups[g].id.clone();
                    let this = Ref::Output { pass: pi, port: tail.to_string() };
                    let carried =
                        self.groups[g].carry.iter().find(|(_, (_, next))| *next == this).map(|(n, _)| n.clone());
                    let help = match carried {
                        Some(name) => {
                            format!("its last iteration's value leaves the group as \"{gid}.{name}\": read that")
                        }
                        None => {
                            format!("values leave a repeat group through its carry: read \"{gid}.<carried name>\"")
                        }
                    };
                    self.err(
                        location,
                        format!("{context} reads \"{text}\" from inside repeat group \"{gid}\""),
                        Some(help),
                    );
                    return None;
                }
                Some(Ref::Output { pass: pi, port: tail.to_string() })
            }
        }
    }

    fn doc_group(&self, gi: usize) -> Option<&crate::graph::ast::RepeatDoc> {
        self.doc
            .passes
            .iter()
            .filter_map(|n| match n {
                NodeDoc::Repeat(r) => Some(r),
                NodeDoc::Pass(_) => None,
            })
            .nth(gi)
    }

    fn pass_doc(&self, path: PassPath) -> Option<&PassDoc> {
        match (self.doc.passes.get(path.top)?, path.body) {
            (NodeDoc::Pass(p), None) => Some(p),
            (NodeDoc::Repeat(r), Some(i)) => r.body.get(i),
            _ => None,
        }
    }

    /// The type of a resolved reference.
    fn ref_desc(&self, r: &Ref, depth: usize) -> Option<ValueDesc> {
        if depth > 32 {
            return None;
        }
        match r {
            Ref::Input(n) => match self.doc.inputs.get(n)? {
                InputKind::Volume => Some(ValueDesc::Volume),
                InputKind::TransferFunction => Some(ValueDesc::TransferFunction),
                InputKind::Scalar(_) => Some(ValueDesc::Scalar),
            },
            Ref::History(n) => {
                let of = &self.doc.history.get(n)?.of;
                let (head, tail) = of.split_once('.')?;
                let p = self.passes.get(*self.pass_by_id.get(head)?)?;
                p.outputs.get(tail).cloned().or_else(|| self.modify_desc(p, tail, depth))
            }
            Ref::Carry { group, name } => {
                let init = &self.groups.get(*group)?.carry.get(name)?.0;
                self.ref_desc(init, depth + 1)
            }
            Ref::Output { pass, port } => {
                let p = self.passes.get(*pass)?;
                p.outputs.get(port).cloned().or_else(|| self.modify_desc(p, port, depth))
            }
        }
    }

    /// A Modify port's output has the type of what it modifies.
    fn modify_desc(&self, p: &PassInfo, port: &str, depth: usize) -> Option<ValueDesc> {
        self.ref_desc(p.inputs.get(port)?, depth + 1)
    }

    fn check_references(&mut self) {
        // Carry init/next first (inputs inside the body depend on them for types).
        for gi in 0..self.groups.len() {
            let Some(r) = self.doc_group(gi).cloned() else { continue };
            let top = self.doc.passes.iter().position(|n| matches!(n, NodeDoc::Repeat(x) if x.id == r.id)).unwrap_or(0);
            let path = PassPath { top, body: None };
            for (name, carry) in &r.carry {
                let ctx = format!("carry \"{name}\" of repeat group \"{}\"", r.id);
                let init_loc = self.loc.pass_entry_field(path, &r.id, "carry", name, "init");
                let next_loc = self.loc.pass_entry_field(path, &r.id, "carry", name, "next");
                let init = self.parse_ref(&carry.init, None, &ctx, init_loc.clone());
                let next = self.parse_ref(&carry.next, Some(gi), &ctx, next_loc.clone());
                if let Some(Ref::Output { pass, .. }) = &next {
                    if self.passes[*pass].group != Some(gi) {
                        self.err(
                            next_loc.clone(),
                            format!(
                                "{ctx} takes its next value from \"{}\", which is not an output of a pass in its body",
                                carry.next
                            ),
                            Some("next must name \"<body pass>.<output>\"".to_string()),
                        );
                    }
                } else if next.is_some() {
                    self.err(
                        next_loc.clone(),
                        format!(
                            "{ctx} takes its next value from \"{}\", which is not an output of a pass in its body",
                            carry.next
                        ),
                        Some("next must name \"<body pass>.<output>\"".to_string()),
                    );
                }
                if let (Some(i), Some(n)) = (init, next) {
                    self.groups[gi].carry.insert(name.clone(), (i, n));
                }
            }
        }
        // Pass inputs and otherwise.
        for pi in 0..self.passes.len() {
            let path = self.passes[pi].path;
            let Some(p) = self.pass_doc(path).cloned() else { continue };
            if self.passes[pi].plugin.is_none() {
                continue;
            }
            let group = self.passes[pi].group;
            for (port, text) in &p.inputs {
                if !self.passes[pi].ports.iter().any(|s| s.name == port && s.is_input()) {
                    continue;
                }
                let location = self.loc.pass_entry(path, &p.id, "inputs", port, false);
                let ctx = format!("pass \"{}\"", p.id);
                if let Some(r) = self.parse_ref(text, group, &ctx, location.clone()) {
                    self.passes[pi].inputs.insert(port.clone(), r);
                }
            }
            for (port, text) in &p.otherwise {
                let location = self.loc.pass_entry(path, &p.id, "otherwise", port, false);
                let ctx = format!("otherwise of pass \"{}\"", p.id);
                if let Some(r) = self.parse_ref(text, group, &ctx, location) {
                    self.passes[pi].otherwise.insert(port.clone(), r);
                }
            }
        }
        // Types, now that every reference is known.
        for pi in 0..self.passes.len() {
            let path = self.passes[pi].path;
            let Some(p) = self.pass_doc(path).cloned() else { continue };
            let inputs = self.passes[pi].inputs.clone();
            let mut pass_size: Option<(TargetSize, String)> = self.passes[pi]
                .ports
                .iter()
                .filter(|s| {
                    matches!(s.kind, PortKind::Target { size: SizeRule::MatchPass, .. }) && s.access == Access::Write
                })
                .find_map(|s| match self.passes[pi].outputs.get(s.name) {
                    Some(ValueDesc::Target { size, .. }) => Some((*size, format!("{}.{}", p.id, s.name))),
                    _ => None,
                });
            for (port, r) in &inputs {
                let Some(spec) = self.passes[pi].ports.iter().find(|s| s.name == port).cloned() else { continue };
                let Some(desc) = self.ref_desc(r, 0) else { continue };
                let location = self.loc.pass_entry(path, &p.id, "inputs", port, false);
                let text = &p.inputs[port];
                let producer_formats = self.producer_formats(r);
                self.check_type(&p.id, &spec, text, &desc, producer_formats.as_deref(), location.clone());
                if let (PortKind::Target { size: SizeRule::MatchPass, .. }, ValueDesc::Target { size, .. }) =
                    (&spec.kind, &desc)
                {
                    match &pass_size {
                        None => pass_size = Some((*size, text.clone())),
                        Some((expected, from)) if expected != size => self.err(
                            location,
                            format!("pass \"{}\" reads \"{text}\" of size {size}, but \"{from}\" is {expected}", p.id),
                            Some(format!(
                                "the targets of pass \"{}\" must have one size; declare the same size on both",
                                p.id
                            )),
                        ),
                        _ => {}
                    }
                }
            }
            let otherwise = self.passes[pi].otherwise.clone();
            for (port, r) in &otherwise {
                let (Some(want), Some(got)) = (self.passes[pi].outputs.get(port).cloned(), self.ref_desc(r, 0)) else {
                    continue;
                };
                if want != got {
                    self.err(
                        self.loc.pass_entry(path, &p.id, "otherwise", port, false),
                        format!(
                            "otherwise of pass \"{}\" stands in \"{}\" ({}) for output \"{port}\" ({})",
                            p.id,
                            p.otherwise[port],
                            got.describe(),
                            want.describe()
                        ),
                        Some("the stand-in must have the output's format and size".to_string()),
                    );
                }
            }
        }
        // Carry types.
        for gi in 0..self.groups.len() {
            let carry = self.groups[gi].carry.clone();
            let id = self.groups[gi].id.clone();
            for (name, (init, next)) in carry {
                let (Some(a), Some(b)) = (self.ref_desc(&init, 0), self.ref_desc(&next, 0)) else { continue };
                if a != b {
                    let top =
                        self.doc.passes.iter().position(|n| matches!(n, NodeDoc::Repeat(x) if x.id == id)).unwrap_or(0);
                    self.err(
                        self.loc.pass_entry(PassPath { top, body: None }, &id, "carry", &name, true),
                        format!(
                            "carry \"{name}\" of repeat group \"{id}\" starts as {} but its next value is {}",
                            a.describe(),
                            b.describe()
                        ),
                        Some("give init and next the same format and size".to_string()),
                    );
                }
            }
        }
        // Readers of gated-off passes need a stand-in.
        for pi in 0..self.passes.len() {
            let inputs = self.passes[pi].inputs.clone();
            let path = self.passes[pi].path;
            let id = self.passes[pi].id.clone();
            if !self.passes[pi].enabled {
                continue;
            }
            for (port, r) in inputs {
                if let Ref::Output { pass, port: out } = &r {
                    self.require_stand_in(
                        *pass,
                        out,
                        &format!("pass \"{id}\""),
                        self.loc.pass_entry(path, &id, "inputs", &port, false),
                    );
                }
            }
        }
    }

    fn require_stand_in(&mut self, producer: usize, port: &str, reader: &str, location: Location) {
        let p = &self.passes[producer];
        if p.enabled || p.otherwise.contains_key(port) {
            return;
        }
        let missing: Vec<&str> =
            p.needs.iter().filter(|f| !self.options.features.contains(*f)).map(String::as_str).collect();
        let features = quoted_list(&missing);
        let msg = format!(
            "{reader} reads \"{}.{port}\", but pass \"{}\" is off (feature {features} not enabled) and gives no otherwise for \"{port}\"",
            p.id, p.id
        );
        let help = format!(
            "add otherwise: {{\"{port}\": \"<pass>.<output>\"}} to pass \"{}\", or enable {}",
            p.id,
            missing.iter().map(|f| format!("--features {f}")).collect::<Vec<_>>().join(" ")
        );
        self.err(location, msg, Some(help));
    }

    /// The formats the producing port of a pass output can be declared with (`None` for other
    /// references: carried values, history, Modify outputs).
    fn producer_formats(&self, r: &Ref) -> Option<Vec<TargetFormat>> {
        let Ref::Output { pass, port } = r else { return None };
        self.passes.get(*pass)?.ports.iter().find(|s| s.name == port && s.access == Access::Write).and_then(
            |s| match &s.kind {
                PortKind::Target { formats, .. } => Some(formats.clone()),
                _ => None,
            },
        )
    }

    fn check_type(
        &mut self,
        reader: &str,
        spec: &PortSpec,
        text: &str,
        desc: &ValueDesc,
        producer_formats: Option<&[TargetFormat]>,
        location: Location,
    ) {
        let ok = match (&spec.kind, desc) {
            (PortKind::Target { formats, .. }, ValueDesc::Target { format, .. }) => {
                if !formats.contains(format) {
                    let names: Vec<&str> = formats.iter().map(|f| f.name()).collect();
                    let (head, tail) = text.split_once('.').unwrap_or((text, ""));
                    // Suggest declaring another format only where the producer can write one
                    // the reader accepts (with no producer port known: any accepted format).
                    let fix = producer_formats
                        .map_or(formats.first().copied(), |can| formats.iter().copied().find(|f| can.contains(f)));
                    let help = match fix {
                        Some(f) => format!(
                            "declare outputs: {{\"{tail}\": (format: {f})}} on \"{head}\", or read another target"
                        ),
                        None => format!(
                            "\"{head}\" cannot write {} to \"{tail}\"; read a target of one of those formats instead",
                            names.join(" or ")
                        ),
                    };
                    self.err(
                        location,
                        format!(
                            "pass \"{reader}\" input \"{}\" accepts {}, but \"{text}\" is {format}",
                            spec.name,
                            names.join(" or ")
                        ),
                        Some(help),
                    );
                }
                return;
            }
            (PortKind::Volume, ValueDesc::Volume) | (PortKind::TransferFunction, ValueDesc::TransferFunction) => true,
            (PortKind::Owned(a), ValueDesc::Owned(b)) => a == b,
            (PortKind::Buffer { .. }, ValueDesc::Buffer { .. }) => true,
            _ => false,
        };
        if !ok {
            self.err(
                location,
                format!(
                    "pass \"{reader}\" input \"{}\" needs {}, but \"{text}\" is {}",
                    spec.name,
                    spec.kind.describe(),
                    desc.describe()
                ),
                Some(match &spec.kind {
                    PortKind::Volume => "declare inputs: {\"volume\": Volume} and read \"input.volume\"".to_string(),
                    PortKind::TransferFunction => {
                        "declare inputs: {\"tf\": TransferFunction} and read \"input.tf\"".to_string()
                    }
                    PortKind::Target { .. } => "read \"<pass>.<output>\" of a pass that writes a target".to_string(),
                    PortKind::Owned(t) => format!("read the output of a pass that makes a {t}"),
                    PortKind::Buffer { .. } => "read the output of a pass that writes a buffer".to_string(),
                }),
            );
        }
    }

    fn check_graph_outputs(&mut self) -> BTreeMap<String, Ref> {
        let mut out = BTreeMap::new();
        if self.doc.outputs.is_empty() {
            self.err(
                self.loc.top_field("outputs").map_or(Location::File, |v| Location::Span(v.span)),
                "the graph has no outputs, so every pass would be culled".to_string(),
                Some("name a result: outputs: {\"image\": \"<pass>.<output>\"}".to_string()),
            );
        }
        for (name, text) in &self.doc.outputs.clone() {
            let location = self.loc.top_entry("outputs", name, false);
            let ctx = format!("graph output \"{name}\"");
            if let Some(r) = self.parse_ref(text, None, &ctx, location.clone()) {
                match self.ref_desc(&r, 0) {
                    Some(ValueDesc::Target { .. } | ValueDesc::Buffer { .. }) | None => {
                        if let Ref::Output { pass, port } = &r {
                            self.require_stand_in(*pass, port, &ctx, location);
                        }
                        out.insert(name.clone(), r);
                    }
                    Some(other) => self.err(
                        location,
                        format!("{ctx} is \"{text}\", which is {}, not a target or buffer", other.describe()),
                        Some("graph outputs name targets or buffers written by passes".to_string()),
                    ),
                }
            }
        }
        out
    }

    fn check_history(&mut self) -> BTreeMap<String, (Ref, HistoryInitial)> {
        let mut out = BTreeMap::new();
        for (name, h) in &self.doc.history.clone() {
            let location = self.loc.top_entry_field("history", name, "of");
            let Some((head, tail)) = h.of.split_once('.') else {
                self.err(
                    location,
                    format!("history \"{name}\" reads \"{}\", which is not of the form \"<pass>.<output>\"", h.of),
                    Some("name the target whose previous-frame value you want".to_string()),
                );
                continue;
            };
            let writer = self.pass_by_id.get(head).map(|&i| &self.passes[i]);
            let writes = writer.is_some_and(|p| p.ports.iter().any(|s| s.name == tail && s.is_output()));
            if !writes {
                let help = match writer {
                    Some(p) => {
                        let outs: Vec<&str> = p.ports.iter().filter(|s| s.is_output()).map(|s| s.name).collect();
                        format!(
                            "pass \"{head}\" writes {} with these parameters; keep one of those in history, or change the parameters so it writes \"{tail}\"",
                            comma_list(&outs)
                        )
                    }
                    None => "name an output of a pass in this graph".to_string(),
                };
                self.err(location, format!("history \"{name}\" reads \"{}\", but no pass writes it", h.of), Some(help));
                continue;
            }
            if let Some(&pi) = self.pass_by_id.get(head) {
                let kept_kind = self.passes[pi].ports.iter().find(|s| s.name == tail).map(|s| s.kind.clone());
                if !matches!(kept_kind, Some(PortKind::Target { .. })) {
                    self.err(
                        location,
                        format!("history \"{name}\" reads \"{}\", which is not a target", h.of),
                        Some("history keeps 2D targets; keep a target the pass writes".to_string()),
                    );
                    continue;
                }
                if self.passes[pi].group.is_some() {
                    self.err(
                        location,
                        format!("history \"{name}\" reads \"{}\" from inside a repeat group", h.of),
                        Some("keep the group's carried result in history instead".to_string()),
                    );
                    continue;
                }
                if !self.passes[pi].enabled {
                    self.err(
                        location,
                        format!("history \"{name}\" reads \"{}\", but pass \"{head}\" is off for these features", h.of),
                        Some("enable its features or keep another target in history".to_string()),
                    );
                    continue;
                }
                out.insert(name.clone(), (Ref::Output { pass: pi, port: tail.to_string() }, h.initial.clone()));
            }
        }
        out
    }

    /// Pass-level dependency cycles (carried feedback and history are not cycles).
    fn check_cycles(&mut self) {
        let mut g: DiGraph<usize, ()> = DiGraph::new();
        let nodes: Vec<NodeIndex> = (0..self.passes.len()).map(|i| g.add_node(i)).collect();
        let producers_of = |r: &Ref, out: &mut Vec<usize>| match r {
            Ref::Output { pass, .. } => out.push(*pass),
            Ref::Carry { group, name } => {
                if let Some((Ref::Output { pass, .. }, _)) = self.groups[*group].carry.get(name) {
                    out.push(*pass);
                }
            }
            _ => {}
        };
        let mut edges = Vec::new();
        for (pi, p) in self.passes.iter().enumerate() {
            let mut producers = Vec::new();
            for r in p.inputs.values().chain(p.otherwise.values()) {
                producers_of(r, &mut producers);
            }
            for q in producers {
                edges.push((q, pi));
            }
        }
        for (a, b) in edges {
            g.add_edge(nodes[a], nodes[b], ());
        }
        let sccs = petgraph::algo::tarjan_scc(&g);
        for scc in sccs {
            let is_cycle = scc.len() > 1 || g.contains_edge(scc[0], scc[0]);
            if !is_cycle {
                continue;
            }
            // Walk the cycle from its first-declared pass.
            let start = *scc.iter().min_by_key(|n| g[**n]).unwrap_or(&scc[0]);
            let mut path = vec![start];
            let mut cur = start;
            loop {
                let next = g
                    .neighbors(cur)
                    .filter(|n| scc.contains(n))
                    .min_by_key(|n| if *n == start { 0 } else { 1 + g[*n] });
                match next {
                    Some(n) if n == start || path.contains(&n) => {
                        path.push(n);
                        break;
                    }
                    Some(n) => {
                        path.push(n);
                        cur = n;
                    }
                    None => break,
                }
            }
            let names: Vec<&str> = path.iter().map(|n| self.passes[g[*n]].id.as_str()).collect();
            let first = &self.passes[g[start]];
            self.err(
                self.loc.pass_field(first.path, &first.id, "inputs"),
                format!("the passes form a cycle: {}", names.join(" → ")),
                Some(
                    "break the cycle; feed values back across iterations with a Repeat group's carry, or across frames with history"
                        .to_string(),
                ),
            );
        }
    }
}
