//! The assignment itself, on hand-built graphs whose causality is derived by hand in each test's comment.

use super::test_model::Builder;
use super::*;
use crate::ir::{Expr, Law, PortVar, Relation};
use crate::syntax::ast::ElementKind as K;

/// The storage causality of the element called `name` (first port).
fn form(model: &Model, c: &Causality, name: &str) -> StorageForm {
    let n = model.node_by_name(name).map(|n| n.index());
    c.storage
        .iter()
        .find(|s| Some(s.node.index()) == n)
        .map(|s| s.causality)
        .unwrap_or_else(|| panic!("no storage named {name}"))
}

/// The name of the node that sets the effort on the bond between `a` and `b`.
fn setter(model: &Model, c: &Causality, a: &str, b: &str) -> String {
    let e = model
        .graph
        .edge_indices()
        .find(|&e| {
            let (x, y) = model.graph.edge_endpoints(e).unwrap();
            model.graph[x].name == a && model.graph[y].name == b
        })
        .unwrap_or_else(|| panic!("no bond {a} -> {b}"));
    let n = c.effort_setter(model, e).unwrap();
    model.graph[n].name.clone()
}

fn codes(d: &[Diagnostic]) -> Vec<&'static str> {
    d.iter().map(|d| d.code.0).collect()
}

#[test]
fn oscillator_is_causally_complete() {
    // Se -> 1 -> I, C, R. Se sets the effort into the 1-junction; I (integral) takes its effort from the
    // junction, which is then the junction's one effort-setting bond; C (integral) and R set their efforts.
    let (m, ca, d) = Builder::from_spec(
        "oscillator",
        "Se push, 1 v, I mass, C spring, R damper",
        "push v mass; v spring; v damper",
    )
    .analyse();
    assert!(d.is_empty(), "{d:?}");
    assert!(ca.consistent);
    assert_eq!(setter(&m, &ca, "push", "v"), "push");
    assert_eq!(setter(&m, &ca, "v", "mass"), "v");
    assert_eq!(setter(&m, &ca, "v", "spring"), "spring");
    assert_eq!(setter(&m, &ca, "v", "damper"), "damper");
    assert_eq!(form(&m, &ca, "mass"), StorageForm::Integral);
    assert_eq!(form(&m, &ca, "spring"), StorageForm::Integral);
    assert_eq!(ca.independent_states(), 2);
    assert!(ca.loops.is_empty() && ca.arbitrary.is_empty());
}

#[test]
fn two_inertias_on_one_junction() {
    // The first inertia takes integral causality and so sets the junction's flow; the second gets it imposed.
    let (m, ca, d) =
        Builder::from_spec("two", "Se tau, 1 j, I J_m, I J_g", "tau j J_m; j J_g").analyse();
    assert_eq!(form(&m, &ca, "J_m"), StorageForm::Integral);
    assert_eq!(form(&m, &ca, "J_g"), StorageForm::Derivative);
    assert_eq!(codes(&d), ["BG0510"]);
    assert!(ca.consistent);
    assert_eq!(ca.independent_states(), 1);
}

#[test]
fn gyrator_inverts_causality() {
    // DC motor: Se -> 1e {L, R} -> GY -> 1m {J, b}. L integral makes 1e set L's effort, so the GY bond is
    // effort-in to 1e from the GY; a gyrator that sets one effort sets both, so 1m receives its effort from
    // the GY and J can be integral. Two states.
    let (m, ca, d) = Builder::from_spec(
        "motor",
        "Se v, 1 je, I L, R Ra, GY kt, 1 jm, I J, R b",
        "v je L; je Ra; je kt jm J; jm b",
    )
    .analyse();
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(setter(&m, &ca, "je", "kt"), "kt");
    assert_eq!(setter(&m, &ca, "kt", "jm"), "kt");
    assert_eq!(ca.independent_states(), 2);
}

#[test]
fn transformer_passes_effort_through() {
    // Se -> 1a -> TF -> 1b -> I: the source brings 1a's effort in, so 1a's one effort-setting bond is the TF
    // bond; the TF then sets the effort on its output bond (effort in, effort out) and the inertia on 1b can be
    // integral.
    let (m, ca, d) = Builder::from_spec(
        "tf",
        "Se tau, 1 ja, TF gear, 1 jb, I load",
        "tau ja gear jb load",
    )
    .analyse();
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(setter(&m, &ca, "ja", "gear"), "ja");
    assert_eq!(setter(&m, &ca, "gear", "jb"), "gear");
    assert_eq!(form(&m, &ca, "load"), StorageForm::Integral);
}

#[test]
fn modulated_elements_propagate_like_plain_ones() {
    // The same graph with MSe and MTF gives the same causality.
    let (m, ca, d) = Builder::from_spec(
        "mtf",
        "MSe tau, 1 ja, I ia, MTF lever, 1 jb, I ib",
        "tau ja ia; ja lever jb ib",
    )
    .analyse();
    // ia integral sets ja's flow, the MTF passes it to jb, so ib is in derivative causality.
    assert_eq!(form(&m, &ca, "ia"), StorageForm::Integral);
    assert_eq!(form(&m, &ca, "ib"), StorageForm::Derivative);
    assert_eq!(codes(&d), ["BG0510"]);
}

#[test]
fn parallel_resistors_on_an_effort_source_are_forced() {
    // Se -> 0 -> R1, R2: the 0-junction passes the source's effort to both resistors: conductance, no choice.
    let (m, ca, d) =
        Builder::from_spec("parallel", "Se u, 0 n, R R1, R R2", "u n R1; n R2").analyse();
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(setter(&m, &ca, "n", "R1"), "n");
    assert_eq!(setter(&m, &ca, "n", "R2"), "n");
}

#[test]
fn nonlinear_resistor_law_preference() {
    // 0 -> R1 {f = g(e)}, R2: nothing but R1's law decides; conductance for R1 makes R2 take the resistance.
    let mut b = Builder::new("laws");
    let j = b.node(K::Zero, "n");
    let r1 = b.r_law("R1", PortVar::Flow);
    let r2 = b.node(K::R, "R2");
    b.bond(j, r1);
    b.bond(j, r2);
    let (m, ca, d) = b.analyse();
    assert_eq!(setter(&m, &ca, "n", "R1"), "n");
    assert_eq!(setter(&m, &ca, "n", "R2"), "R2");
    assert!(ca.arbitrary.is_empty());
    assert!(ca.inverted_laws.is_empty());
    // The two resistors in parallel with nothing else form an algebraic loop.
    assert_eq!(codes(&d), ["BG0520"]);

    // A flow source in series imposes the flow: the law `f = g(e)` must be inverted.
    let mut b = Builder::new("inverted");
    let sf = b.node(K::Sf, "i");
    let j = b.node(K::One, "s");
    let r = b.r_law("diode", PortVar::Flow);
    b.chain(&[sf, j, r]);
    let (m, ca, d) = b.analyse();
    assert_eq!(setter(&m, &ca, "s", "diode"), "diode");
    assert_eq!(
        ca.inverted_laws,
        vec![(m.node_by_name("diode").unwrap(), 0)]
    );
    assert_eq!(codes(&d), ["BG0531"]);
}

#[test]
fn fields_take_causality_per_port() {
    // An I-field with M(q) on two 1-junctions, each driven by an effort source: integral on both ports.
    let mut b = Builder::new("leg");
    let [s1, s2, j1, j2] = b.nodes("Se tau1, Se tau2, 1 hip, 1 knee");
    let mass = Relation::MassMatrix {
        n: 2,
        entries: vec![Expr::Const(1.0); 4],
    };
    let leg = b.add(K::IF, "leg", mass, 2);
    b.chain(&[s1, j1]);
    b.chain(&[s2, j2]);
    b.bond_full(j1, None, leg, Some(0), None);
    b.bond_full(j2, None, leg, Some(1), None);
    // An R-field on both joints with laws in resistance form.
    let laws = (0..2)
        .map(|port| Law {
            lhs: PortVar::Effort,
            port,
            rhs: Expr::Const(1.0),
        })
        .collect();
    let rf = b.add(K::RF, "bearing", Relation::Laws(laws), 2);
    b.bond_full(j1, None, rf, Some(0), None);
    b.bond_full(j2, None, rf, Some(1), None);
    let (m, ca, d) = b.analyse();
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(ca.storage.len(), 2);
    assert!(
        ca.storage
            .iter()
            .all(|s| s.causality == StorageForm::Integral && s.kind == StorageKind::I)
    );
    assert_eq!(
        ca.storage.iter().map(|s| s.port).collect::<Vec<_>>(),
        [0, 1]
    );
    assert_eq!(setter(&m, &ca, "hip", "bearing"), "bearing");
    assert_eq!(setter(&m, &ca, "knee", "bearing"), "bearing");
}

#[test]
fn every_bond_gets_a_causality_on_a_long_chain() {
    // Se -> 1 -> {I, R} -> 0 -> C -> 1 -> ... : every stage alternates a 1-junction with an inertia and a
    // 0-junction with a compliance; all storage is integral. Built with 20 000 bonds to exercise the worklist.
    let mut b = Builder::new("chain");
    let mut prev = b.node(K::Se, "src");
    let stages = 4000;
    for k in 0..stages {
        let one = b.node(K::One, &format!("v{k}"));
        let i = b.node(K::I, &format!("m{k}"));
        let r = b.node(K::R, &format!("d{k}"));
        let zero = b.node(K::Zero, &format!("f{k}"));
        let c = b.node(K::C, &format!("k{k}"));
        b.chain(&[prev, one, i]);
        b.bond(one, r);
        b.chain(&[one, zero, c]);
        prev = zero;
    }
    let (m, _) = b.finish();
    assert_eq!(m.graph.edge_count(), 5 * stages);
    let (ca, d) = analyse(&m);
    assert!(d.is_empty(), "{:?}", d.first());
    assert_eq!(ca.effort_set_by.len(), 5 * stages);
    assert_eq!(ca.independent_states(), 2 * stages);
}
