//! `volgraph plan GRAPH --svg`: the viewer's plan picture ([`crate::view::graph_picture`]) as a
//! standalone SVG, so a plan can be drawn without Graphviz or any other system tool. Same
//! layout and marks: boxes in rows by dependency depth, data edges as arrows, history edges
//! dashed in a lane right of the boxes, culled and gated passes greyed in a last row, repeat
//! groups in a rounded box.

use std::collections::BTreeMap;
use std::fmt::Write;

use volgraph_core::plan::Plan;

use crate::view::graph_picture::{BOX, Node, layout};

/// Margin around the drawing.
const MARGIN: f32 = 8.0;

/// The SVG text of `plan`'s picture.
pub fn plan_svg(plan: &Plan) -> String {
    let picture = layout(plan);
    let (width, height) = picture.size();
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="{x} {x} {w} {h}" font-family="sans-serif" font-size="10">"#,
        w = width + 2.0 * MARGIN,
        h = height + 2.0 * MARGIN,
        x = -MARGIN,
    );
    svg.push_str(
        r#"<defs><marker id="arrow" viewBox="0 0 8 8" refX="8" refY="4" markerWidth="7" markerHeight="7" orient="auto"><path d="M0,0 L8,4 L0,8 z" fill="black"/></marker></defs>
"#,
    );
    let rect_of = |n: &Node| picture.corner(n);
    // Repeat groups: one rounded box around their steps.
    let mut groups: BTreeMap<&str, (f32, f32, f32, f32)> = BTreeMap::new();
    for n in &picture.nodes {
        if let Some(g) = &n.group {
            let (x, y) = rect_of(n);
            let r = (x - 4.0, y - 4.0, x + BOX.0 + 4.0, y + BOX.1 + 4.0);
            groups.entry(g).and_modify(|u| *u = (u.0.min(r.0), u.1.min(r.1), u.2.max(r.2), u.3.max(r.3))).or_insert(r);
        }
    }
    for (name, (x0, y0, x1, y1)) in &groups {
        let _ = writeln!(
            svg,
            r#"<rect x="{x0}" y="{y0}" width="{}" height="{}" rx="6" fill="none" stroke="gray"><title>repeat group {}</title></rect>"#,
            x1 - x0,
            y1 - y0,
            escape(name)
        );
    }
    let lane_x = picture.lane_x();
    for e in &picture.edges {
        let ((ax, ay), (bx, by)) = (rect_of(&picture.nodes[e.from]), rect_of(&picture.nodes[e.to]));
        if e.dashed {
            // From the source box's right edge out to the lane, along it, back into the target's.
            let (ay, by) = (ay + BOX.1 / 2.0, by + BOX.1 / 2.0);
            let _ = writeln!(
                svg,
                r#"<polyline points="{},{ay} {lane_x},{ay} {lane_x},{by} {},{by}" fill="none" stroke="black" stroke-dasharray="4 3" marker-end="url(#arrow)"/>"#,
                ax + BOX.0,
                bx + BOX.0,
            );
        } else {
            let _ = writeln!(
                svg,
                r#"<line x1="{}" y1="{}" x2="{}" y2="{by}" stroke="black" marker-end="url(#arrow)"/>"#,
                ax + BOX.0 / 2.0,
                ay + BOX.1,
                bx + BOX.0 / 2.0,
            );
        }
    }
    for n in &picture.nodes {
        let (x, y) = rect_of(n);
        let (fill, color) = if n.greyed { ("#eeeeee", "gray") } else { ("#f8f8f8", "black") };
        let _ = writeln!(
            svg,
            r#"<rect x="{x}" y="{y}" width="{}" height="{}" rx="3" fill="{fill}" stroke="{color}"/>"#,
            BOX.0, BOX.1
        );
        let lines: Vec<&str> = n.text.lines().collect();
        let cx = x + BOX.0 / 2.0;
        let top = y + BOX.1 / 2.0 - 6.0 * (lines.len() as f32 - 1.0) + 3.5;
        let _ = write!(svg, r#"<text x="{cx}" y="{top}" text-anchor="middle" fill="{color}">"#);
        for (i, line) in lines.iter().enumerate() {
            let dy = if i == 0 { 0.0 } else { 12.0 };
            let _ = write!(svg, r#"<tspan x="{cx}" dy="{dy}">{}</tspan>"#, escape(line));
        }
        svg.push_str("</text>\n");
    }
    svg.push_str("</svg>\n");
    svg
}

/// `text` with XML's special characters escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::graph_picture::tests::plan;

    /// The SVG is well-formed XML with a box per node, an arrow per data edge, a dashed path per
    /// history edge and a rounded box per repeat group.
    #[test]
    fn the_svg_has_every_mark_of_the_picture() {
        for graph in ["klein_2005/leap_iso_aa.ron", "kruger_westermann_2003/rc.ron", "modern/fastest.ron"] {
            let plan = plan(graph);
            let picture = layout(&plan);
            let svg = plan_svg(&plan);
            let doc = check_well_formed(&svg);
            assert_eq!(doc.rects_with_rx3, picture.nodes.len(), "{graph}: a box per node");
            let data = picture.edges.iter().filter(|e| !e.dashed).count();
            let history = picture.edges.iter().filter(|e| e.dashed).count();
            assert_eq!(svg.matches("<line ").count(), data, "{graph}");
            assert_eq!(svg.matches("stroke-dasharray").count(), history, "{graph}");
            // Each history edge leaves its source box's right edge and ends at its target's.
            for e in picture.edges.iter().filter(|e| e.dashed) {
                let ((ax, ay), (bx, by)) =
                    (picture.corner(&picture.nodes[e.from]), picture.corner(&picture.nodes[e.to]));
                let (ay, by) = (ay + BOX.1 / 2.0, by + BOX.1 / 2.0);
                let lane = picture.lane_x();
                let points = format!(r#"points="{},{ay} {lane},{ay} {lane},{by} {},{by}""#, ax + BOX.0, bx + BOX.0);
                assert!(svg.contains(&points), "{graph}: {points}");
            }
            let groups: std::collections::BTreeSet<_> = picture.nodes.iter().filter_map(|n| n.group.clone()).collect();
            assert_eq!(svg.matches("<title>repeat group").count(), groups.len(), "{graph}");
            for n in &picture.nodes {
                let first = n.text.lines().next().expect("a label");
                assert!(svg.contains(&format!(">{}</tspan>", escape(first))), "{graph}: {first}");
            }
        }
        assert!(plan_svg(&plan("klein_2005/leap_iso.ron")).contains("stroke-dasharray"), "history edges are dashed");
        assert!(plan_svg(&plan("kruger_westermann_2003/rc.ron")).contains("repeat group"), "the segment loop is boxed");
    }

    /// `volgraph plan GRAPH --svg` prints it; `--dot` and `--svg` together are a usage error.
    #[test]
    fn the_plan_command_prints_it() {
        use clap::Parser;
        let graph = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/klein_2005/leap_iso.ron");
        let graph = graph.to_str().expect("a UTF-8 path");
        let cli = crate::cli::Cli::try_parse_from(["volgraph", "plan", graph, "--svg"]).expect("parses");
        match crate::cli::check(cli) {
            Ok(crate::cli::Checked::Plan { text, .. }) => {
                assert!(text.starts_with("<svg ") && text.trim_end().ends_with("</svg>"), "{text}")
            }
            Ok(_) => panic!("a plan command gives a plan"),
            Err(crate::cli::CliError::Graph(d)) => panic!("{d}"),
            Err(crate::cli::CliError::Other(e)) => panic!("{e}"),
        }
        let both = crate::cli::Cli::try_parse_from(["volgraph", "plan", graph, "--svg", "--dot"]);
        assert!(both.is_err(), "one picture format at a time");
    }

    struct Counts {
        rects_with_rx3: usize,
    }

    /// Checks that every element opened is closed in order (well-formed for this writer's
    /// subset: no comments, no CDATA) and counts the node boxes.
    fn check_well_formed(svg: &str) -> Counts {
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = rest[start..].find('>').expect("a tag is closed") + start;
            let tag = &rest[start + 1..end];
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop().as_deref(), Some(name), "closing tag matches");
            } else if !tag.ends_with('/') {
                stack.push(tag.split_whitespace().next().expect("a name").to_string());
            }
            rest = &rest[end + 1..];
        }
        assert!(stack.is_empty(), "unclosed: {stack:?}");
        Counts { rects_with_rx3: svg.matches(r#"rx="3""#).count() }
    }
}
