//! Each simplification rule, and canonical equality of permuted inputs.

use super::super::{Expr, Node, Symbol};
use super::{c, p, s};
use crate::ir::Func;
use std::collections::HashSet;

#[test]
fn adding_zero_and_multiplying_by_one_are_identities() {
    let x = s("x");
    assert_eq!(&x + 0.0, x);
    assert_eq!(0.0 + &x, x);
    assert_eq!(&x * 1.0, x);
    assert_eq!(&x / 1.0, x);
}

#[test]
fn multiplying_by_zero_gives_zero() {
    let x = s("x");
    assert!((&x * 0.0).is_zero());
    assert!((c(0.0) * x.sin() * p("k")).is_zero());
}

#[test]
fn constants_fold() {
    assert_eq!(c(2.0) + c(3.0), c(5.0));
    assert_eq!(c(2.0) * c(3.0), c(6.0));
    assert_eq!(c(2.0).powi(10), c(1024.0));
    assert_eq!(c(1.0) / c(4.0), c(0.25));
    assert_eq!(c(0.0).cos(), c(1.0));
    assert_eq!(
        Expr::atan2(&c(1.0), &c(1.0)),
        c(std::f64::consts::FRAC_PI_4)
    );
    assert_eq!(c(-3.0).sign(), c(-1.0));
    assert_eq!(c(0.0).sign(), c(0.0));
    // Constants spread over a sum are gathered into one.
    let x = s("x");
    assert_eq!(1.0 + &x + 2.0, &x + 3.0);
}

#[test]
fn like_terms_collect() {
    let x = s("x");
    assert_eq!(2.0 * &x + 3.0 * &x, 5.0 * &x);
    assert_eq!(&x + &x, 2.0 * &x);
    assert!((&x - &x).is_zero());
    let kx = p("k") * &x;
    assert_eq!(&kx + 2.0 * &kx, 3.0 * &kx);
    // 2x + 3x = 5x is one product with coefficient 5.
    match (2.0 * &x + 3.0 * &x).node() {
        Node::Mul(fs) => assert_eq!(fs.first().and_then(Expr::as_const), Some(5.0)),
        other => panic!("expected a product, got {other:?}"),
    }
}

#[test]
fn like_factors_collect() {
    let x = s("x");
    assert_eq!(&x * &x, x.powi(2));
    assert_eq!(&x * &x * &x, x.powi(3));
    assert_eq!(x.powi(2) * x.powi(-2), c(1.0));
    assert_eq!(&x / &x, c(1.0));
    assert_eq!(x.sqrt() * x.sqrt(), x);
    let y = p("y");
    assert_eq!(x.pow(&y) * x.pow(&c(2.0)), x.pow(&(&y + 2.0)));
}

#[test]
fn powers_of_zero_and_one() {
    let x = s("x");
    assert_eq!(x.pow(&c(0.0)), c(1.0));
    assert_eq!(x.pow(&c(1.0)), x);
    assert_eq!(c(1.0).pow(&x), c(1.0));
}

#[test]
fn power_of_power_merges_for_integer_outer_exponents_only() {
    let x = s("x");
    assert_eq!(x.powi(2).powi(3), x.powi(6));
    assert_eq!(x.pow(&c(0.5)).powi(2), x);
    assert_eq!(x.pow(&p("a")).powi(2), x.pow(&(2.0 * p("a"))));
    // (x^2)^0.5 is |x|, not x: it must stay a power of a power.
    let root_of_square = x.powi(2).sqrt();
    assert_ne!(root_of_square, x);
    assert!(matches!(root_of_square.node(), Node::Pow(b, _) if matches!(b.node(), Node::Pow(..))));
}

#[test]
fn integer_power_of_product_distributes() {
    let (x, k) = (s("x"), p("k"));
    assert_eq!((2.0 * &x * &k).powi(2), 4.0 * x.powi(2) * k.powi(2));
    assert_eq!((2.0 * &x).recip(), 0.5 * x.recip());
}

#[test]
fn negation_and_division() {
    let (x, y) = (s("x"), s("y"));
    assert_eq!(-(-&x), x);
    assert_eq!(-(&x - &y), &y - &x);
    assert_eq!(&x / &y, &x * y.powi(-1));
    assert_eq!(&x - &y, &x + (-1.0) * &y);
}

#[test]
fn canonical_equality_ignores_order_and_grouping() {
    let (a, b, cc) = (p("a"), p("b"), s("c"));
    assert_eq!(&a * &b + &cc, &cc + &b * &a);
    assert_eq!((&a + &b) + &cc, &a + (&b + &cc));
    assert_eq!((&a * &b) * &cc, &a * (&b * &cc));
    assert_eq!(
        Expr::sum([cc.clone(), a.clone(), b.clone()]),
        Expr::sum([b.clone(), cc.clone(), a.clone()])
    );
    let set: HashSet<Expr> = [&a * &b + &cc, &cc + &b * &a, &b * &a + &cc]
        .into_iter()
        .collect();
    assert_eq!(set.len(), 1);
}

#[test]
fn symbols_differ_by_kind() {
    let as_param = Expr::symbol(Symbol::param("x"));
    let as_state = Expr::symbol(Symbol::state("x"));
    assert_ne!(as_param, as_state);
    assert!(!(&as_param - &as_state).is_zero());
}

#[test]
fn sqrt_is_a_half_power_and_calls_fold() {
    let x = s("x");
    assert_eq!(
        Expr::call(Func::Sqrt, std::slice::from_ref(&x)),
        Some(x.pow(&c(0.5)))
    );
    assert_eq!(
        Expr::call(Func::Min, &[x.clone(), x.clone()]),
        Some(x.clone())
    );
    assert_eq!(Expr::call(Func::Sin, &[]), None);
    assert_eq!(Expr::call(Func::Atan2, std::slice::from_ref(&x)), None);
    assert_eq!((-2.0 * &x).abs(), 2.0 * x.abs());
    assert_eq!((-2.0 * &x).sign(), -x.sign());
    assert_eq!(x.abs().abs(), x.abs());
}

#[test]
fn negative_zero_and_nan_constants_are_normalised() {
    assert_eq!(c(-0.0), c(0.0));
    assert!(c(-0.0).is_zero());
    assert_eq!(c(f64::NAN), c(-f64::NAN));
}

#[test]
fn numeric_coefficient_distributes_over_a_single_sum() {
    let (x, y) = (s("x"), s("y"));
    assert_eq!(2.0 * (&x + &y), 2.0 * &x + 2.0 * &y);
    // A symbolic factor does not distribute.
    let k = p("k");
    assert!(matches!((&k * (&x + &y)).node(), Node::Mul(_)));
}

#[test]
fn powers_that_collapse_to_another_base_merge_again() {
    // ((y^1.5)^0.5)^2 = y^1.5, which must merge with y.
    let y = s("y");
    let root = y.pow(&c(1.5)).sqrt();
    assert_eq!(
        Expr::product([y.clone(), root.clone(), root]),
        y.pow(&c(2.5))
    );
}

#[test]
fn sums_inside_products_have_a_positive_leading_coefficient() {
    let (x, y, z) = (s("x"), s("y"), s("z"));
    assert_eq!((&y - &x) * &z, -((&x - &y) * &z));
    assert_eq!((-&x - 1.0).powi(2), (&x + 1.0).powi(2));
    assert_eq!((-&x - 1.0).powi(3), -(&x + 1.0).powi(3));
    // Numeric factors other than the sign stay inside (see the module docs of `build.rs`).
    assert_ne!(
        (2.0 * &x + 2.0) * &y,
        Expr::product([c(2.0), &x + 1.0, y.clone()])
    );
    assert_eq!(
        ((2.0 * &x + 2.0) * &y).expand(),
        Expr::product([c(2.0), &x + 1.0, y]).expand()
    );
}
