//! SVG rendering of a laid-out bond graph.

use super::layout::{LINE_H, Layout, MARGIN, Placed};
use super::{Highlight, Marks};
use crate::causality::{Causality, End};
use crate::ir::Model;
use std::fmt::Write;

const DERIVATIVE: (&str, &str) = ("#c62828", "#fdecea");
const LOOP: (&str, &str) = ("#6a3d9a", "#f1e8fa");
const FONT: &str = "DejaVu Sans Mono, Menlo, Consolas, monospace";
const LEGEND_H: f64 = 92.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Unit direction of the last segment of a polyline, and its left normal (in screen coordinates).
fn end_frame(a: (f64, f64), b: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = (dx * dx + dy * dy).sqrt().max(1e-9);
    let d = (dx / len, dy / len);
    (d, (d.1, -d.0))
}

fn line(out: &mut String, a: (f64, f64), b: (f64, f64), colour: &str, width: f64) {
    let _ = writeln!(
        out,
        r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="{width}"/>"#,
        a.0, a.1, b.0, b.1
    );
}

fn node(out: &mut String, model: &Model, i: usize, p: &Placed, mark: Highlight) {
    let (stroke, fill) = match mark {
        Highlight::Derivative => DERIVATIVE,
        Highlight::Loop => LOOP,
        Highlight::None => ("none", "#ffffff"),
    };
    let junction = model
        .graph
        .node_weights()
        .nth(i)
        .is_some_and(|w| w.kind.is_junction());
    let _ = writeln!(
        out,
        r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" rx="5" fill="{fill}" stroke="{stroke}" stroke-width="1.5"/>"#,
        p.x - p.w / 2.0,
        p.y - p.h / 2.0,
        p.w,
        p.h
    );
    if junction {
        let sub = p.label.caption.as_deref().unwrap_or("");
        let _ = writeln!(
            out,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-weight="bold" font-size="13">{}<tspan font-size="10" font-weight="normal" fill="#555" dy="4">{}</tspan></text>"##,
            p.x,
            p.y + 4.5,
            esc(&p.label.main),
            esc(sub)
        );
        return;
    }
    let first_y = if p.label.caption.is_some() {
        p.y - LINE_H / 2.0 + 4.5
    } else {
        p.y + 4.5
    };
    let _ = writeln!(
        out,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="12">{}</text>"#,
        p.x,
        first_y,
        esc(&p.label.main)
    );
    if let Some(c) = &p.label.caption {
        let _ = writeln!(
            out,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="10" fill="#555">{}</text>"##,
            p.x,
            first_y + LINE_H,
            esc(c)
        );
    }
}

/// Renders the layout as SVG.
pub fn render(model: &Model, lay: &Layout, causality: Option<&Causality>, marks: &Marks) -> String {
    let height = lay.height + LEGEND_H + LINE_H;
    // Wide enough for the legend's longest line.
    let width = lay.width.max(MARGIN * 2.0 + 44.0 + 64.0 * 6.7);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="{FONT}">"#
    );
    let _ = writeln!(out, "<title>{}</title>", esc(&model.name));
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="{MARGIN}" y="18" font-size="13" font-weight="bold">{}</text>"#,
        esc(&model.name)
    );
    let _ = writeln!(out, r#"<g transform="translate(0,{LINE_H})">"#);

    // Bonds first, so that labels sit on top.
    let graph = &model.graph;
    for (e, pts) in graph.edge_indices().zip(&lay.bonds) {
        let (Some(&first), Some(&last)) = (pts.first(), pts.last()) else {
            continue;
        };
        let colour = if marks.loop_bonds.get(e.index()).copied().unwrap_or(false) {
            LOOP.0
        } else {
            "#222"
        };
        let path: Vec<String> = pts
            .iter()
            .map(|p| format!("{:.1},{:.1}", p.0, p.1))
            .collect();
        let _ = writeln!(
            out,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
            path.join(" ")
        );
        // Half-arrow at the `to` end.
        let before_last = pts.get(pts.len().wrapping_sub(2)).copied().unwrap_or(first);
        let (d, nrm) = end_frame(before_last, last);
        let barb = (
            last.0 - 11.0 * d.0 + 7.0 * nrm.0,
            last.1 - 11.0 * d.1 + 7.0 * nrm.1,
        );
        line(&mut out, last, barb, colour, 1.5);
        // Causal stroke at the end that receives the effort.
        if let Some(c) = causality {
            let (at, frame) = match c.effort_set_by.get(e.index()) {
                Some(End::From) => (last, (d, nrm)),
                _ => {
                    let after_first = pts.get(1).copied().unwrap_or(last);
                    (first, end_frame(after_first, first))
                }
            };
            let n = frame.1;
            line(
                &mut out,
                (at.0 + 8.0 * n.0, at.1 + 8.0 * n.1),
                (at.0 - 8.0 * n.0, at.1 - 8.0 * n.1),
                colour,
                2.0,
            );
        }
        // Port numbers at field ends.
        let bond = &graph[e];
        if let Some((a, b)) = graph.edge_endpoints(e) {
            for (node, port, at, toward) in [
                (
                    a,
                    bond.from_port,
                    first,
                    pts.get(1).copied().unwrap_or(last),
                ),
                (b, bond.to_port, last, before_last),
            ] {
                if graph[node].kind.is_field() {
                    let (dd, nn) = end_frame(at, toward);
                    let _ = writeln!(
                        out,
                        r##"<text x="{:.1}" y="{:.1}" font-size="10" fill="#555" text-anchor="middle">{}</text>"##,
                        at.0 + 14.0 * dd.0 - 10.0 * nn.0,
                        at.1 + 14.0 * dd.1 - 10.0 * nn.1 + 3.0,
                        port + 1
                    );
                }
            }
        }
    }
    for (i, p) in lay.nodes.iter().enumerate() {
        let mark = marks.nodes.get(i).copied().unwrap_or(Highlight::None);
        node(&mut out, model, i, p, mark);
    }
    out.push_str("</g>\n");
    legend(&mut out, lay.height + LINE_H, causality.is_some());
    out.push_str("</svg>\n");
    out
}

fn legend(out: &mut String, top: f64, with_causality: bool) {
    let x = MARGIN;
    let mut y = top + 14.0;
    let text = |out: &mut String, y: f64, s: &str| {
        let _ = writeln!(
            out,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" fill="#333">{}</text>"##,
            x + 44.0,
            y + 4.0,
            esc(s)
        );
    };
    line(out, (x, y), (x + 32.0, y), "#222", 1.5);
    line(out, (x + 32.0, y), (x + 21.0, y - 7.0), "#222", 1.5);
    text(
        out,
        y,
        "bond; the half-arrow points in the direction of positive power",
    );
    if !with_causality {
        return;
    }
    y += 18.0;
    line(out, (x, y), (x + 32.0, y), "#222", 1.5);
    line(out, (x + 32.0, y - 8.0), (x + 32.0, y + 8.0), "#222", 2.0);
    text(
        out,
        y,
        "causal stroke: the element at this end receives the effort",
    );
    for (colours, s) in [
        (DERIVATIVE, "storage in derivative causality"),
        (
            LOOP,
            "element on an algebraic loop (zero-order causal path)",
        ),
    ] {
        y += 18.0;
        let _ = writeln!(
            out,
            r#"<rect x="{:.1}" y="{:.1}" width="32" height="12" rx="3" fill="{}" stroke="{}" stroke-width="1.5"/>"#,
            x,
            y - 6.0,
            colours.1,
            colours.0
        );
        text(out, y, s);
    }
}
