//! The plan as a picture in the viewer's panel — the same marks as `volgraph plan --dot`
//! (`Plan::to_dot`): passes as boxes in rows by dependency depth, data edges solid, history
//! edges (last frame's value) dashed, culled and gated passes greyed in a last row, repeat
//! groups boxed. [`layout`] and the geometry are pure (tested); [`show`] paints it with egui,
//! `crate::plan_svg` writes the same picture as SVG (`volgraph plan --svg`).

use std::collections::BTreeMap;

use volgraph_core::plan::{Binding, Plan};

/// One box.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// `label\nkind`.
    pub text: String,
    /// Dependency depth (the row it is drawn in) and its place among the nodes of that depth.
    pub at: (usize, usize),
    /// Culled or switched off by a feature.
    pub greyed: bool,
    /// The repeat group it belongs to.
    pub group: Option<String>,
}

/// One arrow between boxes.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// Node indices.
    pub from: usize,
    /// Node indices.
    pub to: usize,
    /// A history edge (last frame's value).
    pub dashed: bool,
}

/// The laid-out picture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Picture {
    /// Boxes: the plan's steps in order, then culled and gated passes.
    pub nodes: Vec<Node>,
    /// Arrows.
    pub edges: Vec<Edge>,
}

/// Box width and height, in points (egui) or pixels (SVG).
pub const BOX: (f32, f32) = (132.0, 32.0);
/// Space between boxes across and down.
pub const GAP: (f32, f32) = (12.0, 18.0);
/// Width of the lane right of the boxes where history edges run.
pub const LANE: f32 = 18.0;

impl Picture {
    /// Columns and rows of boxes.
    fn grid(&self) -> (f32, f32) {
        let cols = self.nodes.iter().map(|n| n.at.1 + 1).max().unwrap_or(1) as f32;
        let rows = self.nodes.iter().map(|n| n.at.0 + 1).max().unwrap_or(1) as f32;
        (cols, rows)
    }

    /// The drawing's width and height, lane included.
    pub fn size(&self) -> (f32, f32) {
        let (cols, rows) = self.grid();
        (cols * (BOX.0 + GAP.0) + LANE, rows * (BOX.1 + GAP.1))
    }

    /// Top-left corner of a node's box: its depth is its row (top to bottom).
    pub fn corner(&self, n: &Node) -> (f32, f32) {
        (n.at.1 as f32 * (BOX.0 + GAP.0), n.at.0 as f32 * (BOX.1 + GAP.1))
    }

    /// The x of the history-edge lane.
    pub fn lane_x(&self) -> f32 {
        self.grid().0 * (BOX.0 + GAP.0) + LANE * 0.5
    }
}

/// Lays `plan` out: a step's column is one more than the deepest step it reads from.
pub fn layout(plan: &Plan) -> Picture {
    let mut depth = vec![0usize; plan.steps.len()];
    let mut edges = Vec::new();
    for (i, step) in plan.steps.iter().enumerate() {
        for bp in step.ports.iter().filter(|p| p.access != volgraph_core::Access::Write) {
            match &bp.binding {
                Binding::Resource { id, .. } => {
                    let from = plan.resources[*id].producer;
                    if from < i {
                        depth[i] = depth[i].max(depth[from] + 1);
                        edges.push(Edge { from, to: i, dashed: false });
                    }
                }
                Binding::History(name) => {
                    if let Some(h) = plan.history.get(name) {
                        edges.push(Edge { from: plan.resources[h.source].producer, to: i, dashed: true });
                    }
                }
                _ => {}
            }
        }
    }
    edges.dedup();
    let mut rows: BTreeMap<usize, usize> = BTreeMap::new();
    let mut nodes: Vec<Node> = plan
        .steps
        .iter()
        .enumerate()
        .map(|(i, step)| {
            let row = rows.entry(depth[i]).or_default();
            let at = (depth[i], *row);
            *row += 1;
            let group = step.iteration.and_then(|_| step.label.split_once('[').map(|(g, _)| g.to_string()));
            Node { text: format!("{}\n{}", step.label, step.kind), at, greyed: false, group }
        })
        .collect();
    let last = depth.iter().max().map_or(0, |d| d + 1);
    let off = plan
        .culled
        .iter()
        .map(|id| format!("{id}\nculled"))
        .chain(plan.gated.iter().map(|(id, f)| format!("{id}\noff: {}", f.join(", "))));
    for (row, text) in off.enumerate() {
        nodes.push(Node { text, at: (last, row), greyed: true, group: None });
    }
    Picture { nodes, edges }
}

/// Paints `plan`'s picture into `ui`, top to bottom (the panel is narrow): a node's depth is its
/// row. Data edges run down between boxes; history edges (last frame's value, pointing back up)
/// run dashed in a lane right of the boxes, so they never cross a label.
pub fn show(ui: &mut egui::Ui, plan: &Plan) {
    let picture = layout(plan);
    let (width, height) = picture.size();
    let (response, painter) = ui.allocate_painter(egui::vec2(width, height), egui::Sense::hover());
    let origin = response.rect.min + egui::vec2(0.0, 4.0);
    let rect_of = |n: &Node| {
        let (x, y) = picture.corner(n);
        egui::Rect::from_min_size(origin + egui::vec2(x, y), egui::vec2(BOX.0, BOX.1))
    };
    let text_color = ui.visuals().text_color();
    let stroke = egui::Stroke::new(1.0, text_color);
    // Repeat groups: one rounded box around their steps.
    let mut groups: BTreeMap<&str, egui::Rect> = BTreeMap::new();
    for n in &picture.nodes {
        if let Some(g) = &n.group {
            let r = rect_of(n).expand(4.0);
            groups.entry(g).and_modify(|u| *u = u.union(r)).or_insert(r);
        }
    }
    for r in groups.values() {
        painter.rect_stroke(*r, 6.0, egui::Stroke::new(1.0, egui::Color32::GRAY), egui::StrokeKind::Outside);
    }
    let lane_x = origin.x + picture.lane_x();
    for e in &picture.edges {
        let (a, b) = (rect_of(&picture.nodes[e.from]), rect_of(&picture.nodes[e.to]));
        if e.dashed {
            let path = [
                a.right_center(),
                egui::pos2(lane_x, a.center().y),
                egui::pos2(lane_x, b.center().y),
                b.right_center(),
            ];
            painter.extend(egui::Shape::dashed_line(&path, stroke, 4.0, 3.0));
        } else {
            let (p, q) = (a.center_bottom(), b.center_top());
            painter.arrow(p, q - p, stroke);
        }
    }
    for n in &picture.nodes {
        let r = rect_of(n);
        let (fill, color) = if n.greyed {
            (ui.visuals().extreme_bg_color, egui::Color32::GRAY)
        } else {
            (ui.visuals().faint_bg_color, text_color)
        };
        painter.rect_filled(r, 3.0, fill);
        painter.rect_stroke(r, 3.0, egui::Stroke::new(1.0, color), egui::StrokeKind::Inside);
        painter.text(r.center(), egui::Align2::CENTER_CENTER, &n.text, egui::FontId::proportional(10.0), color);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use volgraph_core::{CompileOptions, compile};

    /// The 64×64 plan of a shipped graph (`graphs/` relative path); also `plan_svg`'s tests'.
    pub(crate) fn plan(graph: &str) -> Plan {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs").join(graph);
        let source = std::fs::read_to_string(&path).expect("graph");
        compile(graph, &source, &volgraph_passes::builtin_registry(), &CompileOptions::new(64, 64)).expect("compiles")
    }

    /// The marks of `--dot`: columns follow dependencies, history edges are dashed, repeat
    /// groups are grouped.
    #[test]
    fn the_picture_has_the_marks_of_the_dot_output() {
        let p = layout(&plan("klein_2005/leap_iso.ron"));
        let march = p.nodes.iter().position(|n| n.text.starts_with("march\n")).expect("march");
        let bounds = p.nodes.iter().position(|n| n.text.starts_with("bounds\n")).expect("bounds");
        assert!(p.nodes[march].at.0 > p.nodes[bounds].at.0, "the raycast comes after the bounds");
        assert!(p.edges.iter().any(|e| e.dashed && e.from == march && e.to == bounds), "last frame's hits: dashed");
        let rc = layout(&plan("kruger_westermann_2003/rc.ron"));
        assert!(rc.nodes.iter().any(|n| n.group.is_some()), "the segment loop is a group");
    }

    /// Painting every shipped kind of mark runs without a window (egui alone), and draws a box
    /// per node.
    #[test]
    fn the_picture_paints_headless() {
        for graph in ["klein_2005/leap_iso_aa.ron", "kruger_westermann_2003/rc.ron", "modern/fastest.ron"] {
            let plan = plan(graph);
            let ctx = egui::Context::default();
            let mut output = ctx.run_ui(egui::RawInput::default(), |ui| show(ui, &plan));
            // No renderer here to take the font atlas upload (egui checks, in debug builds).
            output.textures_delta.clear();
            let shapes = output.shapes.len();
            assert!(shapes >= layout(&plan).nodes.len(), "{graph}: {shapes} shapes");
        }
    }
}
