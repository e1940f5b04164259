//! `Equations::param_jacobian_at` against the hand derivation of the mass-spring-damper.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::derive;
use bgc::ir::Model;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

/// `Se F -> 1 -> I m, C 1/k, R d`; outputs the spring deflection and the mass velocity; a derived `k2 = 2 k`
/// stiffness would move with `k`, so the spring is `1/k` directly.
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
fn parameter_jacobian_matches_the_hand_derivation() {
    let model = oscillator();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    // States [p, q]: ṗ = F − d p/m − k q, q̇ = p/m; outputs x = q, v = p/m.
    let (p, q, m, k, d) = (0.8, 0.01, 2.0, 800.0, 4.0);
    let given = vec![None; 3];
    let j = eqs
        .param_jacobian_at(&given, &[p, q], &[1.5], 0.0, &[0, 1, 2])
        .unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-7 * b.abs().max(1.0);
    // ∂ṗ/∂m = d p/m², ∂ṗ/∂k = −q, ∂ṗ/∂d = −p/m; ∂q̇/∂m = −p/m².
    let fp = [[d * p / (m * m), -q, -p / m], [-p / (m * m), 0.0, 0.0]];
    for (row, want) in j.fp.iter().zip(fp) {
        for (got, want) in row.iter().zip(want) {
            assert!(close(*got, want), "{:?}", j.fp);
        }
    }
    // ∂f/∂x = [[−d/m, −k], [1/m, 0]]; ∂h/∂x = [[0, 1], [1/m, 0]]; ∂h/∂p: only ∂v/∂m = −p/m².
    let fx = [[-d / m, -k], [1.0 / m, 0.0]];
    let hx = [[0.0, 1.0], [1.0 / m, 0.0]];
    let hp = [[0.0, 0.0, 0.0], [-p / (m * m), 0.0, 0.0]];
    for (got, want) in j.fx.iter().zip(fx).chain(j.hx.iter().zip(hx)) {
        assert!(
            got.iter().zip(want).all(|(g, w)| close(*g, w)),
            "{got:?} {want:?}"
        );
    }
    for (got, want) in j.hp.iter().zip(hp) {
        assert!(
            got.iter().zip(want).all(|(g, w)| close(*g, w)),
            "{got:?} {want:?}"
        );
    }
}

#[test]
fn a_parameter_index_out_of_range_is_an_error() {
    let model = oscillator();
    let (causality, _) = analyse(&model);
    let (eqs, _) = derive(&model, &causality);
    assert!(
        eqs.param_jacobian_at(&[None; 3], &[0.0, 0.0], &[0.0], 0.0, &[7])
            .is_err()
    );
}
