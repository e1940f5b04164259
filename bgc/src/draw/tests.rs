//! Layout and rendering checks: geometry (no overlapping boxes, bonds not crossing other elements) and content.

use super::layout::{Layout, layout};
use crate::causality::test_model::Builder;
use crate::ir::Model;
use crate::syntax::ast::ElementKind as K;

/// The back-support exoskeleton of Fig. 6 (Shojaei Barjuei et al., Designs 2020), from `models/back_support.bg`.
pub fn back_support() -> Model {
    let text = include_str!("../../../models/back_support.bg");
    let mut sources = crate::span::SourceMap::new();
    let root = sources.add("back_support.bg", text);
    let (mut models, diags) =
        crate::lower::lower(&mut sources, root, &mut crate::lower::MemoryLoader::new());
    assert!(!crate::diagnostic::has_errors(&diags), "{diags:?}");
    models.remove(0)
}

/// A small hand-built graph with a field, a gyrator and a long bond that skips a layer.
fn assorted() -> Model {
    let mut b = Builder::new("assorted");
    let se = b.node(K::Se, "u");
    let j1 = b.node(K::One, "a");
    let gy = b.node(K::GY, "emf");
    let j2 = b.node(K::One, "b");
    let c = b.node(K::C, "spring");
    let z = b.node(K::Zero, "c");
    let mass = crate::ir::Relation::MassMatrix {
        n: 2,
        entries: vec![crate::ir::Expr::Const(1.0); 4],
    };
    let leg = b.add(K::IF, "leg", mass, 2);
    b.chain(&[se, j1, gy, j2, z]);
    b.bond(j1, z);
    b.bond(z, c);
    b.bond_full(j2, None, leg, Some(0), None);
    b.bond_full(z, None, leg, Some(1), None);
    b.finish().0
}

fn overlap(a: (f64, f64, f64, f64), b: (f64, f64, f64, f64)) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Whether segment p-q passes through the rectangle (x0, y0, x1, y1) (Liang-Barsky clipping).
fn crosses(p: (f64, f64), q: (f64, f64), r: (f64, f64, f64, f64)) -> bool {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let mut t0: f64 = 0.0;
    let mut t1: f64 = 1.0;
    for (pp, qq) in [
        (-dx, p.0 - r.0),
        (dx, r.2 - p.0),
        (-dy, p.1 - r.1),
        (dy, r.3 - p.1),
    ] {
        if pp.abs() < 1e-12 {
            if qq < 0.0 {
                return false;
            }
        } else {
            let t = qq / pp;
            if pp < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 < t1
}

pub fn check_geometry(model: &Model, lay: &Layout) {
    let rects: Vec<(f64, f64, f64, f64)> = lay
        .nodes
        .iter()
        .map(|p| {
            (
                p.x - p.w / 2.0,
                p.y - p.h / 2.0,
                p.x + p.w / 2.0,
                p.y + p.h / 2.0,
            )
        })
        .collect();
    for i in 0..rects.len() {
        for j in i + 1..rects.len() {
            assert!(
                !overlap(rects[i], rects[j]),
                "labels of `{}` and `{}` overlap",
                model.graph[petgraph::graph::NodeIndex::new(i)].name,
                model.graph[petgraph::graph::NodeIndex::new(j)].name
            );
        }
    }
    for (e, pts) in model.graph.edge_indices().zip(&lay.bonds) {
        let (a, b) = model.graph.edge_endpoints(e).unwrap();
        for w in pts.windows(2) {
            for (k, r) in rects.iter().enumerate() {
                if k == a.index() || k == b.index() {
                    continue;
                }
                assert!(
                    !crosses(w[0], w[1], *r),
                    "bond {} crosses `{}`",
                    model.bond_name(e),
                    model.graph[petgraph::graph::NodeIndex::new(k)].name
                );
            }
        }
    }
}

#[test]
fn back_support_layout_is_readable() {
    let m = back_support();
    let lay = layout(&m);
    check_geometry(&m, &lay);
    // Everything inside the canvas.
    for p in &lay.nodes {
        assert!(p.x - p.w / 2.0 >= 0.0 && p.x + p.w / 2.0 <= lay.width);
        assert!(p.y - p.h / 2.0 >= 0.0 && p.y + p.h / 2.0 <= lay.height);
    }
}

#[test]
fn assorted_layout_is_readable() {
    let m = assorted();
    let lay = layout(&m);
    check_geometry(&m, &lay);
    let (c, _) = crate::causality::analyse(&m);
    let s = super::svg(&m, Some(&c));
    // Field ports are numbered at the field's ends.
    assert!(s.contains(">1</text>") && s.contains(">2</text>"));
}

#[test]
fn svg_marks_derivative_storage_and_strokes() {
    let m = back_support();
    let (c, _) = crate::causality::analyse(&m);
    let s = super::svg(&m, Some(&c));
    assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
    // Two storage elements in derivative causality, drawn with the derivative colour.
    assert_eq!(
        s.matches(r##"stroke="#c62828" stroke-width="1.5"/>"##)
            .count(),
        2 + 1
    );
    // One stroke per bond (width 2), plus the legend's.
    assert_eq!(
        s.matches(r#"stroke-width="2"/>"#).count(),
        m.graph.edge_count() + 1
    );
    assert!(s.contains(">I:J_m<") && s.contains(">C:1/k_g<") && s.contains(">TF:r_g<"));
    assert!(s.contains(">rotor<") && s.contains(">Sf:omega_h<"));
    let d = super::dot(&m, Some(&c));
    assert_eq!(d.matches(" -> ").count(), m.graph.edge_count());
    assert!(d.contains("tee"));
}

#[test]
fn loop_members_are_highlighted() {
    // Se -> 1 -> R1; 1 -> 0 -> R2, R3: one algebraic loop through all but the source.
    let mut b = Builder::new("divider");
    let se = b.node(K::Se, "u");
    let s1 = b.node(K::One, "series");
    let r1 = b.node(K::R, "R1");
    let p = b.node(K::Zero, "mid");
    let r2 = b.node(K::R, "R2");
    let r3 = b.node(K::R, "R3");
    b.chain(&[se, s1, r1]);
    b.chain(&[s1, p, r2]);
    b.bond(p, r3);
    let m = b.finish().0;
    let (c, _) = crate::causality::analyse(&m);
    let s = super::svg(&m, Some(&c));
    let loop_nodes = c.loops[0]
        .iter()
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    // Each loop member's box has the loop colour, plus the legend's swatch.
    assert_eq!(
        s.matches(r##"fill="#f1e8fa" stroke="#6a3d9a""##).count(),
        loop_nodes + 1
    );
    check_geometry(&m, &layout(&m));
}

#[test]
fn dot_strokes_follow_the_causality() {
    // Se -> 1 -> I, C: the source sets the effort (stroke at the junction's end, the head); the junction sets the
    // inertia's effort (stroke at the inertia, the head); the compliance sets its own (stroke at the junction, the
    // tail).
    let mut b = Builder::new("osc");
    let se = b.node(K::Se, "push");
    let j = b.node(K::One, "v");
    let i = b.node(K::I, "mass");
    let c = b.node(K::C, "spring");
    b.chain(&[se, j, i]);
    b.bond(j, c);
    let m = b.finish().0;
    let (ca, d) = crate::causality::analyse(&m);
    assert!(d.is_empty());
    let dot = super::dot(&m, Some(&ca));
    assert!(dot.contains("n0 -> n1 [arrowhead=teelvee];"), "{dot}");
    assert!(dot.contains("n1 -> n2 [arrowhead=teelvee];"), "{dot}");
    assert!(
        dot.contains("n1 -> n3 [arrowhead=lvee, dir=both, arrowtail=tee];"),
        "{dot}"
    );
    assert!(dot.contains(r#"n0 [label="Se:1\npush""#), "{dot}");
    // Without a causality there are no strokes.
    let plain = super::dot(&m, None);
    assert!(!plain.contains("tee"));
}
