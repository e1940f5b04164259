//! Derivatives of every function against central finite differences at random points.

use super::super::{Expr, Symbol};
use super::{Rng, c, p, s};
use crate::ir::Func;

/// Central difference of `e` in `x` at `x0` with `others` bound for the remaining symbols.
fn central_difference(e: &Expr, x: &Symbol, x0: f64, others: &[(Symbol, f64)]) -> f64 {
    let h = 1e-5 * x0.abs().max(1.0);
    let at = |v: f64| {
        e.eval(|sym: &Symbol| {
            if sym == x {
                Some(v)
            } else {
                others.iter().find(|(o, _)| o == sym).map(|(_, val)| *val)
            }
        })
        .unwrap_or(f64::NAN)
    };
    (at(x0 + h) - at(x0 - h)) / (2.0 * h)
}

/// Checks `d e/dx` against finite differences at `n` points of `[lo, hi]`.
fn check_derivative(e: &Expr, lo: f64, hi: f64, rng: &mut Rng) {
    let x = Symbol::state("x");
    let y = (Symbol::param("y"), 0.7);
    let d = e.diff(&x);
    for _ in 0..20 {
        let x0 = rng.uniform(lo, hi);
        let exact = d
            .eval(|sym: &Symbol| if sym == &x { Some(x0) } else { Some(y.1) })
            .unwrap_or(f64::NAN);
        let fd = central_difference(e, &x, x0, std::slice::from_ref(&y));
        let tol = 1e-6 * exact.abs().max(1.0);
        assert!(
            (exact - fd).abs() <= tol,
            "d/dx {e} = {d} at x = {x0}: {exact} vs finite difference {fd}"
        );
    }
}

#[test]
fn every_function_differentiates_like_its_finite_difference() {
    let mut rng = Rng(7);
    let x = s("x");
    // The argument is itself a function of x, so the chain rule is exercised too.
    let u = 0.3 * &x + 0.1;
    let cases: Vec<(Func, f64, f64)> = vec![
        (Func::Sin, -3.0, 3.0),
        (Func::Cos, -3.0, 3.0),
        (Func::Tan, -3.0, 3.0),
        (Func::Asin, -3.0, 2.5),
        (Func::Acos, -3.0, 2.5),
        (Func::Atan, -3.0, 3.0),
        (Func::Exp, -3.0, 3.0),
        (Func::Ln, 0.5, 3.0),
        (Func::Log10, 0.5, 3.0),
        (Func::Sqrt, 0.5, 3.0),
        (Func::Abs, -3.0, -0.5),
        (Func::Abs, 0.5, 3.0),
        (Func::Sign, 0.5, 3.0),
        (Func::Tanh, -3.0, 3.0),
        (Func::Sinh, -3.0, 3.0),
        (Func::Cosh, -3.0, 3.0),
    ];
    for (func, lo, hi) in cases {
        let e = Expr::call(func, std::slice::from_ref(&u)).unwrap_or_else(Expr::zero);
        check_derivative(&e, lo, hi, &mut rng);
    }
}

#[test]
fn two_argument_functions_differentiate_like_their_finite_differences() {
    let mut rng = Rng(11);
    let (x, y) = (s("x"), p("y"));
    let a = x.powi(2) + 1.0;
    // atan2 in all quadrants.
    check_derivative(&Expr::atan2(&a, &(&x * &y)), -3.0, 3.0, &mut rng);
    check_derivative(&Expr::atan2(&(&x - 0.2), &c(-1.0)), -3.0, 3.0, &mut rng);
    // min/max on each side of the crossing x² + 1 = 2x + 1 (x = 0 and x = 2).
    for (lo, hi) in [(-3.0, -0.1), (0.1, 1.9), (2.1, 4.0)] {
        check_derivative(&Expr::min(&a, &(2.0 * &x + 1.0)), lo, hi, &mut rng);
        check_derivative(&Expr::max(&a, &(2.0 * &x + 1.0)), lo, hi, &mut rng);
    }
}

#[test]
fn powers_differentiate_in_base_and_exponent() {
    let mut rng = Rng(3);
    let (x, y) = (s("x"), p("y"));
    check_derivative(&x.powi(3), -2.0, 2.0, &mut rng);
    check_derivative(&x.powi(-2), 0.5, 2.0, &mut rng);
    check_derivative(&x.pow(&c(1.7)), 0.5, 2.0, &mut rng);
    check_derivative(&x.pow(&y), 0.5, 2.0, &mut rng);
    check_derivative(&y.pow(&x), -2.0, 2.0, &mut rng);
    check_derivative(&x.pow(&x), 0.5, 2.0, &mut rng);
    check_derivative(&((&x + 1.0) / (x.powi(2) + 2.0)), -2.0, 2.0, &mut rng);
}

#[test]
fn hand_derivatives() {
    let (x, k) = (Symbol::state("x"), p("k"));
    let xe = Expr::symbol(x.clone());
    assert_eq!((&k * xe.powi(2)).diff(&x), 2.0 * &k * &xe);
    assert_eq!(xe.sin().diff(&x), xe.cos());
    assert_eq!(xe.abs().diff(&x), xe.sign());
    assert!(xe.sign().diff(&x).is_zero());
    assert!(k.diff(&x).is_zero());
    // d/dx min(x, k) = (1 - sign(x - k))/2: 1 below k, 0 above, 1/2 at the crossing.
    let dmin = Expr::min(&xe, &k).diff(&x);
    let at = |xv: f64| dmin.eval(|s: &Symbol| Some(if s == &x { xv } else { 1.0 }));
    assert_eq!(at(0.0), Ok(1.0));
    assert_eq!(at(2.0), Ok(0.0));
    assert_eq!(at(1.0), Ok(0.5));
}

#[test]
fn jacobian_of_a_pendulum() {
    // ẋ1 = x2, ẋ2 = -g/l sin(x1) - b x2: J = [[0, 1], [-g/l cos(x1), -b]].
    let (x1, x2) = (Symbol::state("x1"), Symbol::state("x2"));
    let (g, l, b) = (p("g"), p("l"), p("b"));
    let f = [
        Expr::symbol(x2.clone()),
        -(&g / &l) * Expr::symbol(x1.clone()).sin() - &b * Expr::symbol(x2.clone()),
    ];
    let j = Expr::jacobian(&f, &[x1.clone(), x2.clone()]);
    let expected = vec![
        vec![c(0.0), c(1.0)],
        vec![-(&g / &l) * Expr::symbol(x1).cos(), -b],
    ];
    assert_eq!(j, expected);
}

/// A row that reads more than 64 variables is differentiated in reverse mode: every entry equals the derivative
/// taken variable by variable (forward, as for narrow rows), at random points, through every kind of node (sums
/// inside products, powers with the variable in the exponent, calls of two arguments, a variable used twice).
#[test]
fn a_wide_row_has_the_gradient_of_forward_differentiation() {
    let n = 100;
    let xs: Vec<Symbol> = (0..n).map(|k| Symbol::state(format!("x{k}"))).collect();
    let x = |k: usize| Expr::symbol(xs[k % n].clone());
    let k = p("k");
    let terms: Vec<Expr> = (0..n)
        .map(|i| match i % 5 {
            0 => &k * x(i) * x(i + 1).sin(),
            1 => (x(i) + x(i + 3) * 2.0).powi(3) / (1.0 + x(i + 7).powi(2)),
            2 => x(i).pow(&(x(i + 1) * 0.1)) + Expr::atan2(&x(i + 2), &x(i)),
            3 => Expr::max(&x(i), &x(i + 4)) * x(i).exp(),
            _ => x(i) * x(i) * (x(i + 9) + &k).ln(),
        })
        .collect();
    let row = Expr::sum(terms) * (x(0) + x(50) + 3.0);
    let entries = Expr::sparse_jacobian(std::slice::from_ref(&row), &xs);
    assert_eq!(entries.len(), n, "every variable is read");
    let mut rng = Rng(41);
    for _ in 0..5 {
        let point: Vec<f64> = (0..n).map(|_| rng.uniform(0.5, 1.5)).collect();
        let env = |sym: &Symbol| {
            if sym == &Symbol::param("k") {
                return Some(0.3);
            }
            xs.iter().position(|x| x == sym).map(|i| point[i])
        };
        for (_, j, entry) in &entries {
            let reverse = entry.eval(env).unwrap_or(f64::NAN);
            let forward = row.diff(&xs[*j]).eval(env).unwrap_or(f64::NAN);
            assert!(
                (reverse - forward).abs() <= 1e-12 * forward.abs().max(1.0),
                "∂/∂x{j}: {reverse} (reverse) vs {forward} (forward)"
            );
        }
    }
}

/// A product of many factors that vary with `x` (differentiated one factor at a time, sharing the tails) has the
/// derivative its finite difference gives, with constant factors, powers and a factor that is a sum of the
/// variable's functions among them.
#[test]
fn a_product_of_many_varying_factors_differentiates_like_its_finite_difference() {
    let x = Symbol::state("x");
    let xe = Expr::symbol(x.clone());
    let factors: Vec<Expr> = (1..=9)
        .map(|k| 1.0 + f64::from(k) * 0.1 * (&xe + f64::from(k) * 0.3).cos())
        .chain([xe.sin().powi(3), xe.exp(), p("k")])
        .collect();
    let product = Expr::product(factors);
    let d = product.diff(&x);
    let mut rng = Rng(7);
    for _ in 0..20 {
        let x0 = rng.uniform(-3.0, 3.0);
        let k = (Symbol::param("k"), 1.7);
        let exact = d
            .eval(|s: &Symbol| Some(if s == &x { x0 } else { 1.7 }))
            .unwrap_or(f64::NAN);
        let fd = central_difference(&product, &x, x0, &[k]);
        assert!(
            (exact - fd).abs() <= 1e-6 * exact.abs().max(1.0),
            "x = {x0}: {exact} vs {fd}"
        );
    }
}

/// The size of expressions as stored: each distinct node and the references to its children.
fn stored_size(exprs: &[Expr]) -> usize {
    let dag = super::super::dag::Dag::new(exprs);
    dag.order
        .iter()
        .map(|e| {
            let mut children = 0;
            e.node().for_each_child(|_| children += 1);
            1 + children
        })
        .sum()
}

/// The derivatives by the angle of the flows along a chain of `n` modulated transformers whose moduli all vary
/// with it, `v_k = n_{k+1} ⋯ n_N` (distinct moduli: the engine keeps their product flat), taken together.
fn chain_flow_derivatives(n: usize) -> Vec<Expr> {
    let theta = Symbol::state("theta");
    let moduli: Vec<Expr> = (1..=n)
        .map(|k| 1.0 + p(&format!("a{k}")) * Expr::symbol(theta.clone()).cos())
        .collect();
    let flows: Vec<Expr> = (0..n)
        .map(|k| Expr::product(moduli[k..].iter().cloned()))
        .collect();
    let column = Expr::jacobian(&flows, std::slice::from_ref(&theta));
    column.into_iter().flatten().collect()
}

/// The derivatives of the chain's flows share their tails, so they grow with the square of the chain as stored:
/// doubling it multiplies their size by about 4 (2,231 at 20 links, 8,287 at 40). The flat product rule grew with
/// the cube, a product of `m` factors for each of the `m` factors of each flow (3,875 and 25,745).
#[test]
fn the_derivatives_of_a_chain_of_products_share_their_tails() {
    let (small, large) = (
        stored_size(&chain_flow_derivatives(20)),
        stored_size(&chain_flow_derivatives(40)),
    );
    assert!(
        large <= 5 * small,
        "{small} -> {large}: more than quadratic"
    );
    // The last flow is one modulus; its derivative is `-a40 sin(theta)`.
    let last = chain_flow_derivatives(40).pop().unwrap_or_else(Expr::zero);
    assert_eq!(
        last,
        -(p("a40") * Expr::symbol(Symbol::state("theta")).sin())
    );
}
