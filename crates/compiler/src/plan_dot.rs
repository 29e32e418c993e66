//! A plan as a Graphviz DOT picture (`volgraph plan GRAPH --dot`): passes as boxes in schedule
//! order, the values they write as ellipses labelled with format and pooled slot, graph inputs
//! and outputs at the ends; passes no output needs (culled) and passes a scene feature switched
//! off (gated) greyed; the steps of a repeat group boxed together; history edges (last frame's
//! value read this frame) dashed.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::plan::{Binding, Plan, ResourceDesc};

/// Quotes `s` as a DOT string (line breaks as `\n`, which Graphviz centres).
fn q(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n"))
}

impl Plan {
    /// The plan as a DOT digraph (render it with `dot -Tsvg`).
    pub fn to_dot(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "digraph {} {{", q(&self.name));
        let _ = writeln!(s, "  rankdir=LR; node [fontname=\"Helvetica\", fontsize=10]; edge [fontsize=9];");
        for (name, kind) in &self.inputs {
            let _ = writeln!(
                s,
                "  {} [shape=cds, label={}];",
                q(&format!("input.{name}")),
                q(&format!("{name}\n{kind:?}"))
            );
        }
        // Steps, grouped by repeat group (`group[i]/pass` labels).
        let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (i, step) in self.steps.iter().enumerate() {
            match (step.iteration, step.label.split_once('[')) {
                (Some(_), Some((group, _))) => groups.entry(group.to_string()).or_default().push(i),
                _ => {
                    let _ = writeln!(s, "  {};", self.step_node(i));
                }
            }
        }
        for (group, steps) in &groups {
            let _ = writeln!(s, "  subgraph {} {{", q(&format!("cluster_{group}")));
            let _ = writeln!(s, "    label={}; style=rounded;", q(&format!("repeat group {group}")));
            for i in steps {
                let _ = writeln!(s, "    {};", self.step_node(*i));
            }
            let _ = writeln!(s, "  }}");
        }
        for id in &self.culled {
            let _ = writeln!(
                s,
                "  {} [shape=box, style=dashed, color=grey60, fontcolor=grey60, label={}];",
                q(&format!("culled.{id}")),
                q(&format!("{id}\nculled: no output needs it"))
            );
        }
        for (id, features) in &self.gated {
            let _ = writeln!(
                s,
                "  {} [shape=box, style=dashed, color=grey60, fontcolor=grey60, label={}];",
                q(&format!("gated.{id}")),
                q(&format!("{id}\noff: needs {}", features.join(", ")))
            );
        }
        for (rid, r) in self.resources.iter().enumerate() {
            let what = match &r.desc {
                ResourceDesc::Target { format, extent, .. } => format!("{} {}×{}", format.name(), extent.0, extent.1),
                ResourceDesc::Buffer { size } => format!("buffer {size} B"),
                ResourceDesc::Owned(t) => format!("owned {t}"),
            };
            let slot = r.slot.map_or(String::new(), |slot| format!("\nslot {slot}"));
            let _ = writeln!(
                s,
                "  {} [shape=ellipse, label={}];",
                q(&format!("r{rid}")),
                q(&format!("{}\n{what}{slot}", r.name))
            );
            let _ = writeln!(s, "  {} -> {};", q(&format!("step{}", r.producer)), q(&format!("r{rid}")));
        }
        for (i, step) in self.steps.iter().enumerate() {
            for bp in step.ports.iter().filter(|p| p.access != crate::decl::Access::Write) {
                let from = match &bp.binding {
                    Binding::Resource { id, .. } => format!("r{id}"),
                    Binding::Input(n) | Binding::InputVoxels(n) => format!("input.{n}"),
                    Binding::History(n) => {
                        if let Some(h) = self.history.get(n) {
                            let _ = writeln!(
                                s,
                                "  {} -> {} [style=dashed, label={}];",
                                q(&format!("r{}", h.source)),
                                q(&format!("step{i}")),
                                q(&format!("{} (last frame)", bp.port))
                            );
                        }
                        continue;
                    }
                    Binding::Unbound => continue,
                };
                let _ = writeln!(s, "  {} -> {} [label={}];", q(&from), q(&format!("step{i}")), q(&bp.port));
            }
        }
        for (name, rid) in &self.outputs {
            let _ = writeln!(s, "  {} [shape=doublecircle, label={}];", q(&format!("output.{name}")), q(name));
            let _ = writeln!(s, "  {} -> {};", q(&format!("r{rid}")), q(&format!("output.{name}")));
        }
        s.push_str("}\n");
        s
    }

    fn step_node(&self, i: usize) -> String {
        let step = &self.steps[i];
        format!(
            "{} [shape=box, style=filled, fillcolor=\"#dde8f5\", label={}]",
            q(&format!("step{i}")),
            q(&format!("{}. {}\n{}", i + 1, step.label, step.kind))
        )
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn quotes_escape() {
        assert_eq!(super::q("a\"b"), "\"a\\\"b\"");
    }
}
