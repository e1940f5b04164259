//! Storages in derivative causality and algebraic loops: state counts and equations against hand derivations.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{StateSelection, derive, numeric_state_space, solve_all, to_text};
use bgc::ir::Relation;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

#[test]
fn two_inertias_on_one_junction_merge() {
    // Se tau -> 1 -> I J1, I J2, R b: one state; (J1 + J2) ω̇ = tau - b ω, with ω = p/J1:
    // ṗ = J1/(J1 + J2) tau - b/(J1 + J2) p.
    let mut b = Builder::new("two_inertias");
    let (j1, j2, damping) = (b.param("J1", 2.0), b.param("J2", 3.0), b.param("b", 0.5));
    let tau = b.input("tau");
    let src = b.node(K::Se, "drive", source(tau));
    let w = b.junction(K::One, "w");
    let i1 = b.node(K::I, "i1", linear(j1));
    let i2 = b.node(K::I, "i2", linear(j2));
    let r = b.node(K::R, "friction", linear(damping));
    b.chain(&[src, w, i1]);
    b.bond(w, i2);
    b.bond(w, r);
    b.output("omega", f(w));
    let model = b.finish();
    let (causality, _) = analyse(&model);
    assert_eq!(causality.derivative().count(), 1);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(eqs.energy_states, 1);
    let mut rng = Rng(5);
    for _ in 0..4 {
        let (j1, j2, d) = (
            rng.log_uniform(0.1, 10.0),
            rng.log_uniform(0.1, 10.0),
            rng.log_uniform(0.01, 1.0),
        );
        let ss = numeric_state_space(&eqs, StateSelection::Energy, &[j1, j2, d]).expect("linear");
        // Whichever inertia keeps the state, ω̇ = (tau - b ω)/(J1 + J2); check through the output ω = C x.
        let (a, bb, c) = (ss.a[0][0], ss.b[0][0], ss.c[0][0]);
        assert!((a - (-d / (j1 + j2))).abs() < 1e-12 * a.abs(), "A = {a}");
        assert!(
            (c * bb - 1.0 / (j1 + j2)).abs() < 1e-12 / (j1 + j2),
            "C B = {}",
            c * bb
        );
    }
    let text = to_text(&eqs);
    assert!(text.contains("(J1 + J2)"), "{text}");
}

#[test]
fn inertia_behind_a_transformer_is_reflected_with_the_square_of_the_ratio() {
    // Se tau -> 1a -> I J1; 1a -> TF n -> 1b -> I J2, R b2. f2 = f1/n, so
    // ṗ1 = (tau - b2 p1/(J1 n²)) J1 n²/(J1 n² + J2).
    let mut b = Builder::new("reflected");
    let (j1, j2, n, b2) = (
        b.param("J1", 1e-4),
        b.param("J2", 0.5),
        b.param("n", 100.0),
        b.param("b2", 2.0),
    );
    let tau = b.input("tau");
    let src = b.node(K::Se, "drive", source(tau));
    let w1 = b.junction(K::One, "w1");
    let i1 = b.node(K::I, "rotor", linear(j1));
    let tf = b.node(K::TF, "gear", Relation::Modulus(n));
    let w2 = b.junction(K::One, "w2");
    let i2 = b.node(K::I, "load", linear(j2));
    let r = b.node(K::R, "load_friction", linear(b2));
    b.chain(&[src, w1, i1]);
    b.chain(&[w1, tf, w2, i2]);
    b.bond(w2, r);
    let model = b.finish();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(
        eqs.states
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>(),
        ["p_rotor"]
    );
    let mut rng = Rng(9);
    for _ in 0..4 {
        let (j1, j2, n, b2) = (
            rng.log_uniform(1e-5, 1e-3),
            rng.log_uniform(0.01, 1.0),
            rng.log_uniform(10.0, 200.0),
            rng.log_uniform(0.1, 5.0),
        );
        let ss =
            numeric_state_space(&eqs, StateSelection::Energy, &[j1, j2, n, b2]).expect("linear");
        let j = j1 * n * n + j2;
        assert_close("A", &ss.a, &[vec![-b2 / j]], 1e-12);
        assert_close("B", &ss.b, &[vec![j1 * n * n / j]], 1e-12);
    }
}

#[test]
fn an_inertia_behind_a_flow_source_adds_no_state() {
    // Sf omega -> 1 -> I J (derivative causality), C 1/k, R b: the only state is the spring's.
    let mut b = Builder::new("driven");
    let (j, k, d) = (b.param("J", 0.05), b.param("k", 1000.0), b.param("b", 0.7));
    let omega = b.input("omega");
    let src = b.node(K::Sf, "motion", source(omega));
    let w = b.junction(K::One, "w");
    let inertia = b.node(K::I, "trunk", linear(j));
    let spring = b.node(K::C, "spring", linear(div(c(1.0), k)));
    let r = b.node(K::R, "hip", linear(d));
    b.chain(&[src, w, inertia]);
    b.bond(w, spring);
    b.bond(w, r);
    b.output("spring_torque", e(spring));
    b.output("source_torque", e(src));
    let model = b.finish();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert_eq!(eqs.energy_states, 1);
    assert_eq!(eqs.states[0].name, "q_spring");
    // The spring output is fine; the source's torque needs J ω̇: an error located at that output.
    assert!(eqs.outputs[0].explicit.is_some());
    assert!(eqs.outputs[1].explicit.is_none());
    let errors: Vec<_> = diags.iter().filter(|d| d.is_error()).collect();
    assert_eq!(errors.len(), 1, "{diags:?}");
    assert_eq!(errors[0].code.0, "BG0602");
    assert!(
        errors[0].message.contains("source_torque") && errors[0].message.contains("omega"),
        "{}",
        errors[0].message
    );
    assert_eq!(
        errors[0].primary_span(),
        model.spans.outputs.get(1).copied()
    );
}

/// A voltage source feeding R1 in series with R2 parallel to the branch R3 + C (bgc/tests/corpus/resistive_network.bg).
fn resistive_network() -> bgc::ir::Model {
    let mut b = Builder::new("resistive_network");
    let (r1, r2, r3, cap) = (
        b.param("R1", 100.0),
        b.param("R2", 220.0),
        b.param("R3", 470.0),
        b.param("C_v", 1e-6),
    );
    let u = b.input("u");
    let src = b.node(K::Se, "source", source(u));
    let series = b.junction(K::One, "series");
    let n1 = b.node(K::R, "r1", linear(r1));
    let middle = b.junction(K::Zero, "middle");
    let n2 = b.node(K::R, "r2", linear(r2));
    let branch = b.junction(K::One, "branch");
    let n3 = b.node(K::R, "r3", linear(r3));
    let capacitor = b.node(K::C, "cap", linear(cap));
    b.chain(&[src, series, n1]);
    b.chain(&[series, middle, n2]);
    b.chain(&[middle, branch, n3]);
    b.bond(branch, capacitor);
    b.output("v_middle", e(middle));
    b.finish()
}

#[test]
fn a_linear_algebraic_loop_is_solved_exactly() {
    let model = resistive_network();
    let (causality, _) = analyse(&model);
    assert!(
        !causality.loops.is_empty(),
        "the network has a zero-order causal path"
    );
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    assert!(!eqs.loops.is_empty());
    assert!(to_text(&eqs).contains("algebraic loop, solved exactly"));
    // Node voltage v: (u - v)/R1 = v/R2 + (v - q/C)/R3, so v = (u/R1 + q/(C R3))/G with G = 1/R1 + 1/R2 + 1/R3;
    // q̇ = (v - q/C)/R3.
    let mut rng = Rng(21);
    for _ in 0..4 {
        let (r1, r2, r3, cap) = (
            rng.log_uniform(10.0, 1e3),
            rng.log_uniform(10.0, 1e3),
            rng.log_uniform(10.0, 1e3),
            rng.log_uniform(1e-7, 1e-5),
        );
        let g = 1.0 / r1 + 1.0 / r2 + 1.0 / r3;
        let ss =
            numeric_state_space(&eqs, StateSelection::Energy, &[r1, r2, r3, cap]).expect("linear");
        let a = (1.0 / (cap * r3 * g) - 1.0 / cap) / r3;
        let bb = 1.0 / (r1 * r3 * g);
        assert_close("A", &ss.a, &[vec![a]], 1e-12);
        assert_close("B", &ss.b, &[vec![bb]], 1e-12);
        assert_close("C", &ss.c, &[vec![1.0 / (cap * r3 * g)]], 1e-12);
        assert_close("D", &ss.d, &[vec![1.0 / (r1 * g)]], 1e-12);
    }
}

#[test]
fn a_nonlinear_algebraic_loop_is_kept_implicit_and_solves_kirchhoffs_law() {
    // As the network above, with R2 a cubic conductance f = e^3/R2: the loop has no closed form. It becomes one
    // tear block, and its numeric solution must satisfy the node equation at v = v_middle:
    //   (u - v)/R1 = v^3/R2 + (v - q/C)/R3,   q̇ = (v - q/C)/R3.
    let mut model = resistive_network();
    let r2 = model.node_by_name("r2").expect("r2");
    let r2_param = bgc::ir::Expr::Param(1);
    model.graph[r2].relation = Relation::Laws(vec![bgc::ir::Law {
        lhs: bgc::ir::PortVar::Flow,
        port: 0,
        rhs: mul(div(c(1.0), r2_param), pow(e(r2), c(3.0))),
    }]);
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    assert_eq!(eqs.tear_blocks.len(), 1);
    assert_eq!(eqs.tear_blocks[0].tears.len(), 1);
    assert!(
        to_text(&eqs).contains("solve for loop_"),
        "{}",
        to_text(&eqs)
    );
    let (r1, r2, r3, cap) = (100.0, 220.0, 470.0, 1e-6);
    let mut rng = Rng(5);
    for _ in 0..6 {
        let (q, u) = (6e-6 * (rng.next() - 0.5), 40.0 * (rng.next() - 0.5));
        let base = |s: Sym| match s {
            Sym::Param(i) => [r1, r2, r3, cap].get(i).copied(),
            Sym::State(0) => Some(q),
            Sym::Input(0) => Some(u),
            Sym::Time => Some(0.0),
            _ => None,
        };
        let tears = solve_all(&eqs, &base).expect("the loop solves");
        let value = |s: Sym| match s {
            Sym::Tear(_) => tears.iter().find(|(t, _)| *t == s).map(|(_, v)| *v),
            other => base(other),
        };
        let explicit = eqs.outputs[0].explicit.as_ref().expect("v_middle");
        let v = sym::eval(explicit, &value).expect("v_middle evaluates");
        let (i1, i2, i3) = ((u - v) / r1, v.powi(3) / r2, (v - q / cap) / r3);
        let scale = i1.abs() + i2.abs() + i3.abs();
        assert!(
            (i1 - i2 - i3).abs() <= 1e-10 * scale,
            "q = {q}, u = {u}: v = {v}, {i1} != {i2} + {i3}"
        );
        let rate = sym::eval(eqs.f[0].as_ref().expect("rate"), &value).expect("rate evaluates");
        assert!((rate - i3).abs() <= 1e-10 * scale, "{rate} vs {i3}");
    }
}
