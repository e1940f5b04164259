//! Printer snapshots for text, LaTeX and Rust, and the exact forms the code generators rely on.

use super::super::{
    Expr, RUST_HELPER_FNS, RUST_HELPER_PREFIX, RUST_HELPERS, RustCode, RustOp, Symbol, SymbolKind,
    latex_subscript, latex_symbol, latex_symbol_parts, rust_helpers_used, to_latex, to_rust,
    to_rust_code, to_text,
};
use super::{c, p, s};

/// A gallery of expressions covering every printing rule.
fn gallery() -> Vec<Expr> {
    let (x, y, k, m, b) = (s("x"), s("y"), p("k"), p("m"), p("b"));
    let jm = p("J_m");
    let theta = s("theta_sint");
    let tau = Expr::symbol(Symbol::input("tau"));
    let t = Expr::symbol(Symbol::time());
    vec![
        c(2.0),
        c(-0.1),
        c(1e-7),
        c(6.02214076e23),
        c(f64::INFINITY),
        &x + 1.0,
        &x - 1.0,
        1.0 - &x,
        -&x,
        -(&k * &x) / &m - &b * &y / &m + &tau,
        x.powi(2),
        x.powi(-1),
        x.powi(-2) * &k,
        &k / (&m * &jm),
        x.sqrt(),
        x.pow(&c(-0.5)),
        x.pow(&c(1.5)),
        x.pow(&y),
        x.pow(&-&y),
        (&x + &y).powi(2),
        (&x + &y).recip(),
        (&x + &y).pow(&(&k + 1.0)),
        &k * (&x + &y),
        c(2.0).pow(&x),
        3.0 * c(2.0).pow(&x),
        x.powi(2).sqrt(),
        (&jm * &theta).sin(),
        theta.cos().powi(2),
        Expr::atan2(&y, &x),
        Expr::min(&x, &k) + Expr::max(&y, &k),
        x.abs() * x.sign(),
        (&x * &y).sqrt(),
        x.exp() + x.ln() + x.log10() + x.tan() + x.asin() + x.acos() + x.atan(),
        x.tanh() - x.sinh() * x.cosh(),
        (-(&x) + 2.0).abs(),
        t.sin() * &tau,
        0.5 * &k * x.powi(2) + 0.5 * &m * y.powi(2),
    ]
}

fn table(print: impl Fn(&Expr) -> String) -> String {
    gallery()
        .iter()
        .map(|e| format!("{}\n", print(e)))
        .collect()
}

/// Rust names: parameters from `p`, states from `x[i]`, others bare.
fn rust_name(sym: &Symbol) -> String {
    match sym.kind() {
        SymbolKind::Param => format!("p.{}", sym.name()),
        SymbolKind::State => format!("x[{}]", if sym.name() == "x" { 0 } else { 1 }),
        _ => sym.name().to_string(),
    }
}

#[test]
fn text_snapshot() {
    insta::assert_snapshot!(table(to_text));
}

#[test]
fn latex_snapshot() {
    insta::assert_snapshot!(table(to_latex));
}

#[test]
fn rust_snapshot() {
    insta::assert_snapshot!(table(|e| to_rust(e, &rust_name)));
}

#[test]
fn printing_is_deterministic_across_construction_orders() {
    let (a, b, cc) = (p("a"), p("b"), s("c"));
    let one = &a * &b + &cc;
    let other = &cc + &b * &a;
    assert_eq!(to_text(&one), to_text(&other));
    assert_eq!(to_latex(&one), to_latex(&other));
    assert_eq!(to_rust(&one, &rust_name), to_rust(&other, &rust_name));
}

#[test]
fn latex_symbol_names() {
    assert_eq!(latex_symbol("J_m"), "J_{m}");
    assert_eq!(latex_symbol("theta_sint"), "\\theta_{sint}");
    assert_eq!(latex_symbol("omega"), "\\omega");
    assert_eq!(latex_symbol("x_theta"), "x_{\\theta}");
    assert_eq!(latex_symbol("p_rotor_x"), "p_{rotor\\_x}");
    assert_eq!(latex_symbol("Kt"), "\\mathrm{Kt}");
    assert_eq!(latex_symbol("x"), "x");
    assert_eq!(latex_symbol("_x"), "\\mathrm{\\_x}");
    // The main symbol apart, for a dot over it alone (`\dot{p}_{leg\_1}`).
    assert_eq!(
        latex_symbol_parts("p_leg_1"),
        ("p".to_string(), Some("leg\\_1".to_string()))
    );
    assert_eq!(latex_symbol_parts("omega"), ("\\omega".to_string(), None));
    // An element's name as a subscript reads as in its states' names: `E_{leg\_1}` beside `p_{leg\_1}`.
    assert_eq!(latex_subscript("leg_1"), "leg\\_1");
}

#[test]
fn rust_forms_the_code_generators_rely_on() {
    let x = s("x");
    assert_eq!(to_rust(&x.powi(2), &rust_name), "bgc_powi(x[0], 2)");
    assert_eq!(to_rust(&x.powi(-3), &rust_name), "1.0 / bgc_powi(x[0], 3)");
    assert_eq!(to_rust(&x.sqrt(), &rust_name), "libm::sqrt(x[0])");
    assert_eq!(
        to_rust(&Expr::atan2(&p("a"), &x), &rust_name),
        "libm::atan2(p.a, x[0])"
    );
    assert_eq!(to_rust(&x.sign(), &rust_name), "bgc_sign(x[0])");
    assert_eq!(to_rust(&x.ln(), &rust_name), "libm::log(x[0])");
    assert_eq!(to_rust(&x.abs(), &rust_name), "libm::fabs(x[0])");
    assert_eq!(to_rust(&c(0.1), &rust_name), "0.1");
    assert_eq!(to_rust(&c(2.0).pow(&x), &rust_name), "libm::pow(2.0, x[0])");
    assert_eq!(
        to_rust(&c(1e-7).pow(&x), &rust_name),
        "libm::pow(1e-7, x[0])"
    );
    assert_eq!(
        to_rust(&c(-2.0).pow(&x), &rust_name),
        "libm::pow(-2.0, x[0])"
    );
    assert_eq!(
        to_rust(&c(f64::NAN).pow(&x), &rust_name),
        "libm::pow(f64::NAN, x[0])"
    );
    // A negated product carries the minus on its first operand, as Rust parses `-a * b`.
    let code = to_rust_code(&-(p("k") * &x), &rust_name);
    assert_eq!(
        code,
        RustCode::Chain(
            Box::new(RustCode::Neg(Box::new(RustCode::Atom("p.k".into())))),
            vec![(RustOp::Mul, RustCode::Atom("x[0]".into()))]
        )
    );
    assert_eq!(code.to_string(), "-p.k * x[0]");
}

#[test]
fn only_the_helpers_a_piece_of_code_calls_are_picked() {
    assert_eq!(rust_helpers_used("x + 1.0"), "");
    let picked = rust_helpers_used("bgc_powi(x, 2) + bgc_sign(y)");
    assert!(picked.starts_with("/// `sign(x)`"), "{picked}");
    assert!(picked.contains("fn bgc_sign(") && picked.contains("fn bgc_powi("));
    assert!(!picked.contains("fn bgc_min(") && !picked.contains("fn bgc_max("));
    // Generated modules indent them by four spaces inside a `pub mod`: they must fit in 96 columns.
    assert!(RUST_HELPERS.lines().all(|l| l.chars().count() <= 96));
    // All four, in file order, give the file back.
    let all = rust_helpers_used("bgc_sign( bgc_min( bgc_max( bgc_powi(");
    assert_eq!(all.trim_end(), RUST_HELPERS.trim_end());
    // The generator looks for the common start of their names first.
    for name in RUST_HELPER_FNS {
        assert!(name.starts_with(RUST_HELPER_PREFIX), "{name}");
    }
}

#[test]
fn numbers_round_trip_through_text() {
    for v in [
        0.1,
        1.0 / 3.0,
        2.0,
        -7.0,
        1e-7,
        6.02214076e23,
        123456.789,
        1e15,
        f64::MIN_POSITIVE,
        f64::MAX,
    ] {
        let printed = to_text(&c(v));
        assert_eq!(printed.parse::<f64>(), Ok(v), "{printed}");
        let rust = to_rust(&c(v), &rust_name);
        assert_eq!(rust.parse::<f64>(), Ok(v), "{rust}");
    }
}

/// The Rust printer's output for [`end_to_end_expr`], pasted here so the compiler checks it and the test below can
/// run it: printing is compared to this text, and its value to the evaluator's.
mod generated {
    include!("../print/rust_helpers.rs");

    pub struct Params {
        pub k: f64,
        pub m: f64,
    }

    pub fn value(x: &[f64; 2], p: &Params) -> f64 {
        libm::pow(2.0, x[1]) - p.k * x[0] / p.m
            + bgc_powi(libm::cos(libm::exp(x[0])), 3)
                / (libm::pow(libm::fabs(x[1]), 1.5) * (x[0] + x[1]))
            + libm::atan2(x[1], x[0]) * libm::sqrt(bgc_powi(x[0], 2) + 1.0)
            + bgc_sign(x[1]) * bgc_min(x[0], p.k)
            - bgc_max(x[1], 0.0)
    }

    pub fn helpers(v: f64) -> [f64; 3] {
        [bgc_sign(v), bgc_min(v, 0.0), bgc_max(0.0, v)]
    }

    pub fn powi(x: f64, n: i32) -> f64 {
        bgc_powi(x, n)
    }
}

const END_TO_END_RUST: &str = "libm::pow(2.0, x[1]) - p.k * x[0] / p.m + bgc_powi(libm::cos(libm::exp(x[0])), 3) \
    / (libm::pow(libm::fabs(x[1]), 1.5) * (x[0] + x[1])) + libm::atan2(x[1], x[0]) * libm::sqrt(bgc_powi(x[0], 2) + 1.0) \
    + bgc_sign(x[1]) * bgc_min(x[0], p.k) - bgc_max(x[1], 0.0)";

fn end_to_end_expr() -> Expr {
    let (x, y, k, m) = (s("x"), s("y"), p("k"), p("m"));
    -(&k * &x) / &m + y.sign() * Expr::min(&x, &k) - Expr::max(&y, &c(0.0))
        + c(2.0).pow(&y)
        + Expr::atan2(&y, &x) * (x.powi(2) + 1.0).sqrt()
        + (&x + &y).recip() * x.exp().cos().powi(3) / y.abs().pow(&c(1.5))
}

#[test]
fn printed_rust_compiles_and_computes_what_eval_computes() {
    let e = end_to_end_expr();
    assert_eq!(to_rust(&e, &rust_name), END_TO_END_RUST);
    let params = generated::Params { k: 1.5, m: 0.8 };
    let mut rng = super::Rng(21);
    for _ in 0..50 {
        let x = [rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0)];
        let env = |sym: &Symbol| match sym.name() {
            "x" => Some(x[0]),
            "y" => Some(x[1]),
            "k" => Some(params.k),
            "m" => Some(params.m),
            _ => None,
        };
        let (compiled, evaluated) = (
            generated::value(&x, &params),
            e.eval(env).unwrap_or(f64::NAN),
        );
        // Same formulas in the same order: the same bits.
        assert_eq!(
            compiled.to_bits(),
            evaluated.to_bits(),
            "{compiled} vs {evaluated} at {x:?}"
        );
    }
}

#[test]
fn rust_helpers_follow_bgc_conventions() {
    assert_eq!(generated::helpers(0.0), [0.0, 0.0, 0.0]);
    assert_eq!(generated::helpers(-3.0), [-1.0, -3.0, 0.0]);
    assert_eq!(generated::helpers(2.0), [1.0, 0.0, 2.0]);
    assert!(generated::helpers(f64::NAN).iter().all(|v| v.is_nan()));
}

#[test]
fn integer_powers_by_binary_powering() {
    use generated::powi;
    // Exact cases: every intermediate product is representable.
    assert_eq!(powi(3.0, 5), 243.0);
    assert_eq!(powi(-2.0, 3), -8.0);
    assert_eq!(powi(2.0, -3), 0.125);
    assert_eq!(powi(1.5, 2), 2.25);
    assert_eq!(powi(7.0, 0), 1.0);
    assert_eq!(powi(0.0, -1), f64::INFINITY);
    // The most negative exponent neither overflows nor panics: 2^-(2^31) underflows to 0.
    assert_eq!(powi(2.0, i32::MIN), 0.0);
    assert!(powi(f64::NAN, 2).is_nan());
    // Inexact cases: within a few rounding errors of the correctly rounded power.
    for (x, n) in [(1.1_f64, 7), (0.3, 11), (-1.7, 5), (2.5, -6)] {
        let want = x.powf(f64::from(n));
        assert!(
            (powi(x, n) - want).abs() <= 4.0 * f64::EPSILON * want.abs(),
            "{x}^{n}"
        );
    }
}
