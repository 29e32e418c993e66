//! Scheduling: unroll repeat groups, resolve every reference to a concrete value, order the
//! pass instances, cull what no output needs, and pool transient targets ([`pooling`]).

mod pooling;

use pooling::{pool, root_of};

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap, HashMap};

use super::check::{Checked, Item, Ref, ValueDesc};
use super::{CompileOptions, MAX_PLAN_STEPS};
use crate::decl::{Access, PortKind};
use crate::diagnostic::{Diagnostic, Location};
use crate::graph::ast::{GraphDoc, HistoryInitial};
use crate::plan::{Binding, BoundPort, History, Plan, Resource, ResourceDesc, ResourceId, Step};

#[derive(Clone, Debug, PartialEq)]
enum Val {
    Out(usize, String),
    Input(String),
    History(String),
    Unbound,
}

struct Inst {
    pass: usize,
    iter: Option<u32>,
    label: String,
}

/// Each instance's inputs: (index of the input port among its pass's ports, the value it reads).
type Inputs = Vec<Vec<(usize, Val)>>;

/// The instance of each (pass, iteration).
type InstanceOf = HashMap<(usize, Option<u32>), usize>;

/// The resource that holds each (instance, output port) value.
type ResourceOf = HashMap<(usize, String), ResourceId>;

/// What culling keeps: which instances are needed, and the values graph outputs and history read.
struct Needed {
    needed: Vec<bool>,
    output_vals: BTreeMap<String, Val>,
    history_vals: BTreeMap<String, (Val, HistoryInitial)>,
}

/// The resources graph outputs and history hold past the last step.
struct Kept {
    outputs: BTreeMap<String, ResourceId>,
    history: BTreeMap<String, History>,
    persistent_roots: Vec<ResourceId>,
}

pub(crate) fn schedule(doc: &GraphDoc, c: Checked, options: &CompileOptions) -> Result<Plan, Vec<Diagnostic>> {
    bound(&c)?;
    let (insts, inst_of) = instantiate(&c);
    let resolver = Resolver { c: &c, inst_of: &inst_of };
    let inputs = resolve_inputs(&c, &insts, &resolver);
    let preds = dependencies(&c, &insts, &inputs)?;
    let Needed { needed, output_vals, history_vals } = cull(&c, &insts, &resolver, &preds);
    let order = order(&c, &insts, &preds, &needed)?;
    let (mut resources, steps, rid_of) = build_resources(&c, options, &insts, &inputs, &order);
    let Kept { outputs, history, persistent_roots } =
        keep_results(&mut resources, &rid_of, &output_vals, &history_vals);
    let slots = pool(&mut resources, &persistent_roots);
    let culled = culled(&c, &insts, &needed);
    let gated = gated(&c, options);
    let mut history = history;
    for (name, h) in history.iter_mut() {
        if let Some(declared) = doc.history.get(name) {
            h.reset_on_params_of = declared.reset_on_params_of.clone();
            h.max_camera_degrees = declared.max_camera_degrees;
            h.while_camera_still = declared.while_camera_still;
        }
    }
    let bypass = c.bypass.iter().filter_map(|b| bypass_in_plan(&c, b, &steps, &resources)).collect();
    Ok(Plan {
        name: doc.name.clone(),
        viewport: options.viewport,
        features: options.features.clone(),
        inputs: c.inputs.clone(),
        steps,
        culled,
        gated,
        resources,
        slots,
        outputs,
        history,
        bypass,
        kinds: doc.kinds.clone(),
        known_features: c
            .passes
            .iter()
            .flat_map(|p| p.needs.iter().cloned())
            .chain(c.features_read.iter().cloned())
            // Crop and clip belong to the frame: every graph takes them.
            .chain([crate::cut_effects::CROP, crate::cut_effects::CLIP].map(String::from))
            .collect(),
        known_scalars: c
            .inputs
            .iter()
            .filter(|(_, k)| {
                matches!(k, crate::graph::ast::InputKind::Scalar(_) | crate::graph::ast::InputKind::Data(_))
            })
            .map(|(n, _)| n.clone())
            .chain(c.scene_values.iter().cloned())
            .collect(),
        warnings: Default::default(),
    })
}

/// A checked bypass in plan terms: its steps, what they write that running steps read, and
/// the resource of its measure; `None` when no output needs the measuring pass (culled: nothing
/// measures, so every pass runs).
fn bypass_in_plan(
    c: &Checked,
    b: &crate::compile::check::CheckedBypass,
    steps: &[crate::plan::Step],
    resources: &[Resource],
) -> Option<crate::plan::Bypass> {
    let ids: Vec<&str> = b.passes.iter().map(|&p| c.passes[p].id.as_str()).collect();
    let left_out: Vec<usize> = (0..steps.len()).filter(|&i| ids.contains(&steps[i].pass_id.as_str())).collect();
    let mut clears = Vec::new();
    for (_, step) in steps.iter().enumerate().filter(|(i, _)| !left_out.contains(i)) {
        for bp in step.ports.iter().filter(|bp| bp.access == crate::decl::Access::Read) {
            if let crate::plan::Binding::Resource { id, .. } = bp.binding
                && left_out.contains(&resources[id].producer)
                && !clears.contains(&id)
            {
                clears.push(id);
            }
        }
    }
    let (pass, port) = (&c.passes[b.measure.0].id, &b.measure.1);
    let measure_step = steps.iter().position(|s| &s.pass_id == pass)?;
    let measure = steps[measure_step].ports.iter().find(|bp| &bp.port == port).and_then(|bp| match bp.binding {
        crate::plan::Binding::Resource { id, written } => Some(written.unwrap_or(id)),
        _ => None,
    })?;
    Some(crate::plan::Bypass { name: b.name.clone(), steps: left_out, clears, measure_step, measure, below: b.below })
}

/// 0. Bound the unrolled size before allocating anything for it.
fn bound(c: &Checked) -> Result<(), Vec<Diagnostic>> {
    let total: u64 = c
        .order
        .iter()
        .map(|item| match item {
            Item::Pass(_) => 1,
            Item::Group(gi) => c.groups[*gi].count as u64 * c.groups[*gi].members.len() as u64,
        })
        .sum();
    if total > MAX_PLAN_STEPS as u64 {
        let groups: Vec<String> =
            c.groups.iter().map(|g| format!("\"{}\" {} × {} passes", g.id, g.count, g.members.len())).collect();
        return Err(vec![
            Diagnostic::new(
                Location::File,
                format!(
                    "the graph unrolls to {total} pass instances ({}), over the limit of {MAX_PLAN_STEPS}",
                    groups.join(", ")
                ),
            )
            .with_help("use fewer repeat iterations (more work per iteration) or fewer passes in the body"),
        ]);
    }
    Ok(())
}

/// 1. Instances, in document order.
fn instantiate(c: &Checked) -> (Vec<Inst>, InstanceOf) {
    let mut insts: Vec<Inst> = Vec::new();
    let mut inst_of: InstanceOf = HashMap::new();
    for item in &c.order {
        match item {
            Item::Pass(pi) if c.passes[*pi].enabled => {
                inst_of.insert((*pi, None), insts.len());
                insts.push(Inst { pass: *pi, iter: None, label: c.passes[*pi].id.clone() });
            }
            Item::Pass(_) => {}
            Item::Group(gi) => {
                let g = &c.groups[*gi];
                for it in 0..g.count {
                    for &m in &g.members {
                        if c.passes[m].enabled {
                            inst_of.insert((m, Some(it)), insts.len());
                            insts.push(Inst {
                                pass: m,
                                iter: Some(it),
                                label: format!("{}[{it}]/{}", g.id, c.passes[m].id),
                            });
                        }
                    }
                }
            }
        }
    }
    (insts, inst_of)
}

/// 2. Each instance's inputs as concrete values.
fn resolve_inputs(c: &Checked, insts: &[Inst], resolver: &Resolver) -> Inputs {
    let mut inputs: Vec<Vec<(usize, Val)>> = Vec::with_capacity(insts.len());
    for inst in insts {
        let p = &c.passes[inst.pass];
        let mut vals = Vec::new();
        for (k, spec) in p.ports.iter().enumerate() {
            if !spec.is_input() {
                continue;
            }
            let v = match p.inputs.get(spec.name) {
                Some(r) => resolver.resolve(r, p.group, inst.iter, 0).unwrap_or(Val::Unbound),
                None => Val::Unbound,
            };
            vals.push((k, v));
        }
        inputs.push(vals);
    }
    inputs
}

/// 3. Dependencies: producer → consumer, and readers of a value before its modifier.
fn dependencies(c: &Checked, insts: &[Inst], inputs: &Inputs) -> Result<Vec<Vec<usize>>, Vec<Diagnostic>> {
    let n = insts.len();
    let mut preds: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut readers: HashMap<(usize, String), Vec<usize>> = HashMap::new();
    let mut modifiers: HashMap<(usize, String), Vec<usize>> = HashMap::new();
    for (i, vals) in inputs.iter().enumerate() {
        let p = &c.passes[insts[i].pass];
        for (k, v) in vals {
            if let Val::Out(src, port) = v {
                preds[i].push(*src);
                let key = (*src, port.clone());
                if p.ports[*k].access == Access::Modify {
                    modifiers.entry(key).or_default().push(i);
                } else {
                    readers.entry(key).or_default().push(i);
                }
            }
        }
    }
    let mut diags = Vec::new();
    for (key, mods) in &modifiers {
        if mods.len() > 1 {
            let a = &insts[mods[0]];
            let b = &insts[mods[1]];
            let pa = &c.passes[a.pass];
            diags.push(
                Diagnostic::new(
                    Location::Field { pass: c.passes[b.pass].id.clone(), field: "inputs".to_string() },
                    format!(
                        "passes \"{}\" and \"{}\" both modify \"{}.{}\"",
                        a.label, b.label, insts[key.0].label, key.1
                    ),
                    )
                .with_help(match (a.pass == b.pass, c.passes[b.pass].group) {
                    // Every iteration of a repeat body modifies the same value: the chain must
                    // go through the group's carry so iteration i modifies iteration i-1's.
                    (true, Some(g)) => {
                        let port = modifier_port(c, insts, inputs, mods[1], key).unwrap_or("<port>");
                        format!(
                            "every iteration of repeat group \"{gid}\" modifies it; carry it instead: carry: {{\"{port}\": (init: \"{}.{}\", next: \"{}.{port}\")}} and read \"{gid}.{port}\"",
                            insts[key.0].label,
                            key.1,
                            pa.id,
                            gid = c.groups[g].id
                        )
                    }
                    _ => format!("let \"{}\" modify the output of \"{}\" instead", c.passes[b.pass].id, pa.id),
                }),
            );
        }
        for r in readers.get(key).into_iter().flatten() {
            if !mods.contains(r) {
                preds[mods[0]].push(*r);
            }
        }
    }
    if !diags.is_empty() {
        return Err(diags);
    }
    Ok(preds)
}

/// 4. Culling: keep what graph outputs, history and sinks need.
fn cull(c: &Checked, insts: &[Inst], resolver: &Resolver, preds: &[Vec<usize>]) -> Needed {
    let n = insts.len();
    let mut needed = vec![false; n];
    let mut stack: Vec<usize> = Vec::new();
    let mut output_vals = BTreeMap::new();
    for (name, r) in &c.outputs {
        if let Some(v) = resolver.resolve(r, None, None, 0) {
            if let Val::Out(i, _) = &v {
                stack.push(*i);
            }
            output_vals.insert(name.clone(), v);
        }
    }
    let mut history_vals = BTreeMap::new();
    for (name, (r, init)) in &c.history {
        if let Some(v @ Val::Out(i, _)) = resolver.resolve(r, None, None, 0) {
            stack.push(i);
            history_vals.insert(name.clone(), (v, init.clone()));
        }
    }
    for (i, inst) in insts.iter().enumerate() {
        if c.passes[inst.pass].plugin.as_ref().is_some_and(|p| p.is_sink()) {
            stack.push(i);
        }
    }
    while let Some(i) = stack.pop() {
        if std::mem::replace(&mut needed[i], true) {
            continue;
        }
        stack.extend(preds[i].iter().copied());
    }
    Needed { needed, output_vals, history_vals }
}

/// 5. Order: Kahn's algorithm, ties broken by document order.
fn order(c: &Checked, insts: &[Inst], preds: &[Vec<usize>], needed: &[bool]) -> Result<Vec<usize>, Vec<Diagnostic>> {
    let n = insts.len();
    let mut indegree = vec![0usize; n];
    let mut succs: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, ps) in preds.iter().enumerate() {
        if !needed[i] {
            continue;
        }
        let mut ps = ps.clone();
        ps.sort_unstable();
        ps.dedup();
        for p in ps {
            if needed[p] {
                indegree[i] += 1;
                succs[p].push(i);
            }
        }
    }
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..n).filter(|&i| needed[i] && indegree[i] == 0).map(Reverse).collect();
    let mut order = Vec::new();
    while let Some(Reverse(i)) = ready.pop() {
        order.push(i);
        for &s in &succs[i] {
            indegree[s] -= 1;
            if indegree[s] == 0 {
                ready.push(Reverse(s));
            }
        }
    }
    let needed_count = needed.iter().filter(|x| **x).count();
    if order.len() != needed_count {
        let mut ordered = vec![false; n];
        for &i in &order {
            ordered[i] = true;
        }
        let stuck: Vec<&str> = (0..n).filter(|&i| needed[i] && !ordered[i]).map(|i| insts[i].label.as_str()).collect();
        let first = (0..n).find(|&i| needed[i] && !ordered[i]).map_or(0, |i| insts[i].pass);
        return Err(vec![
            Diagnostic::new(
                Location::Field { pass: c.passes[first].id.clone(), field: "inputs".to_string() },
                format!(
                    "passes {} cannot be ordered: a pass reads a value after another pass modified it",
                    stuck.join(", ")
                ),
            )
            .with_help("read the modified version (\"<modifier>.<port>\") instead of the original".to_string()),
        ]);
    }
    Ok(order)
}

/// 6. Resources: the steps in order, each port bound to the resource it reads or writes.
fn build_resources(
    c: &Checked,
    options: &CompileOptions,
    insts: &[Inst],
    inputs: &Inputs,
    order: &[usize],
) -> (Vec<Resource>, Vec<Step>, ResourceOf) {
    let mut resources: Vec<Resource> = Vec::new();
    let mut rid_of: HashMap<(usize, String), ResourceId> = HashMap::new();
    let mut steps: Vec<Step> = Vec::new();
    for (s, &i) in order.iter().enumerate() {
        let inst = &insts[i];
        let p = &c.passes[inst.pass];
        let mut ports = Vec::new();
        let mut input_iter = inputs[i].iter();
        for spec in &p.ports {
            let binding = match spec.access {
                Access::Read | Access::Modify => {
                    let v = input_iter.next().map(|(_, v)| v.clone()).unwrap_or(Val::Unbound);
                    match v {
                        Val::Out(src, port) => {
                            let id = rid_of.get(&(src, port.clone())).copied();
                            match id {
                                Some(id) => {
                                    let written = (spec.access == Access::Modify).then(|| {
                                        let desc = resources[id].desc.clone();
                                        let w = resources.len();
                                        resources.push(Resource {
                                            name: format!("{}.{}", inst.label, spec.name),
                                            desc,
                                            producer: s,
                                            last_use: s,
                                            slot: None,
                                            modifies: Some(id),
                                        });
                                        rid_of.insert((i, spec.name.to_string()), w);
                                        w
                                    });
                                    resources[id].last_use = resources[id].last_use.max(s);
                                    Binding::Resource { id, written }
                                }
                                None => Binding::Unbound,
                            }
                        }
                        Val::Input(n) if spec.kind == PortKind::VolumeVoxels => Binding::InputVoxels(n),
                        Val::Input(n) => Binding::Input(n),
                        Val::History(n) => Binding::History(n),
                        Val::Unbound => Binding::Unbound,
                    }
                }
                Access::Write => {
                    let desc = match p.outputs.get(spec.name) {
                        Some(ValueDesc::Target { format, size }) => ResourceDesc::Target {
                            format: *format,
                            size: *size,
                            extent: size.resolve(options.viewport),
                        },
                        Some(ValueDesc::Buffer { bytes, bytes_per_pixel }) => ResourceDesc::Buffer {
                            size: (bytes + bytes_per_pixel * options.viewport.0 as u64 * options.viewport.1 as u64)
                                .max(4),
                        },
                        Some(ValueDesc::Owned(t)) => ResourceDesc::Owned(t.clone()),
                        _ => ResourceDesc::Owned("value".to_string()),
                    };
                    let id = resources.len();
                    resources.push(Resource {
                        name: format!("{}.{}", inst.label, spec.name),
                        desc,
                        producer: s,
                        last_use: s,
                        slot: None,
                        modifies: None,
                    });
                    rid_of.insert((i, spec.name.to_string()), id);
                    Binding::Resource { id, written: None }
                }
            };
            ports.push(BoundPort { port: spec.name.to_string(), access: spec.access, binding });
        }
        steps.push(Step {
            label: inst.label.clone(),
            pass_id: p.id.clone(),
            kind: p.kind.clone(),
            iteration: inst.iter.map(|it| (it, p.group.map_or(1, |g| c.groups[g].count))),
            params: p.params.clone(),
            ports,
        });
    }
    (resources, steps, rid_of)
}

/// 6. Resources, continued: what graph outputs and history read lives past the last step.
fn keep_results(
    resources: &mut [Resource],
    rid_of: &ResourceOf,
    output_vals: &BTreeMap<String, Val>,
    history_vals: &BTreeMap<String, (Val, HistoryInitial)>,
) -> Kept {
    let mut outputs = BTreeMap::new();
    for (name, v) in output_vals {
        if let Val::Out(i, port) = v
            && let Some(&id) = rid_of.get(&(*i, port.clone()))
        {
            resources[id].last_use = usize::MAX;
            outputs.insert(name.clone(), id);
        }
    }
    let mut history = BTreeMap::new();
    let mut persistent_roots = Vec::new();
    for (name, (v, initial)) in history_vals {
        if let Val::Out(i, port) = v
            && let Some(&id) = rid_of.get(&(*i, port.clone()))
        {
            resources[id].last_use = usize::MAX;
            persistent_roots.push(root_of(resources, id));
            // (one walk per history entry: few, however long the chain)
            history.insert(
                name.clone(),
                History {
                    source: id,
                    initial: initial.clone(),
                    reset_on_params_of: Vec::new(),
                    max_camera_degrees: None,
                    while_camera_still: false,
                },
            );
        }
    }
    Kept { outputs, history, persistent_roots }
}

/// Culled: enabled passes none of whose instances is needed, in document order.
fn culled(c: &Checked, insts: &[Inst], needed: &[bool]) -> Vec<String> {
    let mut pass_needed = vec![false; c.passes.len()];
    for (i, inst) in insts.iter().enumerate() {
        pass_needed[inst.pass] |= needed[i];
    }
    let mut ids: Vec<String> = Vec::new();
    for item in &c.order {
        let members: Vec<usize> = match item {
            Item::Pass(pi) => vec![*pi],
            Item::Group(gi) => c.groups[*gi].members.clone(),
        };
        for pi in members {
            if !c.passes[pi].enabled {
                continue;
            }
            let any_needed = pass_needed[pi];
            if !any_needed {
                ids.push(c.passes[pi].id.clone());
            }
        }
    }
    ids
}

/// Gated: passes that are off for these features, with the features they miss.
fn gated(c: &Checked, options: &CompileOptions) -> Vec<(String, Vec<String>)> {
    c.passes
        .iter()
        .filter(|p| !p.enabled)
        .map(|p| (p.id.clone(), p.needs.iter().filter(|f| !options.features.contains(*f)).cloned().collect()))
        .collect()
}

/// The name of the Modify port through which instance `inst` modifies the value `key`.
fn modifier_port<'a>(
    c: &'a Checked,
    insts: &[Inst],
    inputs: &[Vec<(usize, Val)>],
    inst: usize,
    key: &(usize, String),
) -> Option<&'a str> {
    let ports = &c.passes[insts[inst].pass].ports;
    inputs[inst].iter().find_map(|(k, v)| match v {
        Val::Out(src, port) if (*src, port) == (key.0, &key.1) && ports[*k].access == Access::Modify => {
            Some(ports[*k].name)
        }
        _ => None,
    })
}

struct Resolver<'a> {
    c: &'a Checked,
    inst_of: &'a InstanceOf,
}

impl Resolver<'_> {
    fn resolve(&self, r: &Ref, reader_group: Option<usize>, iter: Option<u32>, depth: usize) -> Option<Val> {
        if depth > 64 {
            return None;
        }
        let c = self.c;
        match r {
            Ref::Input(n) => Some(Val::Input(n.clone())),
            Ref::History(n) => Some(Val::History(n.clone())),
            Ref::Output { pass, port } => {
                let p = &c.passes[*pass];
                let it = if p.group.is_some() { iter } else { None };
                if !p.enabled {
                    let stand_in = p.otherwise.get(port)?;
                    return self.resolve(stand_in, p.group, it, depth + 1);
                }
                if let Some(&i) = self.inst_of.get(&(*pass, it)) {
                    return Some(Val::Out(i, port.clone()));
                }
                // A Modify port's output when the pass is not instantiated cannot happen; a
                // pass in a group read from outside is rejected by the checker.
                None
            }
            Ref::Carry { group, name } => {
                let g = &c.groups[*group];
                let (init, next) = g.carry.get(name)?;
                if reader_group == Some(*group) {
                    match iter {
                        Some(0) | None => self.resolve(init, None, None, depth + 1),
                        Some(i) => self.resolve(next, Some(*group), Some(i - 1), depth + 1),
                    }
                } else {
                    self.resolve(next, Some(*group), Some(g.count.saturating_sub(1)), depth + 1)
                }
            }
        }
    }
}
