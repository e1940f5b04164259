//! The memoised, stack-free operations against straightforward recursive references: evaluation to the bit and
//! text printing byte for byte, on random expressions and on random compositions that share subexpressions.
//!
//! The references are the tree walks the engine used before it walked DAGs: they visit a shared node once per use,
//! which is only affordable on small expressions, and they define what the results must be.

use super::super::eval::{apply_func, pow_f64};
use super::super::print::{ATOM, POWER, PRODUCT, SUM, UNARY, negated, number_text, reciprocal};
use super::super::print::{split_fraction, sum_print_order};
use super::super::{Expr, Node, Symbol, to_text};
use super::Rng;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// Evaluation by recursion over the tree, in the printers' order.
fn reference_eval(e: &Expr, env: &dyn Fn(&Symbol) -> f64) -> f64 {
    match e.node() {
        Node::Const(c) => *c,
        Node::Sym(s) => env(s),
        Node::Add(xs) => sum_print_order(xs)
            .into_iter()
            .fold(0.0, |acc, x| acc + reference_eval(x, env)),
        Node::Mul(_) => reference_fraction(e, env),
        Node::Pow(..) if e.negative_power().is_some() => reference_fraction(e, env),
        Node::Pow(b, x) => pow_f64(reference_eval(b, env), reference_eval(x, env)),
        Node::Call(f, xs) => {
            let args: Vec<f64> = xs.iter().map(|x| reference_eval(x, env)).collect();
            apply_func(*f, &args)
        }
    }
}

fn reference_fraction(e: &Expr, env: &dyn Fn(&Symbol) -> f64) -> f64 {
    let (coeff, factors) = match e.node() {
        Node::Mul(_) => e.coeff_and_factors(),
        _ => (1.0, std::slice::from_ref(e)),
    };
    let mut num = coeff;
    let mut den = 1.0;
    for f in factors {
        match f.negative_power() {
            Some((b, x)) => den *= pow_f64(reference_eval(b, env), -reference_eval(x, env)),
            None => num *= reference_eval(f, env),
        }
    }
    num / den
}

/// Text printing by recursion, building strings.
fn reference_text(e: &Expr) -> (String, u8) {
    match e.node() {
        Node::Const(c) => (number_text(*c), if *c < 0.0 { UNARY } else { ATOM }),
        Node::Sym(s) => (s.name().to_string(), ATOM),
        Node::Add(terms) => {
            let mut out = String::new();
            for (i, t) in sum_print_order(terms).into_iter().enumerate() {
                match (i, negated(t)) {
                    (0, _) => out.push_str(&reference_text(t).0),
                    (_, Some(pos)) => {
                        out.push_str(" - ");
                        out.push_str(&wrapped(&pos, PRODUCT));
                    }
                    (_, None) => {
                        out.push_str(" + ");
                        out.push_str(&reference_text(t).0);
                    }
                }
            }
            (out, SUM)
        }
        Node::Mul(_) => match negated(e) {
            Some(pos) => (format!("-{}", reference_product(&pos)), PRODUCT),
            None => (reference_product(e), PRODUCT),
        },
        Node::Pow(b, x) => match reciprocal(e) {
            Some(_) => (reference_product(e), PRODUCT),
            None if x.as_const() == Some(0.5) => (format!("sqrt({})", reference_text(b).0), ATOM),
            None => (format!("{}^{}", wrapped(b, ATOM), wrapped(x, POWER)), POWER),
        },
        Node::Call(f, args) => {
            let args: Vec<String> = args.iter().map(|a| reference_text(a).0).collect();
            (format!("{}({})", f.name(), args.join(", ")), ATOM)
        }
    }
}

fn wrapped(e: &Expr, need: u8) -> String {
    let (s, p) = reference_text(e);
    if p < need { format!("({s})") } else { s }
}

fn reference_product(e: &Expr) -> String {
    let fr = split_fraction(e);
    let mut num: Vec<String> = Vec::new();
    if fr.coeff != 1.0 {
        num.push(number_text(fr.coeff));
    }
    num.extend(fr.num.iter().map(|f| wrapped(f, UNARY)));
    let num = if num.is_empty() {
        "1".to_string()
    } else {
        num.join("*")
    };
    match fr.den.as_slice() {
        [] => num,
        [single] => format!("{num}/{}", wrapped(single, POWER)),
        many => {
            let den: Vec<String> = many.iter().map(|f| wrapped(f, UNARY)).collect();
            format!("{num}/({})", den.join("*"))
        }
    }
}

/// A random expression over `x`, `y`, `k` from shared pieces: each step combines two earlier pieces, so later
/// pieces use earlier ones several times.
fn random_dag(seed: u64, steps: usize) -> Expr {
    let mut rng = Rng(seed);
    let sym = |name: &str| match name {
        "k" => Expr::symbol(Symbol::param("k")),
        _ => Expr::symbol(Symbol::state(name)),
    };
    let mut pool = vec![sym("x"), sym("y"), sym("k"), Expr::constant(0.75)];
    for _ in 0..steps {
        let mut pick = || {
            let i = (rng.next_u64() % pool.len() as u64) as usize;
            pool[i].clone()
        };
        let (a, b) = (pick(), pick());
        let e = match rng.next_u64() % 12 {
            0 => &a + &b,
            1 => &a - &b,
            2 => &a * &b,
            3 => &a / (&b * &b + 1.0),
            4 => -&a * 1.5 + &b,
            5 => a.sin(),
            6 => (&a * 0.5).cos() * &b,
            7 => a.powi(2) - &b,
            8 => (a.powi(2) + 1.0).sqrt(),
            9 => Expr::atan2(&a, &b),
            10 => a.abs() + Expr::max(&a, &b),
            _ => (&a * 0.1).exp() / &b,
        };
        pool.push(e);
    }
    pool.pop().unwrap_or_else(Expr::zero)
}

fn env(v: [f64; 3]) -> impl Fn(&Symbol) -> f64 {
    move |s: &Symbol| match s.name() {
        "x" => v[0],
        "y" => v[1],
        _ => v[2],
    }
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(0xda9_c0de),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(300))]

    #[test]
    fn evaluation_agrees_with_the_tree_walk_to_the_bit(
        seed in any::<u64>(),
        steps in 1usize..14,
        v in [-2.0f64..2.0, -2.0f64..2.0, 0.5f64..2.0],
    ) {
        let e = random_dag(seed, steps);
        let want = reference_eval(&e, &env(v));
        let got = e.eval(|s| Some(env(v)(s))).unwrap_or(f64::NAN);
        prop_assert_eq!(got.to_bits(), want.to_bits(), "{} at {:?}", e, v);
    }

    #[test]
    fn printing_agrees_with_the_tree_walk_byte_for_byte(seed in any::<u64>(), steps in 1usize..12) {
        let e = random_dag(seed, steps);
        prop_assert_eq!(to_text(&e), reference_text(&e).0);
    }

    #[test]
    fn shared_derivatives_match_finite_differences(
        seed in any::<u64>(),
        steps in 1usize..10,
        v in [-2.0f64..2.0, -2.0f64..2.0, 0.5f64..2.0],
    ) {
        let e = random_dag(seed, steps);
        let at = |x: f64| reference_eval(&e, &env([x, v[1], v[2]]));
        let h = 1e-5;
        let fd = |h: f64| (at(v[0] + h) - at(v[0] - h)) / (2.0 * h);
        let (d1, d2) = (fd(h), fd(h / 2.0));
        let scale = at(v[0]).abs().max(d2.abs()).max(1.0);
        // Where the function is not smooth (abs, max, atan2's cut) or not finite, finite differences say nothing.
        prop_assume!(d1.is_finite() && d2.is_finite() && (d1 - d2).abs() <= 1e-6 * scale);
        let exact = reference_eval(&e.diff(&Symbol::state("x")), &env(v));
        prop_assert!((exact - d2).abs() <= 1e-5 * scale, "d/dx {} = {} vs {}", e, exact, d2);
    }
}

#[test]
fn printing_deep_shared_expressions_agrees_with_the_tree_walk() {
    // Deeper than the planner's spacing of kept nodes, with sharing, negated and reciprocal factors.
    for seed in 0..40 {
        let e = random_dag(seed, 60);
        if e.node_count() < 20_000 {
            assert_eq!(to_text(&e), reference_text(&e).0, "seed {seed}");
        }
    }
}
