//! Graphviz DOT output.

use super::layout::Layout;
use super::{Highlight, Marks};
use crate::causality::{Causality, End};
use crate::ir::Model;
use std::fmt::Write;

fn quote(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// Renders DOT: one node per element (label `KIND:param\nname`), one edge per bond with a half-arrow head (`lvee`)
/// and, with a causality, a `tee` (the causal stroke) at the end that receives the effort.
pub fn render(model: &Model, lay: &Layout, causality: Option<&Causality>, marks: &Marks) -> String {
    let g = &model.graph;
    let mut out = format!("digraph {} {{\n", quote(&model.name));
    out.push_str("  rankdir=LR;\n  node [shape=plaintext, fontname=\"monospace\", fontsize=12];\n");
    out.push_str("  edge [arrowsize=0.8];\n");
    for i in g.node_indices() {
        let p = &lay.nodes[i.index()];
        let label = match &p.label.caption {
            Some(c) => format!("{}\\n{}", p.label.main, c),
            None => p.label.main.clone(),
        };
        let style = match marks
            .nodes
            .get(i.index())
            .copied()
            .unwrap_or(Highlight::None)
        {
            Highlight::Derivative => {
                ", shape=box, style=\"rounded,filled\", color=\"#c62828\", fillcolor=\"#fdecea\""
            }
            Highlight::Loop => {
                ", shape=box, style=\"rounded,filled\", color=\"#6a3d9a\", fillcolor=\"#f1e8fa\""
            }
            Highlight::None => "",
        };
        // Graphviz's y axis points up; positions are in points.
        let _ = writeln!(
            out,
            "  n{} [label={}, pos=\"{:.1},{:.1}!\"{style}];",
            i.index(),
            quote(&label).replace("\\\\n", "\\n"),
            p.x,
            lay.height - p.y
        );
    }
    for e in g.edge_indices() {
        let Some((a, b)) = g.edge_endpoints(e) else {
            continue;
        };
        let mut attrs = vec!["arrowhead=lvee".to_string()];
        if let Some(c) = causality {
            match c.effort_set_by.get(e.index()) {
                Some(End::From) => attrs[0] = "arrowhead=teelvee".to_string(),
                _ => {
                    attrs.push("dir=both".to_string());
                    attrs.push("arrowtail=tee".to_string());
                }
            }
        }
        if marks.loop_bonds.get(e.index()).copied().unwrap_or(false) {
            attrs.push("color=\"#6a3d9a\"".to_string());
        }
        if let Some(name) = &g[e].name {
            attrs.push(format!("label={}", quote(name)));
        }
        let _ = writeln!(
            out,
            "  n{} -> n{} [{}];",
            a.index(),
            b.index(),
            attrs.join(", ")
        );
    }
    out.push_str("}\n");
    out
}
