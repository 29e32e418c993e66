//! Bypasses: passes a graph lets the runtime leave out while a measurement of the last frames
//! says they do not pay (Klein et al. 2005's reprojection where rays meet the surface at once).
//! Everything that would make leaving them out change the image other than as declared is an
//! error here: a reader of their outputs that does not read zeros as "none", history or a graph
//! output taken from them, a measure they would stop writing.

use std::collections::BTreeMap;

use super::{Checker, Ref};
use crate::decl::{Access, PortKind};
use crate::graph::ast::{BypassDoc, Threshold};
use crate::suggest::{comma_list, guess_then};

/// A bypass, resolved: the passes (indices into `Checked::passes`), the measuring pass and
/// its buffer port, the threshold per pixel.
#[derive(Clone, Debug)]
pub(crate) struct CheckedBypass {
    pub name: String,
    pub passes: Vec<usize>,
    pub measure: (usize, String),
    pub below: f64,
}

impl Checker<'_> {
    pub(super) fn check_bypasses(
        &mut self,
        outputs: &BTreeMap<String, Ref>,
        history: &BTreeMap<String, (Ref, crate::graph::ast::HistoryInitial)>,
    ) -> Vec<CheckedBypass> {
        let mut out = Vec::new();
        for (name, doc) in &self.doc.bypass.clone() {
            if let Some(b) = self.check_bypass(name, doc, outputs, history) {
                out.push(b);
            }
        }
        // A pass is left out by one measurement at most: two bypasses deciding about it would
        // disagree.
        let mut owner: BTreeMap<usize, &str> = BTreeMap::new();
        let mut twice = Vec::new();
        for b in &out {
            for &p in &b.passes {
                if let Some(first) = owner.insert(p, &b.name) {
                    twice.push((b.name.clone(), first.to_string(), self.passes[p].id.clone()));
                }
            }
        }
        for (name, first, pass) in twice {
            self.err(
                self.loc.top_entry_field("bypass", &name, "passes"),
                format!("bypass \"{name}\" leaves out pass \"{pass}\", which bypass \"{first}\" already leaves out"),
                Some("name each pass in one bypass".to_string()),
            );
        }
        out
    }

    fn check_bypass(
        &mut self,
        name: &str,
        doc: &BypassDoc,
        outputs: &BTreeMap<String, Ref>,
        history: &BTreeMap<String, (Ref, crate::graph::ast::HistoryInitial)>,
    ) -> Option<CheckedBypass> {
        let at_passes = self.loc.top_entry_field("bypass", name, "passes");
        let mut ids: Vec<String> = self.pass_by_id.keys().cloned().collect();
        ids.sort_unstable();
        let mut passes = Vec::new();
        let mut ok = true;
        if doc.passes.is_empty() {
            self.err(
                at_passes.clone(),
                format!("bypass \"{name}\" names no passes to leave out"),
                Some(format!("name the passes that cost more than they save, among: {}", comma_list(&ids))),
            );
            ok = false;
        }
        for id in &doc.passes {
            match self.pass_by_id.get(id) {
                Some(&p) if self.passes[p].group.is_some() => {
                    self.err(
                        at_passes.clone(),
                        format!("bypass \"{name}\" names pass \"{id}\", which is inside a repeat group"),
                        Some("bypass passes outside repeat groups".to_string()),
                    );
                    ok = false;
                }
                Some(&p) => passes.push(p),
                None => {
                    let help =
                        guess_then(id, ids.iter().map(String::as_str), "", format!("passes are: {}", comma_list(&ids)));
                    self.err(
                        at_passes.clone(),
                        format!("bypass \"{name}\" names pass \"{id}\", which the graph does not have"),
                        Some(help),
                    );
                    ok = false;
                }
            }
        }
        let measure = self.check_measure(name, doc, &passes);
        let below = self.check_threshold(name, &doc.below);
        // Passes gated off by the scene's features are not run anyway.
        let left_out: Vec<usize> = passes.iter().copied().filter(|&p| self.passes[p].enabled).collect();
        ok &= self.check_readers(name, &left_out);
        for (output, r) in outputs {
            if let Ref::Output { pass, port } = r
                && left_out.contains(pass)
            {
                self.err(
                    self.loc.top_entry("outputs", output, false),
                    format!(
                        "graph output \"{output}\" is \"{}.{port}\", which bypass \"{name}\" may leave unwritten",
                        self.passes[*pass].id
                    ),
                    Some("name an output of a pass that always runs".to_string()),
                );
                ok = false;
            }
        }
        for (kept, (r, _)) in history {
            if let Ref::Output { pass, port } = r
                && left_out.contains(pass)
            {
                self.err(
                    self.loc.top_entry_field("history", kept, "of"),
                    format!(
                        "history \"{kept}\" keeps \"{}.{port}\", which bypass \"{name}\" may leave unwritten",
                        self.passes[*pass].id
                    ),
                    Some("keep a target of a pass that always runs (it would go stale while bypassed)".to_string()),
                );
                ok = false;
            }
        }
        Some(CheckedBypass { name: name.to_string(), passes: left_out, measure: measure?, below: below? })
            .filter(|_| ok)
    }

    /// `measure`: a buffer output of a pass that runs, outside the bypass.
    fn check_measure(&mut self, name: &str, doc: &BypassDoc, passes: &[usize]) -> Option<(usize, String)> {
        let at = self.loc.top_entry_field("bypass", name, "measure");
        let Some((head, port)) = doc.measure.split_once('.') else {
            self.err(
                at,
                format!("bypass \"{name}\" measures \"{}\", which is not of the form \"<pass>.<output>\"", doc.measure),
                Some("name a buffer a pass that always runs counts into, e.g. \"march.leapable\"".to_string()),
            );
            return None;
        };
        let Some(&p) = self.pass_by_id.get(head) else {
            let mut ids: Vec<&str> = self.pass_by_id.keys().map(String::as_str).collect();
            ids.sort_unstable();
            let help = guess_then(head, ids.iter().copied(), "", format!("passes are: {}", comma_list(&ids)));
            self.err(
                at,
                format!("bypass \"{name}\" measures \"{}\", but the graph has no pass \"{head}\"", doc.measure),
                Some(help),
            );
            return None;
        };
        let info = &self.passes[p];
        let spec = info.ports.iter().find(|s| s.name == port && s.is_output());
        if !matches!(spec.map(|s| &s.kind), Some(PortKind::Buffer { .. })) {
            let buffers: Vec<&str> = info
                .ports
                .iter()
                .filter(|s| s.is_output() && matches!(s.kind, PortKind::Buffer { .. }))
                .map(|s| s.name)
                .collect();
            let help = if buffers.is_empty() {
                format!(
                    "pass \"{head}\" ({}) writes no buffer with these parameters; a raycast with leap_hits and count_leapable writes \"leapable\"",
                    info.kind
                )
            } else {
                guess_then(port, buffers.iter().copied(), "", format!("its buffers are: {}", comma_list(&buffers)))
            };
            self.err(
                at,
                format!("bypass \"{name}\" measures \"{}\", which is not a buffer pass \"{head}\" writes", doc.measure),
                Some(help),
            );
            return None;
        }
        if passes.contains(&p) || info.group.is_some() || !info.enabled {
            let why = if passes.contains(&p) {
                "is one of the passes it leaves out (the measure would stop)"
            } else if info.group.is_some() {
                "is inside a repeat group"
            } else {
                "is off for these features"
            };
            self.err(
                at,
                format!("bypass \"{name}\" measures \"{}\", but pass \"{head}\" {why}", doc.measure),
                Some("measure with a pass that runs every frame, outside the bypass".to_string()),
            );
            return None;
        }
        Some((p, port.to_string()))
    }

    /// `below`: a finite, positive number or the value of a Scalar input.
    fn check_threshold(&mut self, name: &str, below: &Threshold) -> Option<f64> {
        let at = self.loc.top_entry_field("bypass", name, "below");
        let value = match below {
            Threshold::Value(v) => *v,
            Threshold::Input(text) => match text.strip_prefix("input.").and_then(|n| self.scalar_value(n)) {
                Some(v) => v,
                None => {
                    self.err(
                        at,
                        format!("bypass \"{name}\" is below \"{text}\", which is not a Scalar graph input"),
                        Some(
                            "write a number, or \"input.NAME\" with inputs: {\"NAME\": Scalar(<default>)}".to_string(),
                        ),
                    );
                    return None;
                }
            },
        };
        if !(value.is_finite() && value > 0.0) {
            self.err(
                at,
                format!("bypass \"{name}\": threshold {value} is not a positive number"),
                Some("write the measure per pixel under which the passes do not pay, e.g. 16.0".to_string()),
            );
            return None;
        }
        Some(value)
    }

    /// Every pass that still runs reads the bypassed passes' outputs only through ports that
    /// read zeros as "none".
    fn check_readers(&mut self, name: &str, left_out: &[usize]) -> bool {
        let mut problems = Vec::new();
        for (reader, info) in self.passes.iter().enumerate() {
            if left_out.contains(&reader) || !info.enabled {
                continue;
            }
            for (port, r) in &info.inputs {
                let Ref::Output { pass, port: written } = r else { continue };
                if !left_out.contains(pass) {
                    continue;
                }
                let spec = info.ports.iter().find(|s| s.name == port);
                let tolerant = spec.is_some_and(|s| s.access == Access::Read && s.zero_means_none);
                if !tolerant {
                    problems.push((
                        info.path,
                        info.id.clone(),
                        info.kind.clone(),
                        port.clone(),
                        self.passes[*pass].id.clone(),
                        written.clone(),
                    ));
                }
            }
        }
        let ok = problems.is_empty();
        for (path, id, kind, port, writer, written) in problems {
            self.err(
                self.loc.pass_entry(path, &id, "inputs", &port, false),
                format!(
                    "input \"{port}\" of pass \"{id}\" reads \"{writer}.{written}\", which bypass \"{name}\" may leave out; \
                     {kind}'s \"{port}\" does not read zeros as \"none\""
                ),
                Some(format!(
                    "add \"{id}\" to the bypass's passes, or read \"{writer}.{written}\" only through ports that may be left \
                     unwired without changing the image (raycast's \"start\")"
                )),
            );
        }
        ok
    }
}
