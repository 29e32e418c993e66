//! Graph outputs and history: what the graph yields and what it keeps for the next frame.

use std::collections::BTreeMap;

use super::{Checker, Ref, ValueDesc};
use crate::decl::PortKind;
use crate::diagnostic::Location;
use crate::graph::ast::HistoryInitial;
use crate::suggest::comma_list;

impl Checker<'_> {
    pub(super) fn check_graph_outputs(&mut self) -> BTreeMap<String, Ref> {
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

    pub(super) fn check_history(&mut self) -> BTreeMap<String, (Ref, HistoryInitial)> {
        let mut out = BTreeMap::new();
        for (name, h) in &self.doc.history.clone() {
            for pass in &h.reset_on_params_of {
                if !self.pass_by_id.contains_key(pass) {
                    let mut ids: Vec<&str> = self.pass_by_id.keys().map(String::as_str).collect();
                    ids.sort_unstable();
                    let help = crate::suggest::guess_then(
                        pass,
                        ids.iter().copied(),
                        "",
                        format!("passes are: {}", comma_list(&ids)),
                    );
                    self.err(
                        self.loc.top_entry_field("history", name, "reset_on_params_of"),
                        format!(
                            "history \"{name}\" resets when pass \"{pass}\" changes, but the graph has no such pass"
                        ),
                        Some(help),
                    );
                }
            }
            if let Some(d) = h.max_camera_degrees
                && !(d.is_finite() && d > 0.0 && d <= 180.0)
            {
                self.err(
                    self.loc.top_entry_field("history", name, "max_camera_degrees"),
                    format!("history \"{name}\": max_camera_degrees {d} is not an angle the camera can turn"),
                    Some(
                        "write the largest turn between frames that still reuses the history, in degrees, 0 < d <= 180"
                            .to_string(),
                    ),
                );
            }
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
}
