//! Property tests on random expression trees.
//!
//! A [`Tree`] is an unsimplified expression evaluated directly in `f64`; building it through the constructors gives
//! the simplified [`Expr`]. Checked: simplification is idempotent (rebuilding the simplified form changes nothing),
//! printing is deterministic, the simplified form evaluates like the tree wherever the tree is finite, and the
//! derivative matches finite differences where the tree is smooth.

use super::super::{Expr, Node, Symbol, to_latex, to_rust, to_text};
use crate::ir::Func;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// A fixed seed: every run checks the same cases, so a failure is reproducible and a pass is not luck.
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(0x5eed_b0d0),
        failure_persistence: None,
        max_global_rejects: 10 * cases,
        ..ProptestConfig::default()
    }
}

#[derive(Clone, Debug)]
enum Tree {
    Const(f64),
    Var(usize),
    Add(Box<Tree>, Box<Tree>),
    Sub(Box<Tree>, Box<Tree>),
    Mul(Box<Tree>, Box<Tree>),
    Div(Box<Tree>, Box<Tree>),
    Neg(Box<Tree>),
    PowI(Box<Tree>, i32),
    PowF(Box<Tree>, f64),
    Call(Func, Vec<Tree>),
}

const VARS: [&str; 3] = ["x", "y", "k"];

fn symbol(i: usize) -> Symbol {
    match i {
        2 => Symbol::param("k"),
        _ => Symbol::state(VARS.get(i).copied().unwrap_or("x")),
    }
}

impl Tree {
    fn build(&self) -> Expr {
        match self {
            Tree::Const(c) => Expr::constant(*c),
            Tree::Var(i) => Expr::symbol(symbol(*i)),
            Tree::Add(a, b) => a.build() + b.build(),
            Tree::Sub(a, b) => a.build() - b.build(),
            Tree::Mul(a, b) => a.build() * b.build(),
            Tree::Div(a, b) => a.build() / b.build(),
            Tree::Neg(a) => -a.build(),
            Tree::PowI(a, n) => a.build().powi(*n),
            Tree::PowF(a, e) => a.build().pow(&Expr::constant(*e)),
            Tree::Call(f, args) => {
                let args: Vec<Expr> = args.iter().map(Tree::build).collect();
                Expr::call(*f, &args).unwrap_or_else(Expr::zero)
            }
        }
    }

    /// The value, and the largest magnitude met on the way (the scale of rounding errors).
    fn eval(&self, v: &[f64; 3]) -> (f64, f64) {
        self.eval_perturbed(v, 0.0)
    }

    /// As [`Tree::eval`], with every intermediate result `r` replaced by `r*(1 + eps) + eps`: comparing with
    /// `eps = 0` shows how much rounding-sized changes can move the result (its conditioning at this point).
    fn eval_perturbed(&self, v: &[f64; 3], eps: f64) -> (f64, f64) {
        let (val, scale) = match self {
            Tree::Const(c) => (*c, c.abs()),
            Tree::Var(i) => {
                let x = v.get(*i).copied().unwrap_or(f64::NAN);
                (x, x.abs())
            }
            Tree::Add(a, b) | Tree::Sub(a, b) | Tree::Mul(a, b) | Tree::Div(a, b) => {
                let ((x, sa), (y, sb)) = (a.eval_perturbed(v, eps), b.eval_perturbed(v, eps));
                let r = match self {
                    Tree::Add(..) => x + y,
                    Tree::Sub(..) => x - y,
                    Tree::Mul(..) => x * y,
                    _ => x / y,
                };
                (r, sa.max(sb))
            }
            Tree::Neg(a) => {
                let (x, s) = a.eval_perturbed(v, eps);
                (-x, s)
            }
            Tree::PowI(a, n) => {
                let (x, s) = a.eval_perturbed(v, eps);
                (x.powi(*n), s)
            }
            Tree::PowF(a, e) => {
                let (x, s) = a.eval_perturbed(v, eps);
                (if *e == 0.5 { x.sqrt() } else { x.powf(*e) }, s)
            }
            Tree::Call(f, args) => {
                let evals: Vec<(f64, f64)> =
                    args.iter().map(|a| a.eval_perturbed(v, eps)).collect();
                let x = evals.first().map_or(f64::NAN, |e| e.0);
                let y = evals.get(1).map_or(f64::NAN, |e| e.0);
                let mut s = evals.iter().map(|e| e.1).fold(0.0, f64::max);
                // On atan2's branch cut the sign of a zero decides between ±π, and simplification does not keep
                // signs of zeros (`-0` folds to `0`, `x*0` to `0`): mark the point as unusable.
                if *f == Func::Atan2 && x == 0.0 && y <= 0.0 {
                    s = f64::INFINITY;
                }
                let r = match f {
                    Func::Sin => x.sin(),
                    Func::Cos => x.cos(),
                    Func::Tan => x.tan(),
                    Func::Asin => x.asin(),
                    Func::Acos => x.acos(),
                    Func::Atan => x.atan(),
                    Func::Atan2 => x.atan2(y),
                    Func::Exp => x.exp(),
                    Func::Ln => x.ln(),
                    Func::Log10 => x.log10(),
                    Func::Sqrt => x.sqrt(),
                    Func::Abs => x.abs(),
                    Func::Sign => {
                        if x > 0.0 {
                            1.0
                        } else if x < 0.0 {
                            -1.0
                        } else {
                            x * 0.0
                        }
                    }
                    Func::Min | Func::Max if x.is_nan() || y.is_nan() => f64::NAN,
                    Func::Min => x.min(y),
                    Func::Max => x.max(y),
                    Func::Tanh => x.tanh(),
                    Func::Sinh => x.sinh(),
                    Func::Cosh => x.cosh(),
                };
                (r, s)
            }
        };
        (val * (1.0 + eps) + eps, scale.max(val.abs()))
    }

    /// Whether rounding-sized changes of intermediate results (relative `eps`) keep the value within `tol`.
    fn well_conditioned(&self, v: &[f64; 3], eps: f64, tol: f64) -> bool {
        let (a, _) = self.eval(v);
        [eps, -eps]
            .iter()
            .all(|e| (self.eval_perturbed(v, *e).0 - a).abs() <= tol)
    }
}

const SMOOTH: [Func; 13] = [
    Func::Sin,
    Func::Cos,
    Func::Tan,
    Func::Atan,
    Func::Exp,
    Func::Ln,
    Func::Sqrt,
    Func::Tanh,
    Func::Sinh,
    Func::Cosh,
    Func::Asin,
    Func::Acos,
    Func::Log10,
];

fn tree(smooth_only: bool) -> impl Strategy<Value = Tree> {
    let leaf = prop_oneof![
        (-3i32..=3).prop_map(|n| Tree::Const(f64::from(n))),
        (-20i32..=20).prop_map(|n| Tree::Const(f64::from(n) / 8.0)),
        (0usize..3).prop_map(Tree::Var),
        (0usize..3).prop_map(Tree::Var),
    ];
    leaf.prop_recursive(4, 24, 2, move |inner| {
        let unary = if smooth_only {
            proptest::sample::select(SMOOTH.to_vec()).boxed()
        } else {
            proptest::sample::select(
                Func::ALL
                    .iter()
                    .copied()
                    .filter(|f| f.arity() == 1)
                    .collect::<Vec<_>>(),
            )
            .boxed()
        };
        let binary = if smooth_only {
            Just(Func::Atan2).boxed()
        } else {
            proptest::sample::select(vec![Func::Atan2, Func::Min, Func::Max]).boxed()
        };
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Add(Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Sub(Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Mul(Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Div(Box::new(a), Box::new(b))),
            inner.clone().prop_map(|a| Tree::Neg(Box::new(a))),
            (inner.clone(), -3i32..=4).prop_map(|(a, n)| Tree::PowI(Box::new(a), n)),
            (inner.clone(), prop_oneof![Just(0.5), Just(-0.5), Just(1.5)])
                .prop_map(|(a, e)| Tree::PowF(Box::new(a), e)),
            (unary, inner.clone()).prop_map(|(f, a)| Tree::Call(f, vec![a])),
            (binary, inner.clone(), inner).prop_map(|(f, a, b)| Tree::Call(f, vec![a, b])),
        ]
    })
}

fn point() -> impl Strategy<Value = [f64; 3]> {
    [-2.0f64..2.0, -2.0f64..2.0, 0.5f64..2.0]
}

fn eval_expr(e: &Expr, v: &[f64; 3]) -> f64 {
    e.eval(|s: &Symbol| {
        VARS.iter()
            .position(|n| *n == s.name())
            .and_then(|i| v.get(i).copied())
    })
    .unwrap_or(f64::NAN)
}

fn rust_name(s: &Symbol) -> String {
    format!("v.{}", s.name())
}

proptest! {
    #![proptest_config(config(400))]

    #[test]
    fn simplification_is_idempotent(t in tree(false)) {
        let e = t.build();
        let again = rebuild(&e);
        prop_assert_eq!(&again, &e);
        prop_assert_eq!(to_text(&again), to_text(&e));
    }

    #[test]
    fn printing_is_deterministic(t in tree(false)) {
        let (a, b) = (t.build(), t.build());
        prop_assert_eq!(to_text(&a), to_text(&b));
        prop_assert_eq!(to_latex(&a), to_latex(&b));
        prop_assert_eq!(to_rust(&a, &rust_name), to_rust(&b, &rust_name));
    }

    #[test]
    fn simplified_form_evaluates_like_the_tree(t in tree(false), v in point()) {
        let (want, scale) = t.eval(&v);
        prop_assume!(want.is_finite() && scale < 1e8);
        let tol = 1e-9 * scale.max(1.0);
        // Near a singularity (asin at 1, sqrt at 0, a cancellation) rounding alone moves the value: skip.
        prop_assume!(t.well_conditioned(&v, 1e-13, tol / 10.0));
        let got = eval_expr(&t.build(), &v);
        prop_assert!(
            (got - want).abs() <= tol,
            "tree {:?} = {} but simplified {} = {}", t, want, t.build(), got
        );
    }

    #[test]
    fn derivative_matches_finite_differences(t in tree(true), v in point()) {
        let x = symbol(0);
        let f = |x0: f64| t.eval(&[x0, v[1], v[2]]);
        let (f0, scale) = f(v[0]);
        prop_assume!(f0.is_finite() && scale < 1e4);
        // Where a function is not differentiable (sqrt at 0) its value is ill-conditioned: skip.
        prop_assume!(t.well_conditioned(&v, 1e-10, 1e-7 * scale.max(1.0)));
        // Richardson: the estimates with h and h/2 must agree, or the point is too close to a singularity.
        let h = 1e-4;
        let fd = |h: f64| (f(v[0] + h).0 - f(v[0] - h).0) / (2.0 * h);
        let (d1, d2) = (fd(h), fd(h / 2.0));
        prop_assume!(d1.is_finite() && d2.is_finite());
        let tol = 1e-5 * scale.max(d2.abs()).max(1.0);
        prop_assume!((d1 - d2).abs() <= tol / 10.0);
        let exact = eval_expr(&t.build().diff(&x), &v);
        prop_assert!(
            (exact - d2).abs() <= tol,
            "d/dx {} = {} at {:?}: {} vs finite difference {} (tree {:?})", t.build(), t.build().diff(&x), v, exact, d2, t
        );
    }
}

/// The node built again through the constructors from its children (not `map_children`, which keeps a node whose
/// children are unchanged without rebuilding it).
fn rebuild(e: &Expr) -> Expr {
    match e.node() {
        Node::Const(_) | Node::Sym(_) => e.clone(),
        Node::Add(xs) => Expr::sum(xs.iter().cloned()),
        Node::Mul(xs) => Expr::product(xs.iter().cloned()),
        Node::Pow(b, x) => b.pow(x),
        Node::Call(f, xs) => Expr::call(*f, xs).unwrap_or_else(Expr::zero),
    }
}

/// Asserts the invariants of canonical form (see `Node`) on every node of `e`.
fn assert_canonical(e: &Expr) {
    match e.node() {
        Node::Const(c) => assert!(c.to_bits() != (-0.0f64).to_bits(), "-0 in {e}"),
        Node::Sym(_) => {}
        Node::Add(ts) => {
            assert!(ts.len() >= 2, "short sum {e}");
            assert!(ts.windows(2).all(|w| w[0] < w[1]), "unsorted sum {e}");
            assert!(
                ts.iter().skip(1).all(|t| t.as_const().is_none()),
                "constant not first in {e}"
            );
            assert!(
                ts.iter().all(|t| !matches!(t.node(), Node::Add(_))),
                "nested sum {e}"
            );
            assert!(
                ts.first().and_then(Expr::as_const) != Some(0.0),
                "zero term in {e}"
            );
            ts.iter().for_each(assert_canonical);
        }
        Node::Mul(fs) => {
            assert!(fs.len() >= 2, "short product {e}");
            assert!(fs.windows(2).all(|w| w[0] < w[1]), "unsorted product {e}");
            assert!(
                fs.iter().skip(1).all(|f| f.as_const().is_none()),
                "constant not first in {e}"
            );
            assert!(
                fs.iter().all(|f| !matches!(f.node(), Node::Mul(_))),
                "nested product {e}"
            );
            let c = fs.first().and_then(Expr::as_const);
            assert!(
                c != Some(0.0) && c != Some(1.0),
                "trivial coefficient in {e}"
            );
            let bases: Vec<&Expr> = fs.iter().map(|f| f.base_exp().0).collect();
            assert!(
                bases.windows(2).all(|w| w[0] != w[1]),
                "repeated base in {e}"
            );
            fs.iter().for_each(assert_canonical);
        }
        Node::Pow(b, x) => {
            assert!(!x.is_zero() && !x.is_one(), "trivial exponent in {e}");
            assert_canonical(b);
            assert_canonical(x);
        }
        Node::Call(f, args) => {
            assert!(
                *f != Func::Sqrt && args.iter().any(|a| a.as_const().is_none()),
                "foldable call {e}"
            );
            args.iter().for_each(assert_canonical);
        }
    }
}

proptest! {
    #![proptest_config(config(300))]

    #[test]
    fn built_expressions_are_canonical(t in tree(false)) {
        assert_canonical(&t.build());
    }

    #[test]
    fn sums_and_products_ignore_order_and_grouping(parts in proptest::collection::vec(tree(false), 1..6)) {
        let exprs: Vec<Expr> = parts.iter().map(Tree::build).collect();
        // Infinite coefficients are not normalised (`inf*(x + 1)` stays apart from `inf*x + inf`).
        prop_assume!(exprs.iter().all(|e| !has_non_finite_constant(e)));
        let reversed: Vec<Expr> = exprs.iter().rev().cloned().collect();
        // Left fold in one order against the n-ary constructor in the other.
        let folded_sum = exprs.iter().fold(Expr::zero(), |acc, e| acc + e);
        let nary_sum = Expr::sum(reversed.clone());
        prop_assert!(same_up_to_rounding(&folded_sum, &nary_sum), "{} vs {}", structure(&folded_sum), structure(&nary_sum));
        // Products: parts without sum factors (a numeric coefficient met by a lone sum is distributed at once, so
        // `(2*(x + 1))*y` and `2*((x + 1)*y)` differ by design; see `build.rs`).
        let has_sum_factor = |e: &Expr| match e.node() {
            Node::Const(_) => false,
            _ => e.coeff_and_factors().1.iter().any(|f| matches!(f.base_exp().0.node(), Node::Add(_))),
        };
        let exprs: Vec<Expr> = exprs.into_iter().filter(|e| !has_sum_factor(e)).collect();
        let reversed: Vec<Expr> = exprs.iter().rev().cloned().collect();
        let folded_product = exprs.iter().fold(Expr::one(), |acc, e| acc * e);
        let nary_product = Expr::product(reversed);
        prop_assert!(same_up_to_rounding(&folded_product, &nary_product), "{} vs {} from {:?}", structure(&folded_product), structure(&nary_product), parts);
    }
}

/// Structural equality with constants compared to a relative 1e-12: folding constants in another order rounds
/// differently (floating-point products and sums are not associative).
fn same_up_to_rounding(a: &Expr, b: &Expr) -> bool {
    // As multisets: a constant that differs in the last bit can change the sort order.
    let lists = |xs: &[Expr], ys: &[Expr]| {
        let mut unused: Vec<&Expr> = ys.iter().collect();
        xs.len() == ys.len()
            && xs.iter().all(
                |x| match unused.iter().position(|y| same_up_to_rounding(x, y)) {
                    Some(i) => {
                        unused.remove(i);
                        true
                    }
                    None => false,
                },
            )
    };
    match (a.node(), b.node()) {
        (Node::Const(x), Node::Const(y)) => {
            (x.is_nan() && y.is_nan()) || x == y || (x - y).abs() <= 1e-12 * x.abs().max(y.abs())
        }
        (Node::Sym(x), Node::Sym(y)) => x == y,
        (Node::Add(xs), Node::Add(ys)) | (Node::Mul(xs), Node::Mul(ys)) => lists(xs, ys),
        (Node::Pow(b1, e1), Node::Pow(b2, e2)) => {
            same_up_to_rounding(b1, b2) && same_up_to_rounding(e1, e2)
        }
        (Node::Call(f, xs), Node::Call(g, ys)) => f == g && lists(xs, ys),
        _ => false,
    }
}

fn has_non_finite_constant(e: &Expr) -> bool {
    match e.node() {
        Node::Const(c) => !c.is_finite(),
        Node::Sym(_) => false,
        Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => xs.iter().any(has_non_finite_constant),
        Node::Pow(b, x) => has_non_finite_constant(b) || has_non_finite_constant(x),
    }
}

/// The node structure, for failure messages.
fn structure(e: &Expr) -> String {
    let list = |xs: &[Expr]| xs.iter().map(structure).collect::<Vec<_>>().join(", ");
    match e.node() {
        Node::Const(c) => format!("{c:?}"),
        Node::Sym(s) => format!("{s:?}"),
        Node::Add(xs) => format!("Add[{}]", list(xs)),
        Node::Mul(xs) => format!("Mul[{}]", list(xs)),
        Node::Pow(b, x) => format!("Pow[{}, {}]", structure(b), structure(x)),
        Node::Call(f, xs) => format!("{}[{}]", f.name(), list(xs)),
    }
}
