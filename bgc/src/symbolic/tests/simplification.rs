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

/// `n` distinct symbols summed: a sum longer than the engine merges into the sums and products that hold it.
fn long_sum(name: &str, n: usize) -> Expr {
    Expr::sum((0..n).map(|i| s(&format!("{name}{i}"))))
}

#[test]
fn a_long_sum_stays_whole_inside_sums_and_numeric_multiples() {
    let (x, big) = (s("x"), long_sum("t", 40));
    let scaled = 2.0 * &big;
    assert!(matches!(scaled.node(), Node::Mul(fs) if fs.len() == 2));
    let held = &x + &scaled;
    assert!(matches!(held.node(), Node::Add(ts) if ts.len() == 2));
    // It is one term: like terms of it still collect and cancel.
    assert!((&big - &big).is_zero());
    assert!((&held - &scaled - &x).is_zero());
    assert_eq!(&scaled + &big, 3.0 * &big);
    assert_eq!(-(-&big), big);
    // Multiplied out, it is the flat sum with every term scaled.
    let flat = Expr::sum((0..40).map(|i| 2.0 * s(&format!("t{i}"))));
    assert_eq!(scaled.expand(), flat);
    // A long sum whose first term is negative keeps its sign, in a sum and in a product alike.
    let negative = Expr::sum((0..40).map(|i| -s(&format!("n{i}"))));
    assert_eq!(&negative + &negative, 2.0 * &negative);
    assert!((&negative + &negative - 2.0 * &negative).is_zero());
    assert_eq!(-(-&negative), negative);
    assert!((&x * &negative - &negative * &x).is_zero());
    // A short sum is still merged and distributed.
    let short = long_sum("u", 5);
    assert!(matches!((&x + 2.0 * &short).node(), Node::Add(ts) if ts.len() == 6));
}

/// The efforts along a chain of junctions, each scaled by a transformer's numeric ratio,
/// `v_k = 1.001 (a_k + b_k + v_{k+1})`: shared, the chain is stored in a size linear in its length (merged into one
/// flat sum at each link, it was quadratic: 4,012,001 nodes at 2,000 links).
#[test]
fn a_chain_of_scaled_sums_is_stored_in_linear_size() {
    let n = 2000;
    let mut v = s("end");
    let mut all = Vec::with_capacity(n);
    for k in 0..n {
        v = 1.001 * (s(&format!("a{k}")) + s(&format!("b{k}")) + &v);
        all.push(v.clone());
    }
    let nodes = Expr::distinct_nodes(&all);
    assert!(nodes < 40 * n, "{nodes} nodes for {n} links");
    // The innermost terms carry the product of the ratios from the outermost link.
    let outer = all.last().cloned().unwrap_or_else(Expr::zero);
    let d = outer.diff(&Symbol::state("a0"));
    let expected = 1.001f64.powi(n as i32);
    let got = d.as_const().unwrap_or(f64::NAN);
    assert!(
        (got / expected - 1.0).abs() < 1e-12,
        "{got} against {expected}"
    );
}
