//! LaTeX printer: `\frac{}{}`, `x^{2}`, `\sqrt{}`, `\sin\left(...\right)`, `\left|x\right|`.
//!
//! Symbol names are typeset by [`latex_symbol`]: the part before the first `_` is the main symbol (a Greek letter
//! name becomes the letter, one character stays as is, a longer name is upright `\mathrm{}`), the rest is the
//! subscript (a Greek name becomes the letter, other text is kept with `_` escaped): `J_m` → `J_{m}`,
//! `theta_sint` → `\theta_{sint}`, `omega` → `\omega`, `x_theta` → `x_{\theta}`, `Kt` → `\mathrm{Kt}`.

use super::super::expr::{Expr, Symbol};
use super::plan::Kept;
use super::{ATOM, Doc, Layout, POWER, UNARY, number_text, split_fraction};
use crate::ir::Func;

const GREEK: [&str; 40] = [
    "alpha",
    "beta",
    "gamma",
    "delta",
    "epsilon",
    "varepsilon",
    "zeta",
    "eta",
    "theta",
    "vartheta",
    "iota",
    "kappa",
    "lambda",
    "mu",
    "nu",
    "xi",
    "pi",
    "varpi",
    "rho",
    "varrho",
    "sigma",
    "varsigma",
    "tau",
    "upsilon",
    "phi",
    "varphi",
    "chi",
    "psi",
    "omega",
    "Gamma",
    "Delta",
    "Theta",
    "Lambda",
    "Xi",
    "Pi",
    "Sigma",
    "Upsilon",
    "Phi",
    "Psi",
    "Omega",
];

fn is_greek(s: &str) -> bool {
    GREEK.contains(&s)
}

/// The LaTeX form of a symbol name (see the module docs).
pub fn latex_symbol(name: &str) -> String {
    match latex_symbol_parts(name) {
        (head, None) => head,
        (head, Some(sub)) => format!("{head}_{{{sub}}}"),
    }
}

/// The LaTeX form of a symbol name as its main symbol and its subscript, for a decoration that belongs on the main
/// symbol alone: `\dot{p}_{leg\_1}`, not `\dot{p_{leg\_1}}` (the dot over the middle of both).
pub fn latex_symbol_parts(name: &str) -> (String, Option<String>) {
    let (head, sub) = match name.split_once('_') {
        Some((h, s)) if !h.is_empty() && !s.is_empty() => (h, Some(s)),
        _ => (name, None),
    };
    let head = if is_greek(head) {
        format!("\\{head}")
    } else if head.chars().count() == 1 {
        head.to_string()
    } else {
        format!("\\mathrm{{{}}}", escape(head))
    };
    let sub = sub.map(|s| {
        if is_greek(s) {
            format!("\\{s}")
        } else {
            escape(s)
        }
    });
    (head, sub)
}

/// A name as a LaTeX subscript: kept as written, with `_` and the other special characters escaped.
pub fn latex_subscript(name: &str) -> String {
    escape(name)
}

/// Escapes the characters that are special in LaTeX math.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '_' | '#' | '$' | '%' | '&' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// `e` in LaTeX, symbols by [`latex_symbol`].
pub fn to_latex(e: &Expr) -> String {
    to_latex_with(e, &|s: &Symbol| latex_symbol(s.name()))
}

/// `e` in LaTeX, each symbol printed as `names` says.
pub fn to_latex_with(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> String {
    LatexPrinter {
        names,
        kept: Kept::new(),
    }
    .print_root(e)
}

/// A constant: `1.5 \cdot 10^{-7}` for exponent notation.
fn latex_number(c: f64) -> String {
    if c.is_nan() {
        return "\\mathrm{NaN}".to_string();
    }
    if c.is_infinite() {
        return if c > 0.0 { "\\infty" } else { "-\\infty" }.to_string();
    }
    let text = number_text(c);
    match text.split_once('e') {
        Some((mantissa, exp)) => format!("{mantissa} \\cdot 10^{{{exp}}}"),
        None => text,
    }
}

struct LatexPrinter<'a> {
    names: &'a dyn Fn(&Symbol) -> String,
    kept: Kept<Doc>,
}

impl LatexPrinter<'_> {
    /// Factors side by side, with `\cdot` where a factor starts with a digit (so `2 \cdot 3^{x}`, not `2 3^{x}`).
    fn juxtapose(&self, parts: Vec<Doc>) -> Doc {
        let mut out = Vec::with_capacity(2 * parts.len());
        for (i, p) in parts.into_iter().enumerate() {
            if i > 0 {
                out.push(Doc::text(if p.starts_with_digit() {
                    " \\cdot "
                } else {
                    " "
                }));
            }
            out.push(p);
        }
        Doc::cat(out)
    }

    fn factors(&self, coeff: Option<f64>, fs: &[Expr]) -> Doc {
        let alone = fs.len() + usize::from(coeff.is_some()) == 1;
        let mut parts: Vec<Doc> = coeff
            .map(|c| Doc::text(latex_number(c)))
            .into_iter()
            .collect();
        // A lone sum needs no parentheses inside a `\frac`.
        parts.extend(fs.iter().map(|f| {
            if alone {
                self.print(f).0
            } else {
                self.wrapped(f, UNARY)
            }
        }));
        if parts.is_empty() {
            Doc::text("1")
        } else {
            self.juxtapose(parts)
        }
    }
}

impl Layout for LatexPrinter<'_> {
    fn number(&self, c: f64) -> String {
        latex_number(c)
    }

    fn symbol(&self, s: &Symbol) -> String {
        (self.names)(s)
    }

    fn parenthesised(&self, s: Doc) -> Doc {
        s.wrap("\\left(", "\\right)")
    }

    fn kept(&self) -> &Kept<Doc> {
        &self.kept
    }

    fn product(&self, e: &Expr) -> Doc {
        let fr = split_fraction(e);
        let coeff = (fr.coeff != 1.0).then_some(fr.coeff);
        if fr.den.is_empty() {
            return self.factors(coeff, &fr.num);
        }
        Doc::cat(vec![
            Doc::text("\\frac{"),
            self.factors(coeff, &fr.num),
            Doc::text("}{"),
            self.factors(None, &fr.den),
            Doc::text("}"),
        ])
    }

    fn power(&self, base: &Expr, exp: &Expr) -> (Doc, u8) {
        if exp.as_const() == Some(0.5) {
            return (self.print(base).0.wrap("\\sqrt{", "}"), ATOM);
        }
        let b = self.wrapped(base, ATOM);
        (Doc::cat(vec![b, self.print(exp).0.wrap("^{", "}")]), POWER)
    }

    fn call(&self, f: Func, args: &[Expr]) -> Doc {
        let args: Vec<Doc> = args.iter().map(|a| self.print(a).0).collect();
        let inner = Doc::join(args, ", ");
        let name = match f {
            Func::Abs => return inner.wrap("\\left|", "\\right|"),
            Func::Sqrt => return inner.wrap("\\sqrt{", "}"),
            Func::Sin => "\\sin",
            Func::Cos => "\\cos",
            Func::Tan => "\\tan",
            Func::Asin => "\\arcsin",
            Func::Acos => "\\arccos",
            Func::Atan => "\\arctan",
            Func::Atan2 => "\\operatorname{atan2}",
            Func::Exp => "\\exp",
            Func::Ln => "\\ln",
            Func::Log10 => "\\log_{10}",
            Func::Sign => "\\operatorname{sign}",
            Func::Min => "\\min",
            Func::Max => "\\max",
            Func::Tanh => "\\tanh",
            Func::Sinh => "\\sinh",
            Func::Cosh => "\\cosh",
        };
        inner.wrap(format!("{name}\\left("), "\\right)")
    }
}
