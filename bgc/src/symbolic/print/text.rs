//! Plain-text printer in the syntax of bgc expressions: `+ - * / ^`, calls by name, minimal parentheses.
//!
//! Precedence follows docs/language.md (`+ -` < `* /` < unary `-` < `^`, `^` right-associative), so the text parses
//! back to an equal expression. Constants print so they parse back to the same `f64` (integers without `.0`;
//! non-finite values print as `inf`, `-inf`, `NaN`, which are not bgc syntax).

use super::super::expr::{Expr, Symbol};
use super::plan::Kept;
use super::{ATOM, Doc, Layout, POWER, UNARY, number_text, split_fraction};
use crate::ir::Func;
use std::fmt;

/// `e` as text, symbols by their names.
pub fn to_text(e: &Expr) -> String {
    to_text_with(e, &|s: &Symbol| s.to_string())
}

/// `e` as text, each symbol printed as `names` says.
pub fn to_text_with(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> String {
    TextPrinter {
        names,
        kept: Kept::new(),
    }
    .print_root(e)
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&to_text(self))
    }
}

struct TextPrinter<'a> {
    names: &'a dyn Fn(&Symbol) -> String,
    kept: Kept<Doc>,
}

impl Layout for TextPrinter<'_> {
    fn number(&self, c: f64) -> String {
        number_text(c)
    }

    fn symbol(&self, s: &Symbol) -> String {
        (self.names)(s)
    }

    fn parenthesised(&self, s: Doc) -> Doc {
        s.wrap("(", ")")
    }

    fn kept(&self) -> &Kept<Doc> {
        &self.kept
    }

    fn product(&self, e: &Expr) -> Doc {
        let fr = split_fraction(e);
        let mut num: Vec<Doc> = Vec::new();
        if fr.coeff != 1.0 {
            num.push(Doc::text(number_text(fr.coeff)));
        }
        num.extend(fr.num.iter().map(|f| self.wrapped(f, UNARY)));
        let num = if num.is_empty() {
            Doc::text("1")
        } else {
            Doc::join(num, "*")
        };
        match fr.den.as_slice() {
            [] => num,
            [single] => Doc::cat(vec![num, Doc::text("/"), self.wrapped(single, POWER)]),
            many => {
                let den: Vec<Doc> = many.iter().map(|f| self.wrapped(f, UNARY)).collect();
                Doc::cat(vec![
                    num,
                    Doc::text("/"),
                    Doc::join(den, "*").wrap("(", ")"),
                ])
            }
        }
    }

    fn power(&self, base: &Expr, exp: &Expr) -> (Doc, u8) {
        if exp.as_const() == Some(0.5) {
            return (self.print(base).0.wrap("sqrt(", ")"), ATOM);
        }
        let b = self.wrapped(base, ATOM);
        let x = self.wrapped(exp, POWER);
        (Doc::cat(vec![b, Doc::text("^"), x]), POWER)
    }

    fn call(&self, f: Func, args: &[Expr]) -> Doc {
        let args: Vec<Doc> = args.iter().map(|a| self.print(a).0).collect();
        Doc::join(args, ", ").wrap(format!("{}(", f.name()), ")")
    }
}
