//! Linear-coefficient extraction and expansion on hand examples.

use super::super::{Expr, Symbol, SymbolicError};
use super::{c, p, s};

fn vars(names: &[&str]) -> Vec<Symbol> {
    names.iter().map(|n| Symbol::state(*n)).collect()
}

#[test]
fn mass_spring_damper_rows() {
    // ṗ = -k q - (b/m) p + F: coefficients (-k, -b/m), rest F.
    let (q, pm, k, b, m) = (s("q"), s("p"), p("k"), p("b"), p("m"));
    let f = Expr::symbol(Symbol::input("F"));
    let rhs = -(&k * &q) - &b * &pm / &m + &f;
    let form = rhs
        .linear_form(&vars(&["q", "p"]))
        .map_err(|e| e.to_string());
    assert_eq!(
        form.map(|f| (f.coefficients, f.rest)),
        Ok((vec![-&k, -(&b / &m)], f))
    );
}

#[test]
fn coefficients_inside_products_of_sums_are_found() {
    // (a + b)(x + 2y) + 3 = (a + b) x + 2 (a + b) y + 3.
    let (x, y, a, b) = (s("x"), s("y"), p("a"), p("b"));
    let e = (&a + &b) * (&x + 2.0 * &y) + 3.0;
    let form = e.linear_form(&vars(&["x", "y"])).map_err(|e| e.to_string());
    assert_eq!(
        form.map(|f| (f.coefficients, f.rest)),
        Ok((vec![&a + &b, 2.0 * (&a + &b)], c(3.0)))
    );
}

#[test]
fn cancelling_coefficients_are_zero() {
    // x (a + b) - a x - b x + y: the x coefficient expands to 0.
    let (x, y, a, b) = (s("x"), s("y"), p("a"), p("b"));
    let e = &x * (&a + &b) - &a * &x - &b * &x + &y;
    let form = e.linear_form(&vars(&["x", "y"])).map_err(|e| e.to_string());
    assert_eq!(form.map(|f| f.coefficients), Ok(vec![c(0.0), c(1.0)]));
}

#[test]
fn hidden_linearity_is_found_by_expansion() {
    // x (x + 1) - x² = x.
    let x = s("x");
    let e = &x * (&x + 1.0) - x.powi(2);
    let form = e.linear_form(&vars(&["x"])).map_err(|e| e.to_string());
    assert_eq!(
        form.map(|f| (f.coefficients, f.rest)),
        Ok((vec![c(1.0)], c(0.0)))
    );
}

#[test]
fn nonlinear_expressions_are_refused() {
    let (x, y, k) = (s("x"), s("y"), p("k"));
    let vs = vars(&["x", "y"]);
    for e in [
        x.powi(2),
        &x * &y,
        x.sin(),
        &k / &x,
        k.pow(&x),
        Expr::min(&x, &k),
    ] {
        assert!(
            matches!(e.linear_form(&vs), Err(SymbolicError::NotLinear { .. })),
            "{e} must not be linear"
        );
    }
    assert_eq!(
        (&k * x.sin()).linear_form(&vs),
        Err(SymbolicError::NotLinear {
            symbol: "x".to_string(),
            term: "sin(x)".to_string()
        })
    );
}

#[test]
fn nonlinear_in_other_symbols_is_fine() {
    // sin(k) x + u²: linear in x with a nonlinear coefficient and rest.
    let (x, k, u) = (s("x"), p("k"), Expr::symbol(Symbol::input("u")));
    let e = k.sin() * &x + u.powi(2);
    let form = e.linear_form(&vars(&["x"])).map_err(|e| e.to_string());
    assert_eq!(
        form.map(|f| (f.coefficients, f.rest)),
        Ok((vec![k.sin()], u.powi(2)))
    );
}

#[test]
fn expansion_distributes_and_expands_powers() {
    let (x, y) = (s("x"), s("y"));
    assert_eq!(
        (&x + &y).powi(2).expand(),
        x.powi(2) + 2.0 * &x * &y + y.powi(2)
    );
    assert_eq!(((&x + 1.0) * (&x - 1.0)).expand(), x.powi(2) - 1.0);
    assert!((2.0 * (&x + &y) - 2.0 * &x - 2.0 * &y).expand().is_zero());
    // Inside function arguments too.
    assert_eq!(
        ((&x + 1.0).powi(2)).sin().expand(),
        (x.powi(2) + 2.0 * &x + 1.0).sin()
    );
    // Negative powers of sums are kept.
    assert_eq!((&x + &y).recip().expand(), (&x + &y).recip());
}
