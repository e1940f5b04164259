//! Evaluation against direct f64 computation, free symbols, substitution.

use super::super::{Expr, Symbol, SymbolKind, SymbolicError, sign};
use super::{Rng, c, p, s};
use std::collections::BTreeMap;

#[test]
fn evaluation_matches_f64_arithmetic() {
    let (x, y, k) = (s("x"), s("y"), p("k"));
    let e = (&k * x.sin() + y.powi(3) / (1.0 + x.powi(2))).sqrt()
        - Expr::atan2(&y, &x) * x.exp().ln().abs();
    let mut rng = Rng(1);
    for _ in 0..50 {
        let (xv, yv, kv) = (
            rng.uniform(-2.0, 2.0),
            rng.uniform(0.0, 2.0),
            rng.uniform(1.0, 3.0),
        );
        let direct = (kv * xv.sin() + yv.powi(3) / (1.0 + xv.powi(2))).sqrt()
            - yv.atan2(xv) * xv.exp().ln().abs();
        let env: BTreeMap<Symbol, f64> = [
            (Symbol::state("x"), xv),
            (Symbol::state("y"), yv),
            (Symbol::param("k"), kv),
        ]
        .into_iter()
        .collect();
        let got = e.eval_map(&env).unwrap_or(f64::NAN);
        if direct.is_finite() {
            assert!(
                (got - direct).abs() <= 1e-12 * direct.abs().max(1.0),
                "{got} vs {direct}"
            );
        } else {
            assert!(!got.is_finite());
        }
    }
}

#[test]
fn unbound_symbols_are_errors() {
    let e = s("x") + p("k");
    let only_x = |sym: &Symbol| (sym.name() == "x").then_some(1.0);
    assert_eq!(
        e.eval(only_x),
        Err(SymbolicError::UnboundSymbol {
            name: "k".to_string(),
            kind: SymbolKind::Param
        })
    );
}

#[test]
fn non_finite_values_propagate() {
    let x = s("x");
    assert!(x.ln().eval(|_: &Symbol| Some(-1.0)).is_ok_and(f64::is_nan));
    assert_eq!((1.0 / &x).eval(|_: &Symbol| Some(0.0)), Ok(f64::INFINITY));
}

#[test]
fn sign_is_zero_at_zero() {
    assert_eq!(sign(0.0), 0.0);
    assert_eq!(sign(-0.0), 0.0);
    assert_eq!(sign(2.5), 1.0);
    assert_eq!(sign(-1e-300), -1.0);
    assert!(sign(f64::NAN).is_nan());
    assert_eq!(s("x").sign().eval(|_: &Symbol| Some(0.0)), Ok(0.0));
}

#[test]
fn min_and_max_propagate_nan_unlike_f64() {
    let (x, y) = (s("x"), s("y"));
    let env = |sym: &Symbol| Some(if sym.name() == "x" { f64::NAN } else { 2.0 });
    assert!(Expr::min(&x, &y).eval(env).is_ok_and(f64::is_nan));
    assert!(Expr::max(&y, &x).eval(env).is_ok_and(f64::is_nan));
    let env = |sym: &Symbol| Some(if sym.name() == "x" { -1.0 } else { 2.0 });
    assert_eq!(Expr::min(&x, &y).eval(env), Ok(-1.0));
    assert_eq!(Expr::max(&x, &y).eval(env), Ok(2.0));
}

#[test]
fn free_symbols_are_listed_in_order() {
    let e = s("q") * p("k") + Expr::symbol(Symbol::input("u")) + Expr::symbol(Symbol::time()).sin();
    let names: Vec<(String, SymbolKind)> = e
        .free_symbols()
        .into_iter()
        .map(|s| (s.name().to_string(), s.kind()))
        .collect();
    assert_eq!(
        names,
        vec![
            ("k".to_string(), SymbolKind::Param),
            ("u".to_string(), SymbolKind::Input),
            ("t".to_string(), SymbolKind::Time),
            ("q".to_string(), SymbolKind::State),
        ]
    );
    assert!(c(3.0).free_symbols().is_empty());
}

#[test]
fn substitution_is_simultaneous_and_simplifies() {
    let (x, y) = (s("x"), s("y"));
    // Swap x and y: a sequential substitution would give y + y.
    let map: BTreeMap<Symbol, Expr> = [
        (Symbol::state("x"), y.clone()),
        (Symbol::state("y"), x.clone()),
    ]
    .into_iter()
    .collect();
    assert_eq!((2.0 * &x + &y).substitute(&map), 2.0 * &y + &x);
    // x*y with y := 1/x simplifies to 1.
    let inv: BTreeMap<Symbol, Expr> = [(Symbol::state("y"), x.recip())].into_iter().collect();
    assert_eq!((&x * &y).substitute(&inv), c(1.0));
    // Substituting numbers folds to a constant.
    let nums = |_: &Symbol| Some(c(2.0));
    assert_eq!(
        (x.powi(2) + x.sin()).substitute_with(&nums),
        c(4.0 + 2f64.sin())
    );
}
