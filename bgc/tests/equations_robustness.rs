//! Large and malformed inputs: no panic, no stack overflow; a clear diagnostic instead.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::{StateSelection, derive, numeric_state_space};
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

/// A chain of `n` masses joined by springs, driven by a force at one end.
fn chain(n: usize) -> bgc::ir::Model {
    let mut b = Builder::new("chain");
    let m = b.param("m", 1.0);
    let k = b.param("k", 100.0);
    let force = b.input("F");
    let src = b.node(K::Se, "push", source(force));
    let mut prev = b.junction(K::One, "v0");
    b.bond(src, prev);
    let mass = b.node(K::I, "m0", linear(m.clone()));
    b.bond(prev, mass);
    for i in 1..n {
        let zero = b.junction(K::Zero, &format!("s{i}"));
        let spring = b.node(K::C, &format!("k{i}"), linear(div(c(1.0), k.clone())));
        let next = b.junction(K::One, &format!("v{i}"));
        let mass = b.node(K::I, &format!("m{i}"), linear(m.clone()));
        b.bond(prev, zero);
        b.bond(zero, spring);
        b.bond(zero, next);
        b.bond(next, mass);
        prev = next;
    }
    b.finish()
}

#[test]
fn a_long_chain_is_derived() {
    let model = chain(200);
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{:?}", diags.first());
    assert_eq!(eqs.energy_states, 399);
    let ss = numeric_state_space(&eqs, StateSelection::Energy, &[1.0, 100.0]).expect("linear");
    // The first mass feels the force and the first spring only.
    let p0 = eqs
        .states
        .iter()
        .position(|s| s.name == "p_m0")
        .expect("p_m0");
    assert_eq!(ss.b[p0][0], 1.0);
    assert_eq!(ss.a[p0].iter().filter(|v| **v != 0.0).count(), 1);
}

#[test]
fn a_very_long_dependency_chain_is_refused_without_crashing() {
    // A chain of 12000 resistors in series behind one inertia: every flow depends on the one before it.
    let mut b = Builder::new("long");
    let r = b.param("r", 1.0);
    let inertia = b.param("J", 1.0);
    let u = b.input("u");
    let src = b.node(K::Se, "drive", source(u));
    let j = b.junction(K::One, "w");
    b.bond(src, j);
    let i = b.node(K::I, "mass", linear(inertia));
    b.bond(j, i);
    let mut prev = j;
    for k in 0..12_000 {
        let next = b.junction(K::One, &format!("w{k}"));
        b.bond(prev, next);
        let res = b.node(K::R, &format!("r{k}"), linear(r.clone()));
        b.bond(next, res);
        prev = next;
    }
    let model = b.finish();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    // Derived exactly (ṗ = u - 12000 r p/J), or, past the resolver's depth limit, refused with a diagnostic: never
    // a crash, never a silent gap.
    match eqs.f.first().cloned().flatten() {
        Some(_) => {
            let ss =
                numeric_state_space(&eqs, StateSelection::Energy, &[1.0, 2.0]).expect("linear");
            assert!((ss.a[0][0] + 12_000.0 / 2.0).abs() < 1e-9, "{}", ss.a[0][0]);
            assert_eq!(ss.b[0][0], 1.0);
        }
        None => {
            let err = diags.iter().find(|d| d.is_error()).expect("an error");
            assert_eq!(err.code.0, "BG0605");
            assert!(err.message.contains("too long"), "{}", err.message);
        }
    }
}
