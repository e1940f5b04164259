//! Layout and rendering checks: geometry (no overlapping boxes, bonds not crossing other elements) and content.

use super::layout::{Layout, layout};
use crate::causality::test_model::Builder;
use crate::ir::Model;
use crate::syntax::ast::ElementKind as K;

/// The back-support exoskeleton of Fig. 6 (Shojaei Barjuei et al., Designs 2020), built by hand.
pub fn back_support() -> Model {
    let mut b = Builder::new("back_support");
    let tau = b.node(K::Se, "tau_m");
    let jm = b.node(K::One, "j_m");
    let rotor = b.node(K::I, "J_m");
    let gin = b.node(K::I, "J_g");
    let bf = b.node(K::R, "b_f");
    let gear = b.node(K::TF, "r_g");
    let jg = b.node(K::One, "j_g");
    let bg = b.node(K::R, "b_g");
    let z1 = b.node(K::Zero, "z_g");
    let rel1 = b.node(K::One, "j_kg");
    let kg = b.node(K::C, "k_g");
    let dg = b.node(K::R, "d_g");
    let js = b.node(K::One, "j_sint");
    let sint = b.node(K::I, "J_sint");
    let z2 = b.node(K::Zero, "z_s");
    let rel2 = b.node(K::One, "j_ks");
    let ks = b.node(K::C, "k_s");
    let ds = b.node(K::R, "d_s");
    let je = b.node(K::One, "j_sext");
    let sext = b.node(K::I, "J_sext");
    let z3 = b.node(K::Zero, "z_h");
    let rel3 = b.node(K::One, "j_keh");
    let keh = b.node(K::C, "k_eh");
    let deh = b.node(K::R, "d_eh");
    let jh = b.node(K::One, "j_h");
    let trunk = b.node(K::I, "J_h");
    let bh = b.node(K::R, "b_h");
    let sf = b.node(K::Sf, "omega_h");
    b.chain(&[tau, jm, rotor]);
    b.bond(jm, gin);
    b.bond(jm, bf);
    b.chain(&[jm, gear, jg, bg]);
    b.chain(&[jg, z1, rel1, kg]);
    b.bond(rel1, dg);
    b.chain(&[z1, js, sint]);
    b.chain(&[js, z2, rel2, ks]);
    b.bond(rel2, ds);
    b.chain(&[z2, je, sext]);
    b.chain(&[je, z3, rel3, keh]);
    b.bond(rel3, deh);
    b.chain(&[z3, jh, trunk]);
    b.bond(jh, bh);
    b.bond(sf, jh);
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
    assert!(s.contains(">I:J_m<") || s.contains(">I:1<"));
    let d = super::dot(&m, Some(&c));
    assert_eq!(d.matches(" -> ").count(), m.graph.edge_count());
    assert!(d.contains("tee"));
}
