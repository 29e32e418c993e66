//! References: resolving every carry, input and otherwise reference, then checking types,
//! sizes and stand-ins for gated-off passes.

use super::{Checker, PassInfo, Ref, ValueDesc};
use crate::decl::{Access, PortKind, PortSpec, SizeRule};
use crate::diagnostic::Location;
use crate::format::{TargetFormat, TargetSize};
use crate::graph::ast::{InputKind, NodeDoc, PassDoc};
use crate::graph::locate::PassPath;
use crate::suggest::{closest, comma_list, guess_then, quoted_list};

impl Checker<'_> {
    /// Parses `text` as a reference in the context of `group` (the group of the reader).
    pub(super) fn parse_ref(
        &mut self,
        text: &str,
        reader_group: Option<usize>,
        context: &str,
        location: Location,
    ) -> Option<Ref> {
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
    pub(super) fn ref_desc(&self, r: &Ref, depth: usize) -> Option<ValueDesc> {
        if depth > 32 {
            return None;
        }
        match r {
            Ref::Input(n) => match self.doc.inputs.get(n)? {
                InputKind::Volume => Some(ValueDesc::Volume),
                InputKind::TransferFunction => Some(ValueDesc::TransferFunction),
                InputKind::LabelTable => Some(ValueDesc::LabelTable),
                InputKind::Scalar(_) | InputKind::Data(_) => Some(ValueDesc::Scalar),
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

    pub(super) fn check_references(&mut self) {
        // Carry init/next first (inputs inside the body depend on them for types).
        for gi in 0..self.groups.len() {
            let Some(r) = self.doc_group(gi).cloned() else { continue };
            let top = self.doc.passes.iter().position(|n| matches!(n, NodeDoc::Repeat(x) if x.id == r.id)).unwrap_or(0);
            let path = PassPath { top, body: None };
            for (name, carry) in &r.carry {
                let ctx = format!("carry \"{name}\" of repeat group \"{}\"", r.id);
                let init_loc = self.loc.pass_entry_field(path, &r.id, "carry", name, "init");
                let next_loc = self.loc.pass_entry_field(path, &r.id, "carry", name, "next");
                let mut init = self.parse_ref(&carry.init, None, &ctx, init_loc.clone());
                if matches!(&init, Some(Ref::Carry { group, .. }) if *group == gi) {
                    self.err(
                        init_loc.clone(),
                        format!("{ctx} starts from \"{}\", a value the group itself carries", carry.init),
                        Some(
                            "init is the value before the first iteration: name an output of a pass outside the group"
                                .to_string(),
                        ),
                    );
                    init = None;
                }
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

    pub(super) fn require_stand_in(&mut self, producer: usize, port: &str, reader: &str, location: Location) {
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
            (PortKind::Volume | PortKind::VolumeVoxels, ValueDesc::Volume)
            | (PortKind::TransferFunction, ValueDesc::TransferFunction)
            | (PortKind::LabelTable, ValueDesc::LabelTable) => true,
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
                    PortKind::Volume | PortKind::VolumeVoxels => {
                        "declare inputs: {\"volume\": Volume} and read \"input.volume\"".to_string()
                    }
                    PortKind::TransferFunction => {
                        "declare inputs: {\"tf\": TransferFunction} and read \"input.tf\"".to_string()
                    }
                    PortKind::LabelTable => {
                        "declare inputs: {\"label_table\": LabelTable} and read \"input.label_table\"".to_string()
                    }
                    PortKind::Target { .. } => "read \"<pass>.<output>\" of a pass that writes a target".to_string(),
                    PortKind::Owned(t) => format!("read the output of a pass that makes a {t}"),
                    PortKind::Buffer { .. } => "read the output of a pass that writes a buffer".to_string(),
                }),
            );
        }
    }
}
