//! Linear models against hand derivations: the mass-spring-damper and the series RLC circuit.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::{StateSelection, derive, linear_state_space, numeric_state_space, to_text};
use bgc::ir::Model;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

/// `Se F -> 1 -> I m, C 1/k, R d`; outputs the spring deflection and the mass velocity.
fn oscillator() -> Model {
    let mut b = Builder::new("oscillator");
    let m = b.param("m", 2.0);
    let k = b.param("k", 800.0);
    let d = b.param("d", 4.0);
    let force = b.input("F");
    let push = b.node(K::Se, "push", source(force));
    let mass = b.node(K::I, "mass", linear(m));
    let spring = b.node(K::C, "spring", linear(div(c(1.0), k)));
    let damper = b.node(K::R, "damper", linear(d));
    let v = b.junction(K::One, "v");
    b.chain(&[push, v, mass]);
    b.bond(v, spring);
    b.bond(v, damper);
    b.output("x", q(spring));
    b.output("v_mass", f(mass));
    b.finish()
}

#[test]
fn mass_spring_damper_matches_hand_derivation() {
    let model = oscillator();
    let (causality, cdiags) = analyse(&model);
    assert!(cdiags.is_empty(), "{cdiags:?}");
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    assert_eq!(
        eqs.states
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>(),
        ["p_mass", "q_spring"]
    );
    // Hand derivation: ṗ = F - d p/m - k q, q̇ = p/m; x = q, v = p/m.
    let mut rng = Rng(7);
    for _ in 0..5 {
        let (m, k, d) = (
            rng.log_uniform(0.1, 10.0),
            rng.log_uniform(1.0, 1e4),
            rng.log_uniform(0.01, 100.0),
        );
        let ss = numeric_state_space(&eqs, StateSelection::Energy, &[m, k, d]).expect("linear");
        assert_close("A", &ss.a, &[vec![-d / m, -k], vec![1.0 / m, 0.0]], 1e-12);
        assert_close("B", &ss.b, &[vec![1.0], vec![0.0]], 1e-12);
        assert_close("C", &ss.c, &[vec![0.0, 1.0], vec![1.0 / m, 0.0]], 1e-12);
        assert_close("D", &ss.d, &[vec![0.0], vec![0.0]], 1e-12);
    }
    // The symbolic A has the parameters in it.
    let sym = linear_state_space(&eqs, StateSelection::Energy).expect("linear");
    assert_eq!(bgc::equations::expr_text(&eqs, &sym.dfdx[0][0]), "-d/m");
    assert_eq!(bgc::equations::expr_text(&eqs, &sym.dfdx[0][1]), "-k");
    insta::assert_snapshot!("oscillator_text", to_text(&eqs));
}

/// `Se V -> 1 -> R, I L, C`: a series RLC circuit, current as output.
fn series_rlc() -> Model {
    let mut b = Builder::new("series_rlc");
    let r = b.param("R", 10.0);
    let l = b.param("L", 1e-3);
    let cap = b.param("Cap", 1e-6);
    let v = b.input("V");
    let src = b.node(K::Se, "supply", source(v));
    let res = b.node(K::R, "resistor", linear(r));
    let ind = b.node(K::I, "inductor", linear(l));
    let capacitor = b.node(K::C, "capacitor", linear(cap));
    let loop_ = b.junction(K::One, "loop");
    b.chain(&[src, loop_, res]);
    b.bond(loop_, ind);
    b.bond(loop_, capacitor);
    b.output("i", f(ind));
    b.output("v_c", e(capacitor));
    b.finish()
}

#[test]
fn series_rlc_matches_hand_derivation() {
    let model = series_rlc();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    // λ̇ = V - R λ/L - q/C, q̇ = λ/L; i = λ/L, v_c = q/C.
    let mut rng = Rng(11);
    for _ in 0..5 {
        let (r, l, cap) = (
            rng.log_uniform(1.0, 1e3),
            rng.log_uniform(1e-4, 1e-1),
            rng.log_uniform(1e-9, 1e-3),
        );
        let ss = numeric_state_space(&eqs, StateSelection::Energy, &[r, l, cap]).expect("linear");
        assert_close(
            "A",
            &ss.a,
            &[vec![-r / l, -1.0 / cap], vec![1.0 / l, 0.0]],
            1e-12,
        );
        assert_close("B", &ss.b, &[vec![1.0], vec![0.0]], 1e-12);
        assert_close(
            "C",
            &ss.c,
            &[vec![1.0 / l, 0.0], vec![0.0, 1.0 / cap]],
            1e-12,
        );
    }
    insta::assert_snapshot!("series_rlc_text", to_text(&eqs));
    insta::assert_snapshot!("series_rlc_latex", bgc::equations::to_latex(&eqs));
}
