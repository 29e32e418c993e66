//! Validation: every problem of a graph file, located, with a fix, all at once.

mod bypass;
mod cycles;
mod nodes;
mod outputs;
mod params;
mod ports;
mod references;

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use super::CompileOptions;
use crate::decl::{KindLookup, PassDecl, PortSpec};
use crate::diagnostic::{Diagnostic, Location};
use crate::format::{TargetFormat, TargetSize};
use crate::graph::ast::{GraphDoc, HistoryInitial, InputKind, NodeDoc, RepeatCount};
use crate::graph::locate::{Locator, PassPath};
use crate::params::Params;
use crate::suggest::comma_list;
pub(crate) use bypass::CheckedBypass;

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
    LabelTable,
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
            ValueDesc::LabelTable => "a label table".to_string(),
            ValueDesc::Scalar => "a scalar".to_string(),
        }
    }
}

pub(crate) struct PassInfo {
    pub id: String,
    pub kind: String,
    pub path: PassPath,
    pub group: Option<usize>,
    pub plugin: Option<Arc<dyn PassDecl>>,
    pub params: Params,
    pub ports: Vec<PortSpec>,
    pub outputs: BTreeMap<String, ValueDesc>,
    pub inputs: BTreeMap<String, Ref>,
    pub enabled: bool,
    pub needs: Vec<String>,
    /// How many of `needs` the graph's `when:` list wrote (the rest the plugin declares).
    pub when_count: usize,
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
    /// Scene features parameters read as `"feature.NAME"` (effects a pass specializes for).
    pub features_read: std::collections::BTreeSet<String>,
    /// The graph's bypasses, resolved.
    pub bypass: Vec<CheckedBypass>,
}

const RESERVED: [&str; 2] = ["input", "history"];

struct Checker<'a> {
    doc: &'a GraphDoc,
    source: &'a str,
    loc: Locator,
    registry: &'a dyn KindLookup,
    options: &'a CompileOptions,
    diags: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    passes: Vec<PassInfo>,
    groups: Vec<GroupInfo>,
    pass_by_id: HashMap<String, usize>,
    group_by_id: HashMap<String, usize>,
    features_read: std::collections::BTreeSet<String>,
}

pub(crate) fn check(
    doc: &GraphDoc,
    source: &str,
    registry: &dyn KindLookup,
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
        features_read: Default::default(),
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
    c.check_when_names();
    let outputs = c.check_graph_outputs();
    let history = c.check_history();
    let bypass = c.check_bypasses(&outputs, &history);
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
            features_read: c.features_read,
            bypass,
        })
    } else {
        Err(c.diags)
    }
}

impl Checker<'_> {
    /// A `when:` name one typo away from a scene effect or from a feature the graph uses
    /// elsewhere (`"shadng"`) would gate its pass off for good, since nothing turns that name
    /// on: an error with "did you mean". Names far from every known one are the graph's own
    /// features (`"reprojection"`, turned on by `--features`).
    fn check_when_names(&mut self) {
        let effects = self.registry.scene_effects();
        let mut known: std::collections::BTreeSet<&str> = effects.iter().copied().collect();
        known.extend(self.features_read.iter().map(String::as_str));
        let mut uses: HashMap<&str, usize> = HashMap::new();
        for p in &self.passes {
            for name in &p.needs {
                *uses.entry(name.as_str()).or_default() += 1;
            }
        }
        let mut found = Vec::new();
        for p in &self.passes {
            // Only what the graph wrote; a name the user turns on (`--features`) is meant.
            for (i, name) in p.needs.iter().enumerate().take(p.when_count) {
                if known.contains(name.as_str()) || self.options.features.contains(name) {
                    continue;
                }
                // Another name used more often than this one, or a known one, that it is a typo of.
                let others = known
                    .iter()
                    .copied()
                    .chain(
                        uses.iter().filter(|(n, count)| **n != name && **count > uses[name.as_str()]).map(|(n, _)| *n),
                    )
                    .filter(|n| *n != name);
                if let Some(best) = crate::suggest::closest(name, others) {
                    found.push((
                        self.loc.pass_list_item(p.path, &p.id, "when", i),
                        format!(
                            "pass \"{}\" is gated on feature \"{name}\", which no scene effect or other pass of \
                             the graph uses",
                            p.id
                        ),
                        format!(
                            "did you mean \"{best}\"? (a feature of the graph's own is turned on with --features \
                             {name}) the scene effects are: {}",
                            comma_list(&effects)
                        ),
                    ));
                }
            }
        }
        for (at, message, help) in found {
            self.err(at, message, Some(help));
        }
    }

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
}
