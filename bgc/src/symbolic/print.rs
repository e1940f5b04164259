//! Printers: plain text, LaTeX and Rust source.
//!
//! All three walk the canonical form in its sorted order, so the same expression always prints the same text. They
//! share the layout decisions made here: a sum prints its constant term last and its negative terms as `- term`; a
//! product prints its numeric coefficient first, then the factors with non-negative exponents, then `/` and the
//! factors with negative exponents (made positive); `x^0.5` prints as a square root.
//!
//! Each printer takes a closure mapping a symbol to its printed name, so the caller decides whether `J_m` prints as
//! `J_m`, `p.J_m` or `x[0]`. The walk itself (which node prints how, and a sum's terms) is [`Layout`]; a printer
//! that implements it supplies only its own forms of numbers, products, powers, calls and parentheses.
//!
//! Printing is memoised: shared subexpressions are printed once, and deep expressions are printed without deep
//! recursion and in time linear in the length of the text (`plan.rs`, `doc.rs`). [`cse`](super::cse) names the
//! shared subexpressions instead, for printing them as definitions.

mod doc;
pub mod latex;
mod plan;
pub mod rust;
pub mod text;

use super::expr::{Expr, Node, Symbol};
use crate::ir::Func;
use doc::Doc;
use plan::{Kept, plan};

/// Binding strength of what a printer produced, weakest first: callers parenthesise a part whose strength is below
/// what its position needs.
pub(super) const SUM: u8 = 1;
pub(super) const PRODUCT: u8 = 2;
pub(super) const UNARY: u8 = 3;
pub(super) const POWER: u8 = 4;
pub(super) const ATOM: u8 = 5;

/// `-e` when `e` prints with a leading minus (a negative constant or a product with a negative coefficient).
pub(super) fn negated(e: &Expr) -> Option<Expr> {
    match e.node() {
        Node::Const(c) if *c < 0.0 => Some(Expr::constant(-c)),
        Node::Mul(_) if e.coeff_and_factors().0 < 0.0 => Some(e.negated_product()),
        _ => None,
    }
}

/// The terms of a sum in print order: sorted, the constant last, then the first term that prints without a minus
/// moved to the front (`1 - x`, not `-x + 1`).
pub(super) fn sum_print_order(terms: &[Expr]) -> Vec<&Expr> {
    let (consts, others): (Vec<&Expr>, Vec<&Expr>) =
        terms.iter().partition(|t| t.as_const().is_some());
    let mut order: Vec<&Expr> = others.into_iter().chain(consts).collect();
    if let Some(i) = order.iter().position(|t| negated(t).is_none()) {
        let first_positive = order.remove(i);
        order.insert(0, first_positive);
    }
    order
}

/// A product laid out as `coeff * num / den`, the exponents of `den` made positive.
pub(super) struct Fraction {
    pub coeff: f64,
    pub num: Vec<Expr>,
    pub den: Vec<Expr>,
}

/// `b^(-e)` when `f = b^e` has a visibly negative exponent (a negative constant or a negative coefficient).
pub(super) fn reciprocal(f: &Expr) -> Option<Expr> {
    f.negative_power().map(|(b, e)| b.pow(&-e))
}

/// Splits a product (or a single power) into coefficient, numerator and denominator.
pub(super) fn split_fraction(e: &Expr) -> Fraction {
    let (coeff, factors) = match e.node() {
        Node::Mul(_) => e.coeff_and_factors(),
        _ => (1.0, std::slice::from_ref(e)),
    };
    let mut num = Vec::new();
    let mut den = Vec::new();
    for f in factors {
        match reciprocal(f) {
            Some(r) => den.push(r),
            None => num.push(f.clone()),
        }
    }
    Fraction { coeff, num, den }
}

/// Shortest text that parses back to exactly `c`: integers without a decimal point, others as Rust's `{:?}`.
pub(super) fn number_text(c: f64) -> String {
    if c.is_nan() {
        "NaN".to_string()
    } else if c.is_infinite() {
        if c > 0.0 { "inf" } else { "-inf" }.to_string()
    } else if c.fract() == 0.0 && c.abs() < 1e15 {
        format!("{c:.0}")
    } else {
        format!("{c:?}")
    }
}

/// The walk of an expression that the printers share; each printed part comes with its binding strength so that
/// its user can parenthesise it. A printer supplies the forms of its own language.
pub(super) trait Layout {
    /// A constant (a negative one binds as a unary minus).
    fn number(&self, c: f64) -> String;
    /// A symbol's printed name.
    fn symbol(&self, s: &Symbol) -> String;
    /// `s` in the printer's parentheses.
    fn parenthesised(&self, s: Doc) -> Doc;
    /// A product, or a power with a visibly negative exponent ([`split_fraction`] gives its parts); it binds as
    /// a product.
    fn product(&self, e: &Expr) -> Doc;
    /// `base^exp` for an exponent that is not visibly negative, with its binding strength.
    fn power(&self, base: &Expr, exp: &Expr) -> (Doc, u8);
    /// A function call; it binds as an atom.
    fn call(&self, f: Func, args: &[Expr]) -> Doc;
    /// The nodes printed ahead (see `plan.rs`).
    fn kept(&self) -> &Kept<Doc>;

    /// The whole text of `e`: the planned nodes first, bottom-up, then `e`.
    fn print_root(&self, e: &Expr) -> String {
        for (node, reused) in plan(e) {
            let printed = self.print_node(node);
            self.kept().insert(node, printed, reused);
        }
        self.print(e).0.into_string()
    }

    /// The text of `e` and its binding strength.
    fn print(&self, e: &Expr) -> (Doc, u8) {
        match self.kept().fetch(e) {
            Some(kept) => kept,
            None => self.print_node(e),
        }
    }

    /// The text of `e` and its binding strength, printed from its children.
    fn print_node(&self, e: &Expr) -> (Doc, u8) {
        match e.node() {
            Node::Const(c) => (
                Doc::text(self.number(*c)),
                if *c < 0.0 { UNARY } else { ATOM },
            ),
            Node::Sym(s) => (Doc::text(self.symbol(s)), ATOM),
            Node::Add(terms) => (self.sum(terms), SUM),
            Node::Mul(_) => match negated(e) {
                Some(pos) => (Doc::cat(vec![Doc::text("-"), self.product(&pos)]), PRODUCT),
                None => (self.product(e), PRODUCT),
            },
            Node::Pow(b, x) => match reciprocal(e) {
                Some(_) => (self.product(e), PRODUCT),
                None => self.power(b, x),
            },
            Node::Call(f, args) => (self.call(*f, args), ATOM),
        }
    }

    /// `e` parenthesised when it binds less tightly than `need`.
    fn wrapped(&self, e: &Expr, need: u8) -> Doc {
        let (s, p) = self.print(e);
        if p < need { self.parenthesised(s) } else { s }
    }

    /// The terms in [`sum_print_order`], joined by ` + ` and, for a term that prints with a leading minus,
    /// ` - ` and the term made positive.
    fn sum(&self, terms: &[Expr]) -> Doc {
        let mut out = Vec::with_capacity(2 * terms.len());
        for (i, t) in sum_print_order(terms).into_iter().enumerate() {
            match (i, negated(t)) {
                (0, _) => out.push(self.print(t).0),
                (_, Some(pos)) => {
                    out.push(Doc::text(" - "));
                    out.push(self.wrapped(&pos, PRODUCT));
                }
                (_, None) => {
                    out.push(Doc::text(" + "));
                    out.push(self.print(t).0);
                }
            }
        }
        Doc::cat(out)
    }
}
