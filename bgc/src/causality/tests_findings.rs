//! Findings: each one's code, message, and places (primary span at the offending element, secondary labels along
//! the causal path).

use super::test_model::Builder;
use super::*;
use crate::diagnostic::Severity;
use crate::span::Span;
use crate::syntax::ast::ElementKind as K;

/// The nodes of the resistor divider `Se -> 1 -> R1; 1 -> 0 -> R2, R3`.
const DIVIDER: &str = "Se u, 1 series, R R1, 0 mid, R R2, R R3";

fn span_of(m: &Model, name: &str) -> Span {
    let n = m
        .node_by_name(name)
        .unwrap_or_else(|| panic!("no node {name}"));
    m.spans.nodes[n.index()]
}

fn secondary_spans(d: &Diagnostic) -> Vec<Span> {
    d.labels
        .iter()
        .filter(|l| !l.primary)
        .map(|l| l.span)
        .collect()
}

/// Asserts that `text` contains every one of `parts`, and shows `text` when it does not.
#[track_caller]
fn assert_mentions(text: &str, parts: &[&str]) {
    for part in parts {
        assert!(text.contains(part), "{part:?} is not in {text:?}");
    }
}

/// The help of a finding that must have one.
#[track_caller]
fn help(d: &Diagnostic) -> &str {
    d.help
        .as_deref()
        .unwrap_or_else(|| panic!("no help in {d:#?}"))
}

fn only(d: &[Diagnostic], code: &str) -> Diagnostic {
    let found: Vec<&Diagnostic> = d.iter().filter(|x| x.code.0 == code).collect();
    assert_eq!(found.len(), 1, "one {code} expected in {d:#?}");
    found[0].clone()
}

#[test]
fn two_effort_sources_on_a_zero_junction() {
    let (m, ca, d) = Builder::from_spec(
        "conflict",
        "Se battery, Se supply, 0 node, R load",
        "battery node; supply node; node load",
    )
    .analyse();
    assert!(!ca.consistent);
    let e = only(&d, "BG0501");
    assert_eq!(e.severity, Severity::Error);
    assert_eq!(e.primary_span(), Some(span_of(&m, "node")));
    assert_mentions(
        &e.message,
        &["`battery`", "`supply`", "effort of 0-junction `node`"],
    );
    // The path: battery sets the effort, the junction passes it on to the supply's bond.
    let sec = secondary_spans(&e);
    assert!(sec.contains(&span_of(&m, "battery")) && sec.contains(&span_of(&m, "supply")));
    assert!(e.help.is_some());
    // The resistor still gets a causality (the result is complete).
    assert_eq!(ca.effort_set_by.len(), 3);
}

#[test]
fn two_flow_sources_on_a_one_junction() {
    let (m, _, d) = Builder::from_spec(
        "conflict",
        "Sf pump1, Sf pump2, 1 pipe, R valve",
        "pump1 pipe; pump2 pipe; pipe valve",
    )
    .analyse();
    let e = only(&d, "BG0501");
    assert_eq!(e.primary_span(), Some(span_of(&m, "pipe")));
    assert_mentions(&e.message, &["flow of 1-junction `pipe`"]);
}

#[test]
fn flow_source_forced_through_a_transformer() {
    // Sf1 sets the TF's input flow, so the TF sets the output flow: Sf2 cannot set its own.
    let (m, ca, d) = Builder::from_spec(
        "forced",
        "Sf driver, TF gear, Sf brake",
        "driver gear brake",
    )
    .analyse();
    assert!(!ca.consistent);
    let e = only(&d, "BG0503");
    assert_eq!(e.primary_span(), Some(span_of(&m, "brake")));
    assert_mentions(&e.message, &["flow source `brake`", "flow source `driver`"]);
    // Element by element: (1) driver, (2) gear.
    let labels: Vec<&str> = e
        .labels
        .iter()
        .filter(|l| !l.primary)
        .map(|l| l.message.as_str())
        .collect();
    assert_eq!(labels.len(), 2, "{labels:?}");
    assert!(
        labels[0].starts_with("(1) `driver` sets the flow"),
        "{labels:?}"
    );
    assert!(
        labels[1].starts_with("(2) `gear` sets the flow"),
        "{labels:?}"
    );
}

#[test]
fn transformer_closing_a_loop_on_one_junction_is_over_determined() {
    // Se -> 0 and both ports of a TF on the same 0-junction: the junction sets both of the TF's efforts.
    let (m, _, d) = Builder::from_spec("overdetermined", "Se u, 0 n, TF t", "u n t n").analyse();
    let e = only(&d, "BG0502");
    assert_eq!(e.primary_span(), Some(span_of(&m, "t")));
    assert_mentions(&e.message, &["transformer `t` is over-determined"]);
}

#[test]
fn derivative_inertia_across_a_junction() {
    let (m, ca, d) = Builder::from_spec(
        "rigid",
        "Se tau, 1 j_m, I J_m, I J_g",
        "tau j_m J_m; j_m J_g",
    )
    .analyse();
    let w = only(&d, "BG0510");
    assert_eq!(w.severity, Severity::Warning);
    assert_eq!(w.primary_span(), Some(span_of(&m, "J_g")));
    assert_eq!(
        w.message,
        "inertia `J_g` is in derivative causality: its flow is imposed by inertia `J_m` across 1-junction `j_m`"
    );
    assert_mentions(help(&w), &["merge", "compliance"]);
    assert_eq!(
        secondary_spans(&w),
        [span_of(&m, "J_m"), span_of(&m, "j_m")]
    );
    assert!(ca.consistent);
}

#[test]
fn derivative_inertia_through_a_transformer() {
    let (m, _, d) = Builder::from_spec(
        "rigid_tf",
        "Se tau, 1 ja, I rotor, TF gear, 1 jb, I load",
        "tau ja rotor; ja gear jb load",
    )
    .analyse();
    let w = only(&d, "BG0510");
    assert_eq!(w.primary_span(), Some(span_of(&m, "load")));
    assert!(
        w.message.ends_with(
            "imposed by inertia `rotor` across 1-junction `ja`, transformer `gear`, 1-junction `jb`"
        ),
        "{}",
        w.message
    );
}

#[test]
fn derivative_inertia_driven_by_a_flow_source() {
    let (m, ca, d) = Builder::from_spec(
        "driven",
        "Sf trunk, 1 j_h, I J_h, R b_h",
        "trunk j_h J_h; j_h b_h",
    )
    .analyse();
    assert_eq!(d.len(), 1, "{d:#?}");
    let w = only(&d, "BG0510");
    assert_eq!(w.primary_span(), Some(span_of(&m, "J_h")));
    assert_mentions(
        &w.message,
        &["imposed by flow source `trunk` across 1-junction `j_h`"],
    );
    assert_mentions(help(&w), &["add a compliance between `trunk` and `J_h`"]);
    assert_eq!(ca.independent_states(), 0);
}

#[test]
fn resistor_divider_has_an_algebraic_loop() {
    // Se -> 1 -> R1; 1 -> 0 -> R2, R3. No storage: R1 is chosen arbitrarily (resistance), which makes the
    // 1-junction set the effort towards the 0-junction, and R2, R3 take conductance. Then R1's effort depends on
    // the series flow, which is the sum of R2's and R3's flows, which depend on the 0-junction's effort, which is
    // the source's minus R1's: a loop R1 -> 1 -> 0 -> R2 -> 0 -> 1 -> R1.
    let b = Builder::from_spec("divider", DIVIDER, "u series R1; series mid R2; mid R3");
    let r1 = b.id("R1");
    let (m, ca, d) = b.analyse();
    assert_eq!(ca.arbitrary.len(), 1);
    assert_eq!(ca.arbitrary[0].node, r1);
    let note = only(&d, "BG0530");
    assert_eq!(note.severity, Severity::Note);
    assert_eq!(note.primary_span(), Some(span_of(&m, "R1")));
    assert_eq!(ca.loops.len(), 1);
    let names: Vec<&str> = ca.loops[0]
        .iter()
        .map(|&n| m.graph[n].name.as_str())
        .collect();
    assert_eq!(names[0], "R1");
    assert!(
        names.contains(&"series") && names.contains(&"mid"),
        "{names:?}"
    );
    assert!(names.contains(&"R2") || names.contains(&"R3"), "{names:?}");
    let w = only(&d, "BG0520");
    assert_eq!(w.primary_span(), Some(span_of(&m, "R1")));
    assert_eq!(w.labels.len(), names.len());
}

#[test]
fn resistor_network_without_loop_is_silent() {
    // Se -> 1 -> R1; 1 -> 0 -> R2, C: the compliance fixes the 0-junction's effort, which decides both resistors.
    let (_, ca, d) = Builder::from_spec(
        "rc",
        "Se u, 1 series, R R1, 0 mid, R R2, C cap",
        "u series R1; series mid R2; mid cap",
    )
    .analyse();
    assert!(d.is_empty(), "{d:#?}");
    assert!(ca.loops.is_empty());
    assert_eq!(ca.independent_states(), 1);
}

#[test]
fn only_arbitrary_choices_between_junctions() {
    // Se -> 1 and two bonds from the 1-junction to a 0-junction: after the source nothing decides which of the
    // two bonds carries the 1-junction's effort.
    let mut b = Builder::from_spec("arbitrary", "Se u, 1 a, 0 b", "u a");
    let first = b.bond(b.id("a"), b.id("b"));
    b.chains("a b");
    let (m, ca, d) = b.analyse();
    assert_eq!(ca.arbitrary.len(), 1);
    assert_eq!(ca.arbitrary[0].bond, first);
    let note = only(&d, "BG0530");
    assert_eq!(note.primary_span(), Some(m.spans.bonds[first.index()]));
    assert_mentions(&note.message, &["bond `a->b`"]);
    assert!(ca.consistent);
}

#[test]
fn preferred_hint_honoured() {
    // Two inertias on one junction, the hint asks for the stroke at the junction's end of J_m's bond: J_m sets
    // the effort (derivative) and J_g becomes the state.
    let mut b = Builder::from_spec("hinted", "Se tau, 1 j, I J_m, I J_g", "tau j");
    let hinted = b.bond_hint(b.id("j"), b.id("J_m"), false, false);
    b.chains("j J_g");
    let (m, ca, d) = b.analyse();
    let note = only(&d, "BG0540");
    assert_mentions(&note.message, &["is honoured"]);
    assert_eq!(note.primary_span(), Some(m.spans.bonds[hinted.index()]));
    let w = only(&d, "BG0510");
    assert_eq!(w.primary_span(), Some(span_of(&m, "J_m")));
    assert_eq!(
        ca.hints,
        [HintOutcome {
            bond: hinted,
            fixed: false,
            honoured: true
        }]
    );
}

#[test]
fn preferred_hint_overruled_and_fixed_hint_violated() {
    // A flow source imposes the junction's flow: the inertia cannot be integral whatever the hint says.
    for fixed in [false, true] {
        let mut b = Builder::from_spec("overruled", "Sf trunk, 1 j, I J_h", "trunk j");
        let hinted = b.bond_hint(b.id("j"), b.id("J_h"), true, fixed);
        let (m, ca, d) = b.analyse();
        assert_eq!(ca.hints.len(), 1);
        assert!(!ca.hints[0].honoured);
        let code = if fixed { "BG0541" } else { "BG0540" };
        let h = only(&d, code);
        assert_eq!(h.primary_span(), Some(m.spans.bonds[hinted.index()]));
        assert_eq!(
            h.severity,
            if fixed {
                Severity::Error
            } else {
                Severity::Note
            }
        );
        assert_eq!(ca.consistent, !fixed);
        // The path from the source is shown.
        assert!(
            secondary_spans(&h).contains(&span_of(&m, "trunk")),
            "{h:#?}"
        );
    }
}

#[test]
fn fixed_hint_honoured_is_a_note() {
    let mut b = Builder::from_spec("fixed", "Se tau, 1 j, I J", "tau j");
    b.bond_hint(b.id("j"), b.id("J"), true, true);
    let (_, ca, d) = b.analyse();
    assert_eq!(d.len(), 1);
    assert_eq!(d[0].code.0, "BG0540");
    assert_mentions(&d[0].message, &["fixed causality hint"]);
    assert!(ca.consistent);
}

#[test]
fn fixed_hint_against_a_source_over_determines_a_junction() {
    // Se -> 0 -> C with a fixed stroke asking the C to set the effort: the source already does.
    let mut b = Builder::from_spec("fixed_conflict", "Se u, 0 n, C cap, R leak", "u n");
    let hinted = b.bond_hint(b.id("n"), b.id("cap"), false, true);
    b.chains("n leak");
    let (m, _, d) = b.analyse();
    let e = only(&d, "BG0541");
    assert_eq!(e.primary_span(), Some(m.spans.bonds[hinted.index()]));
    assert!(d.iter().all(|x| x.code.0 != "BG0540"));
}

#[test]
fn preferred_hint_on_a_resistor_takes_the_place_of_an_arbitrary_choice() {
    // The divider of `resistor_divider_has_an_algebraic_loop` with a hint putting r1 in conductance: r1 is no
    // longer an arbitrary choice, but the 0-junction still needs one of R2, R3 to set its effort.
    let mut b = Builder::from_spec("divider_hint", DIVIDER, "u series");
    b.bond_hint(b.id("series"), b.id("R1"), true, false);
    b.chains("series mid R2; mid R3");
    let r2 = b.id("R2");
    let (m, ca, d) = b.analyse();
    assert!(ca.hints[0].honoured);
    assert_eq!(ca.arbitrary.len(), 1);
    assert_eq!(ca.arbitrary[0].node, r2);
    assert_eq!(only(&d, "BG0530").primary_span(), Some(span_of(&m, "R2")));
    assert_eq!(ca.loops.len(), 1);
}

#[test]
fn preferred_hint_does_not_push_storage_into_derivative_causality() {
    // Series Se-R-C: a hint asking the resistor to set the effort would leave the capacitor's effort to the
    // junction (derivative). Storage is decided before hints on other bonds, so the hint is overruled instead.
    let mut b = Builder::from_spec("rc_hint", "Se u, 1 loop, R R, C C", "u loop");
    b.bond_hint(b.id("loop"), b.id("R"), false, false);
    b.chains("loop C");
    let (_, ca, d) = b.analyse();
    assert_eq!(ca.independent_states(), 1);
    assert!(!ca.hints[0].honoured);
    let note = only(&d, "BG0540");
    assert_mentions(&note.message, &["overruled"]);
    assert!(
        note.notes
            .iter()
            .any(|n| n.contains("compliance `C` decides the other way")),
        "{note:#?}"
    );
}

#[test]
fn long_causal_paths_are_shortened() {
    // A rigid chain Se -> 1 -> I -> TF -> 1 -> I -> TF ...: the first inertia is integral, every later one is
    // imposed through all the transformers before it. Each warning shows the origin and the last steps only, so the
    // findings stay linear in size.
    let stages = 300;
    let mut b = Builder::new("rigid_chain");
    let se = b.node(K::Se, "tau");
    let mut prev = se;
    for k in 0..stages {
        let j = b.node(K::One, &format!("j{k}"));
        let i = b.node(K::I, &format!("J{k}"));
        b.chain(&[prev, j, i]);
        let tf = b.node(K::TF, &format!("g{k}"));
        b.bond(j, tf);
        prev = tf;
    }
    let end = b.node(K::One, "end");
    let r = b.node(K::R, "load");
    b.chain(&[prev, end, r]);
    let (m, c, d) = b.analyse();
    assert_eq!(c.independent_states(), 1);
    assert_eq!(d.len(), stages - 1);
    let last = d.last().unwrap();
    assert_mentions(&last.message, &["`J299`", "inertia `J0`"]);
    assert!(last.labels.len() <= 14, "{}", last.labels.len());
    assert!(
        last.notes
            .iter()
            .any(|n| n.contains("in its middle are not shown"))
    );
    // The origin is still the first secondary label.
    assert_eq!(last.labels[1].span, span_of(&m, "J0"));
}
