//! Rust source printer for generated model code.
//!
//! Forms: `x.powi(2)` for integer constant exponents, `x.sqrt()` for `x^0.5`, `x.powf(e)` otherwise, `1.0 / x` for
//! negative exponents, `x.sin()` for one-argument functions, `f64::atan2(y, x)`. These are the formulas the
//! evaluator uses (`eval.rs`), so evaluation and generated code agree.
//!
//! `sign`, `min` and `max` print as calls to helpers ([`RUST_SIGN_FN`], [`RUST_MIN_FN`], [`RUST_MAX_FN`]):
//! `f64::signum(0.0)` is 1 while bgc's `sign(0)` is 0, and `f64::min`/`f64::max` return the other argument for a
//! NaN while bgc's propagate it. The generated code must define the helpers once; [`RUST_HELPERS`] is their source.
//!
//! Constants print as Rust's shortest round-trip `f64` literals (`2.0`, `0.1`, `1e-7`), with an `_f64` suffix when
//! they are the receiver of a method call (`2.0_f64.powf(x)`, `(-2.0_f64).powf(x)`), and `f64::INFINITY`, `f64::NEG_INFINITY`,
//! `f64::NAN` for non-finite values. Symbol names come from the caller's closure and must be Rust expressions that
//! bind at least as tightly as a method call (a path, a field access `p.J_m` or an index `x[0]`).

use super::super::eval::as_i32;
use super::super::expr::{Expr, Node, Symbol};
use super::{ATOM, PRODUCT, SUM, UNARY, negated, reciprocal, split_fraction, sum_print_order};
use crate::ir::Func;

/// The name of the sign helper that printed code calls.
pub const RUST_SIGN_FN: &str = "bgc_sign";
/// The name of the NaN-propagating minimum that printed code calls.
pub const RUST_MIN_FN: &str = "bgc_min";
/// The name of the NaN-propagating maximum that printed code calls.
pub const RUST_MAX_FN: &str = "bgc_max";

/// The source of the helpers printed code calls: [`RUST_SIGN_FN`] (`sign(±0) = 0`, `sign(NaN) = NaN`, else ±1),
/// [`RUST_MIN_FN`] and [`RUST_MAX_FN`] (NaN when either argument is NaN). Generated code includes it once.
pub const RUST_HELPERS: &str = include_str!("rust_helpers.rs");

/// `e` as a Rust `f64` expression, each symbol printed as `names` says.
pub fn to_rust(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> String {
    RustPrinter { names }.print(e).0
}

fn rust_number(c: f64) -> String {
    if c.is_nan() {
        "f64::NAN".to_string()
    } else if c.is_infinite() {
        if c > 0.0 {
            "f64::INFINITY"
        } else {
            "f64::NEG_INFINITY"
        }
        .to_string()
    } else {
        format!("{c:?}")
    }
}

struct RustPrinter<'a> {
    names: &'a dyn Fn(&Symbol) -> String,
}

impl RustPrinter<'_> {
    fn print(&self, e: &Expr) -> (String, u8) {
        match e.node() {
            Node::Const(c) => (rust_number(*c), if *c < 0.0 { UNARY } else { ATOM }),
            Node::Sym(s) => ((self.names)(s), ATOM),
            Node::Add(terms) => (self.sum(terms), SUM),
            Node::Mul(_) => match negated(e) {
                Some(pos) => (format!("-{}", self.product(&pos)), PRODUCT),
                None => (self.product(e), PRODUCT),
            },
            Node::Pow(b, x) => match reciprocal(e) {
                Some(_) => (self.product(e), PRODUCT),
                None => (self.power(b, x), ATOM),
            },
            Node::Call(f, args) => (self.call(*f, args), ATOM),
        }
    }

    fn wrapped(&self, e: &Expr, need: u8) -> String {
        let (s, p) = self.print(e);
        if p < need { format!("({s})") } else { s }
    }

    /// `e` as the receiver of a method call.
    fn receiver(&self, e: &Expr) -> String {
        // A literal receiver needs its type spelled out: `2.0.sqrt()` does not compile, `2.0_f64.sqrt()` does.
        match e.as_const() {
            Some(c) if c.is_finite() && c >= 0.0 => format!("{}_f64", rust_number(c)),
            Some(c) if c.is_finite() => format!("({}_f64)", rust_number(c)),
            _ => self.wrapped(e, ATOM),
        }
    }

    fn sum(&self, terms: &[Expr]) -> String {
        let mut out = String::new();
        for (i, t) in sum_print_order(terms).into_iter().enumerate() {
            match (i, negated(t)) {
                (0, _) => out.push_str(&self.print(t).0),
                (_, Some(pos)) => {
                    out.push_str(" - ");
                    out.push_str(&self.wrapped(&pos, PRODUCT));
                }
                (_, None) => {
                    out.push_str(" + ");
                    out.push_str(&self.print(t).0);
                }
            }
        }
        out
    }

    fn product(&self, e: &Expr) -> String {
        let fr = split_fraction(e);
        let mut num: Vec<String> = Vec::new();
        if fr.coeff != 1.0 {
            num.push(rust_number(fr.coeff));
        }
        num.extend(fr.num.iter().map(|f| self.wrapped(f, UNARY)));
        let num = if num.is_empty() {
            "1.0".to_string()
        } else {
            num.join(" * ")
        };
        match fr.den.as_slice() {
            [] => num,
            [single] => format!("{num} / {}", self.wrapped(single, ATOM)),
            many => {
                let den: Vec<String> = many.iter().map(|f| self.wrapped(f, UNARY)).collect();
                format!("{num} / ({})", den.join(" * "))
            }
        }
    }

    fn power(&self, base: &Expr, exp: &Expr) -> String {
        let b = self.receiver(base);
        match exp.as_const() {
            Some(0.5) => format!("{b}.sqrt()"),
            Some(c) => match as_i32(c) {
                Some(n) => format!("{b}.powi({n})"),
                None => format!("{b}.powf({})", rust_number(c)),
            },
            None => format!("{b}.powf({})", self.print(exp).0),
        }
    }

    fn call(&self, f: Func, args: &[Expr]) -> String {
        let printed: Vec<String> = args.iter().map(|a| self.print(a).0).collect();
        match f {
            Func::Atan2 => format!("f64::atan2({})", printed.join(", ")),
            Func::Min => format!("{RUST_MIN_FN}({})", printed.join(", ")),
            Func::Max => format!("{RUST_MAX_FN}({})", printed.join(", ")),
            Func::Sign => format!("{RUST_SIGN_FN}({})", printed.join(", ")),
            _ => {
                let zero = Expr::zero();
                format!(
                    "{}.{}()",
                    self.receiver(args.first().unwrap_or(&zero)),
                    f.name()
                )
            }
        }
    }
}
