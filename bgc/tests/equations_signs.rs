//! The sign of `e(x)` and `f(x)` for every one-port kind and both directions of its bond (docs/language.md,
//! "Effort and flow of an element"): `f(x)` is counted into a C, I or R and out of a source, so that
//!
//! - a source's value is its own variable (`Sf x = v` gives `f(x) = v`, `Se x = v` gives `e(x) = v`);
//! - `q̇ = f(x)` for a C, `ṗ = e(x)` for an I, `e(x) = R f(x)` for an R;
//! - `e(x)·f(x)` is the power a source supplies and an R dissipates, as the energy terms say;
//! - the stored energy changes by supplied minus dissipated power (the physical law checked independently of the
//!   element-by-element rules).
//!
//! Each law is checked at random states and inputs, on a series circuit (one 1-junction, driven by an effort source)
//! and a parallel one (one 0-junction, driven by a flow source), for every combination of bond directions.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{EnergyKind, Equations, derive};
use bgc::ir::Model;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

const L: f64 = 0.7;
const CAP: f64 = 0.3;
const RES: f64 = 2.5;
const GAIN: f64 = 1.5;

/// The five one-ports around one junction; `reversed[k]` draws the bond of element `k` (source, coil, cap, res) the
/// unusual way. The source is `kind` with value `u` (`GAIN·u` for a modulated source).
fn circuit(kind: K, reversed: [bool; 4]) -> Model {
    let mut b = Builder::new("signs");
    let l = b.param("L", L);
    let cap_p = b.param("Cap", CAP);
    let r = b.param("R", RES);
    let u = b.input("u");
    let value = match kind {
        K::MSe | K::MSf => mul(c(GAIN), u),
        _ => u,
    };
    let junction = if matches!(kind, K::Se | K::MSe) {
        K::One
    } else {
        K::Zero
    };
    let j = b.junction(junction, "j");
    let src = b.node(kind, "src", source(value));
    let coil = b.node(K::I, "coil", linear(l));
    let cap = b.node(K::C, "cap", linear(cap_p));
    let res = b.node(K::R, "res", linear(r));
    // The standard direction is out of the source and into the others.
    let standard = [(src, j), (j, coil), (j, cap), (j, res)];
    for ((a, z), rev) in standard.into_iter().zip(reversed) {
        if rev {
            b.bond(z, a);
        } else {
            b.bond(a, z);
        }
    }
    for (name, n) in [("src", src), ("coil", coil), ("cap", cap), ("res", res)] {
        b.output(&format!("e_{name}_out"), e(n));
        b.output(&format!("f_{name}_out"), f(n));
    }
    b.finish()
}

fn state(eqs: &Equations, name: &str) -> usize {
    eqs.states
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no state `{name}` in {:?}", eqs.states))
}

fn energy(
    eqs: &Equations,
    element: &str,
    kind: EnergyKind,
    p: &[f64],
    x: &[f64],
    u: &[f64],
) -> f64 {
    let term = eqs
        .energy
        .iter()
        .find(|t| t.element == element && t.kind == kind)
        .and_then(|t| t.value.as_ref())
        .unwrap_or_else(|| panic!("no {kind:?} term of `{element}`"));
    sym::eval(term, &|s| match s {
        Sym::Param(i) => p.get(i).copied(),
        Sym::State(i) => x.get(i).copied(),
        Sym::Input(i) => u.get(i).copied(),
        Sym::Time => Some(0.0),
        _ => None,
    })
    .expect("the energy term evaluates")
}

fn close(what: &str, got: f64, want: f64) {
    let tol = 1e-12 * (1.0 + want.abs());
    assert!((got - want).abs() <= tol, "{what}: got {got}, want {want}");
}

fn check(kind: K, reversed: [bool; 4]) {
    let model = circuit(kind, reversed);
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(
        !bgc::diagnostic::has_errors(&diags),
        "{kind:?} {reversed:?}: {diags:?}"
    );
    let case = format!("{kind:?} with reversed bonds {reversed:?}");
    let (ip, iq) = (state(&eqs, "p_coil"), state(&eqs, "q_cap"));
    let p = eqs.default_params();
    let mut rng = Rng(11);
    for _ in 0..4 {
        let mut x = vec![0.0; eqs.states.len()];
        x[ip] = rng.next() * 4.0 - 2.0;
        x[iq] = rng.next() * 4.0 - 2.0;
        let u = [rng.next() * 4.0 - 2.0];
        let y = eqs.outputs_at(&p, &x, &u, 0.0).expect("outputs");
        let dx = eqs.rates_at(&p, &x, &u, 0.0).expect("rates");
        let (e_src, f_src, e_coil, f_coil, e_cap, f_cap, e_res, f_res) =
            (y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7]);
        let value = match kind {
            K::MSe | K::MSf => GAIN * u[0],
            _ => u[0],
        };
        // Each element's own law in its own variables.
        if matches!(kind, K::Se | K::MSe) {
            close(&format!("{case}: e(src) = its value"), e_src, value);
        } else {
            close(&format!("{case}: f(src) = its value"), f_src, value);
        }
        close(&format!("{case}: f(coil) = p/L"), f_coil, x[ip] / L);
        close(&format!("{case}: dp/dt = e(coil)"), dx[ip], e_coil);
        close(&format!("{case}: e(cap) = q/C"), e_cap, x[iq] / CAP);
        close(&format!("{case}: dq/dt = f(cap)"), dx[iq], f_cap);
        close(&format!("{case}: e(res) = R f(res)"), e_res, RES * f_res);
        // Powers: the energy terms are e·f of the element's own variables.
        let supplied = energy(&eqs, "src", EnergyKind::Supplied, &p, &x, &u);
        let dissipated = energy(&eqs, "res", EnergyKind::Dissipated, &p, &x, &u);
        close(
            &format!("{case}: supplied = e(src) f(src)"),
            supplied,
            e_src * f_src,
        );
        close(
            &format!("{case}: dissipated = e(res) f(res)"),
            dissipated,
            e_res * f_res,
        );
        // The physical law: d/dt (p²/2L + q²/2C) = supplied − dissipated.
        let stored_rate = x[ip] / L * dx[ip] + x[iq] / CAP * dx[iq];
        close(
            &format!("{case}: energy balance"),
            stored_rate,
            supplied - dissipated,
        );
    }
}

fn every_direction(kind: K) {
    for bits in 0..16u32 {
        let reversed = [0, 1, 2, 3].map(|k| bits & (1 << k) != 0);
        check(kind, reversed);
    }
}

#[test]
fn effort_source_and_storages_in_series_keep_their_signs_in_every_direction() {
    every_direction(K::Se);
}

#[test]
fn flow_source_and_storages_in_parallel_keep_their_signs_in_every_direction() {
    every_direction(K::Sf);
}

#[test]
fn modulated_sources_keep_their_signs_in_every_direction() {
    every_direction(K::MSe);
    every_direction(K::MSf);
}

/// The reported case of issue 13: `Sf isrc = i_in; bond isrc -> node -> cap, shunt; output i_isrc = f(isrc);` gives
/// `i_isrc = i_in` (D = 1), and `f(vsrc)` of `Se vsrc = u; bond vsrc -> loop -> coil, res;` is the loop current
/// `p/L`, not minus it.
#[test]
fn a_source_reads_its_own_flow() {
    let mut b = Builder::new("isrc");
    let i_in = b.input("i_in");
    let cp = b.param("Cap", CAP);
    let rp = b.param("R", RES);
    let isrc = b.node(K::Sf, "isrc", source(i_in));
    let node = b.junction(K::Zero, "node");
    let cap = b.node(K::C, "cap", linear(cp));
    let shunt = b.node(K::R, "shunt", linear(rp));
    b.chain(&[isrc, node, cap]);
    b.bond(node, shunt);
    b.output("i_isrc", f(isrc));
    let model = b.finish();
    let (causality, _) = analyse(&model);
    let (eqs, _) = derive(&model, &causality);
    let ss = bgc::equations::numeric_state_space(
        &eqs,
        bgc::equations::StateSelection::Energy,
        &eqs.default_params(),
    )
    .expect("linear");
    assert_eq!(ss.c, vec![vec![0.0]]);
    assert_eq!(ss.d, vec![vec![1.0]]);

    let mut b = Builder::new("vsrc");
    let u = b.input("u");
    let lp = b.param("L", L);
    let rp = b.param("R", RES);
    let vsrc = b.node(K::Se, "vsrc", source(u));
    let lp_j = b.junction(K::One, "loop");
    let coil = b.node(K::I, "coil", linear(lp));
    let res = b.node(K::R, "res", linear(rp));
    b.chain(&[vsrc, lp_j, coil]);
    b.bond(lp_j, res);
    b.output("i_vsrc", f(vsrc));
    let model = b.finish();
    let (causality, _) = analyse(&model);
    let (eqs, _) = derive(&model, &causality);
    let ss = bgc::equations::numeric_state_space(
        &eqs,
        bgc::equations::StateSelection::Energy,
        &eqs.default_params(),
    )
    .expect("linear");
    assert_eq!(ss.c, vec![vec![1.0 / L]]);
}
