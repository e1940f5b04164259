//! Plain-text printer in the syntax of bgc expressions: `+ - * / ^`, calls by name, minimal parentheses.
//!
//! Precedence follows docs/language.md (`+ -` < `* /` < unary `-` < `^`, `^` right-associative), so the text parses
//! back to an equal expression. Constants print so they parse back to the same `f64` (integers without `.0`;
//! non-finite values print as `inf`, `-inf`, `NaN`, which are not bgc syntax).

use super::super::expr::{Expr, Node, Symbol};
use super::{
    ATOM, POWER, PRODUCT, SUM, UNARY, negated, number_text, reciprocal, split_fraction,
    sum_print_order,
};
use std::fmt;

/// `e` as text, symbols by their names.
pub fn to_text(e: &Expr) -> String {
    to_text_with(e, &|s: &Symbol| s.name().to_string())
}

/// `e` as text, each symbol printed as `names` says.
pub fn to_text_with(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> String {
    TextPrinter { names }.print(e).0
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&to_text(self))
    }
}

struct TextPrinter<'a> {
    names: &'a dyn Fn(&Symbol) -> String,
}

impl TextPrinter<'_> {
    /// The text and its binding strength.
    fn print(&self, e: &Expr) -> (String, u8) {
        match e.node() {
            Node::Const(c) => (number_text(*c), if *c < 0.0 { UNARY } else { ATOM }),
            Node::Sym(s) => ((self.names)(s), ATOM),
            Node::Add(terms) => (self.sum(terms), SUM),
            Node::Mul(_) => match negated(e) {
                Some(pos) => (format!("-{}", self.product(&pos)), PRODUCT),
                None => (self.product(e), PRODUCT),
            },
            Node::Pow(b, x) => match reciprocal(e) {
                Some(_) => (self.product(e), PRODUCT),
                None => self.power(b, x),
            },
            Node::Call(f, args) => {
                let args: Vec<String> = args.iter().map(|a| self.print(a).0).collect();
                (format!("{}({})", f.name(), args.join(", ")), ATOM)
            }
        }
    }

    /// `e` parenthesised when it binds less tightly than `need`.
    fn wrapped(&self, e: &Expr, need: u8) -> String {
        let (s, p) = self.print(e);
        if p < need { format!("({s})") } else { s }
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
            num.push(number_text(fr.coeff));
        }
        num.extend(fr.num.iter().map(|f| self.wrapped(f, UNARY)));
        let num = if num.is_empty() {
            "1".to_string()
        } else {
            num.join("*")
        };
        match fr.den.as_slice() {
            [] => num,
            [single] => format!("{num}/{}", self.wrapped(single, POWER)),
            many => {
                let den: Vec<String> = many.iter().map(|f| self.wrapped(f, UNARY)).collect();
                format!("{num}/({})", den.join("*"))
            }
        }
    }

    fn power(&self, base: &Expr, exp: &Expr) -> (String, u8) {
        if exp.as_const() == Some(0.5) {
            return (format!("sqrt({})", self.print(base).0), ATOM);
        }
        let b = self.wrapped(base, ATOM);
        let x = self.wrapped(exp, POWER);
        (format!("{b}^{x}"), POWER)
    }
}
