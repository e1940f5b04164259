//! Plain-text printer in the syntax of bgc expressions: `+ - * / ^`, calls by name, minimal parentheses.
//!
//! Precedence follows docs/language.md (`+ -` < `* /` < unary `-` < `^`, `^` right-associative), so the text parses
//! back to an equal expression. Constants print so they parse back to the same `f64` (integers without `.0`;
//! non-finite values print as `inf`, `-inf`, `NaN`, which are not bgc syntax).

use super::super::expr::{Expr, Symbol};
use super::{ATOM, Layout, POWER, UNARY, number_text, split_fraction};
use crate::ir::Func;
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

impl Layout for TextPrinter<'_> {
    fn number(&self, c: f64) -> String {
        number_text(c)
    }

    fn symbol(&self, s: &Symbol) -> String {
        (self.names)(s)
    }

    fn parenthesised(&self, s: String) -> String {
        format!("({s})")
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

    fn call(&self, f: Func, args: &[Expr]) -> String {
        let args: Vec<String> = args.iter().map(|a| self.print(a).0).collect();
        format!("{}({})", f.name(), args.join(", "))
    }
}
