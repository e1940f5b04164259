//! Simplifying constructors: every expression is put in canonical form as it is built.
//!
//! Rules applied on construction:
//! - sums: nested sums of at most [`FLAT_SUM`] terms are flattened, constants folded, like terms collected
//!   (`2*x + 3*x = 5*x`), zero terms dropped (`x + 0 = x`, `x - x = 0`); a longer sum inside a sum is one term of it
//!   (so `S - S = 0` still holds for it, but its terms do not meet the outer sum's);
//! - products: nested products flattened, constants folded, like factors collected by adding exponents
//!   (`x*x = x^2`, `x^a * x^b = x^(a+b)`, `x/x = 1`), `x*1 = x`, `x*0 = 0`, and a numeric coefficient times a single
//!   sum of at most [`FLAT_SUM`] terms is distributed (`-(a - b) = b - a`, so `-(-x) = x`);
//! - sums inside products (of at most [`FLAT_SUM`] terms) and under integer powers have their sign taken out, so
//!   that their first non-constant term has a positive coefficient: `(y - x)*z = -(x - y)*z`, `(-x - 1)^2 = (x + 1)^2`. Other numeric factors are
//!   not taken out of sums (that would need inexact divisions and print `3*(x + 0.3333333333333333)`), so
//!   `2*(x + 1)*y` and `(2*x + 2)*y` stay different forms of the same value; [`Expr::expand`] maps both to
//!   `2*x*y + 2*y`. Likewise, as a product is built pairwise, `(2*(x + 1))*y` is `(2*x + 2)*y`: the numeric
//!   coefficient was distributed before `y` arrived. Build products of several factors with [`Expr::product`] when
//!   the grouping should not matter;
//! - powers: `x^0 = 1`, `x^1 = x`, `1^x = 1`, constant powers folded, `(x^a)^n = x^(a*n)` and
//!   `(x*y)^n = x^n * y^n` for integer constants `n`; division is multiplication by a power `-1`;
//! - calls: all-constant arguments are folded, `sqrt(x)` becomes `x^0.5`, `min(x, x) = max(x, x) = x`,
//!   `abs(c*x) = |c|*abs(x)` and `sign(c*x) = sign(c)*sign(x)` for a constant `c ≠ 0`, `abs(abs(x)) = abs(x)`,
//!   `sign(sign(x)) = sign(x)`.
//!
//! # Domain caveat
//! These are the generic rules of computer algebra: the simplified form equals the original wherever the original
//! is finite, but it may be defined where the original is not. `x*0 = 0`, `x - x = 0` and `x/x = 1` hold for finite
//! non-zero `x` only: under IEEE arithmetic `NaN*0`, `inf - inf` and `0/0` are NaN. `x^0.5 * x^0.5 = x` holds for
//! `x ≥ 0` (the left side is NaN for `x < 0`). Callers that need to catch such points evaluate the original
//! expressions of the model, not only their simplified forms.
//!
//! A NaN constant absorbs a whole sum or product (`x + NaN = NaN`, `x * NaN = NaN`), as in IEEE arithmetic; this
//! also keeps the result independent of the order in which NaN, zeros and infinities are combined.

use super::eval::{apply_func, pow_f64};
use super::expr::{Expr, Node, Symbol};
use super::order::cmp_factors;
use crate::ir::Func;
use std::ops;

impl Expr {
    /// A numeric constant.
    pub fn constant(value: f64) -> Expr {
        Expr::from_canonical(Node::Const(value))
    }

    /// `0` (a small constant: interned once per process).
    pub fn zero() -> Expr {
        Expr::constant(0.0)
    }

    /// `1` (a small constant: interned once per process).
    pub fn one() -> Expr {
        Expr::constant(1.0)
    }

    /// A bare symbol.
    pub fn symbol(symbol: Symbol) -> Expr {
        Expr::from_canonical(Node::Sym(symbol))
    }

    /// The canonical sum of `terms` (0 when empty).
    pub fn sum(terms: impl IntoIterator<Item = Expr>) -> Expr {
        let mut constant = 0.0;
        let mut collected: Vec<(f64, Expr)> = Vec::new();
        for term in terms {
            collect_term(&term, &mut constant, &mut collected);
        }
        // Like terms (equal factors) made adjacent; stable, so their coefficients add in the order they came.
        collected.sort_by(|(_, a), (_, b)| {
            cmp_factors(a.coeff_and_factors().1, b.coeff_and_factors().1)
        });
        // Per distinct term: the sum of its coefficients, and the term itself while it met no like term (it is
        // `coeff * rest` already, so it needs no building).
        let mut merged: Vec<(f64, Expr, bool)> = Vec::with_capacity(collected.len());
        for (c, term) in collected {
            match merged.last_mut() {
                Some((sum, last, alone)) if same_factors(last, &term) => {
                    *sum += c;
                    *alone = false;
                }
                _ => merged.push((c, term, true)),
            }
        }
        if constant.is_nan() || merged.iter().any(|(c, _, _)| c.is_nan()) {
            return Expr::constant(f64::NAN);
        }
        let mut out: Vec<Expr> = Vec::with_capacity(merged.len() + 1);
        if constant != 0.0 {
            out.push(Expr::constant(constant));
        }
        for (coeff, term, alone) in merged {
            if coeff == 0.0 {
                continue;
            }
            out.push(if alone {
                term
            } else {
                scale_rest(rest_of(term.coeff_and_factors().1), coeff)
            });
        }
        // Sorted already: the constant comes first, and terms compare by their coefficient-free factors before
        // their coefficients, so the order of the distinct factor lists is the order of the terms.
        debug_assert!(out.is_sorted());
        match out.len() {
            0 => Expr::zero(),
            1 => out.pop().unwrap_or_else(Expr::zero),
            _ => Expr::from_canonical(Node::Add(out)),
        }
    }

    /// The canonical product of `factors` (1 when empty).
    pub fn product(factors: impl IntoIterator<Item = Expr>) -> Expr {
        let mut coeff = 1.0;
        let mut bases: Vec<(Expr, Expr)> = Vec::new();
        for f in factors {
            collect_factor(&f, &mut coeff, &mut bases);
        }
        if coeff == 0.0 || coeff.is_nan() {
            return Expr::constant(coeff);
        }
        let bases = merge_bases(bases);
        let mut out: Vec<Expr> = Vec::with_capacity(bases.len() + 1);
        let mut needs_another_pass = false;
        // Factors that are their bases (exponent 1) keep the order of the bases, which is sorted already.
        let mut reordered = false;
        for (base, exps) in bases {
            let f = base.pow(&exps.total());
            // `pow` can yield a constant (`x^0`), a product (`(x*y)^2`) or a power of another base
            // (`((y^1.5)^0.5)^2 = y^1.5`), which must be merged again.
            needs_another_pass |=
                matches!(f.node(), Node::Const(_) | Node::Mul(_)) || f.base_exp().0 != &base;
            reordered |= !f.same_node(&base);
            out.push(f);
        }
        if needs_another_pass {
            out.push(Expr::constant(coeff));
            return Expr::product(out);
        }
        if reordered {
            out.sort();
        }
        if coeff != 1.0 {
            if let [single] = out.as_slice()
                && let Node::Add(terms) = single.node()
                && terms.len() <= FLAT_SUM
            {
                return Expr::sum(terms.iter().map(|t| t * coeff));
            }
            out.insert(0, Expr::constant(coeff));
        }
        match out.len() {
            0 => Expr::constant(coeff),
            1 => out.pop().unwrap_or_else(Expr::one),
            _ => Expr::from_canonical(Node::Mul(out)),
        }
    }

    /// `self ^ exponent`.
    pub fn pow(&self, exponent: &Expr) -> Expr {
        let int_exp = exponent.as_const().filter(|e| e.fract() == 0.0);
        match (self.node(), exponent.as_const()) {
            (_, Some(0.0)) => Expr::one(),
            (_, Some(1.0)) => self.clone(),
            (Node::Const(b), Some(e)) => Expr::constant(pow_f64(*b, e)),
            (Node::Const(b), _) if *b == 1.0 => Expr::one(),
            (Node::Pow(b, a), _) if int_exp.is_some() => b.pow(&(a * exponent)),
            (Node::Mul(fs), _) if int_exp.is_some() => {
                Expr::product(fs.iter().map(|f| f.pow(exponent)))
            }
            (Node::Add(_), Some(n)) if int_exp.is_some() => match split_content(self) {
                Some((content, primitive)) => Expr::product([
                    Expr::constant(pow_f64(content, n)),
                    Expr::from_canonical(Node::Pow(primitive, exponent.clone())),
                ]),
                None => Expr::from_canonical(Node::Pow(self.clone(), exponent.clone())),
            },
            _ => Expr::from_canonical(Node::Pow(self.clone(), exponent.clone())),
        }
    }

    /// `self ^ n` for an integer `n`.
    pub fn powi(&self, n: i32) -> Expr {
        self.pow(&Expr::constant(f64::from(n)))
    }

    /// `1 / self`.
    pub fn recip(&self) -> Expr {
        self.powi(-1)
    }

    /// A function call, or `None` when `args.len()` is not the function's arity.
    pub fn call(func: Func, args: &[Expr]) -> Option<Expr> {
        match args {
            [x] if func.arity() == 1 => Some(call1(func, x)),
            [a, b] if func.arity() == 2 => Some(call2(func, a, b)),
            _ => None,
        }
    }

    pub fn sqrt(&self) -> Expr {
        self.pow(&Expr::constant(0.5))
    }

    pub fn atan2(y: &Expr, x: &Expr) -> Expr {
        call2(Func::Atan2, y, x)
    }

    pub fn min(a: &Expr, b: &Expr) -> Expr {
        call2(Func::Min, a, b)
    }

    pub fn max(a: &Expr, b: &Expr) -> Expr {
        call2(Func::Max, a, b)
    }
}

macro_rules! unary_funcs {
    ($($name:ident => $func:ident),* $(,)?) => {
        impl Expr {
            $(
                #[doc = concat!("`", stringify!($name), "(self)`.")]
                pub fn $name(&self) -> Expr {
                    call1(Func::$func, self)
                }
            )*
        }
    };
}

unary_funcs! {
    sin => Sin, cos => Cos, tan => Tan, asin => Asin, acos => Acos, atan => Atan, exp => Exp, ln => Ln,
    log10 => Log10, abs => Abs, sign => Sign, tanh => Tanh, sinh => Sinh, cosh => Cosh,
}

fn call1(func: Func, x: &Expr) -> Expr {
    if let Some(v) = x.as_const() {
        return Expr::constant(apply_func(func, &[v]));
    }
    let (coeff, rest) = x.coeff_and_factors();
    match (func, x.node()) {
        (Func::Sqrt, _) => x.sqrt(),
        (Func::Abs | Func::Sign, Node::Call(inner, _)) if *inner == func => x.clone(),
        (Func::Abs, Node::Mul(_)) if coeff != 1.0 => {
            coeff.abs() * Expr::product(rest.iter().cloned()).abs()
        }
        (Func::Sign, Node::Mul(_)) if coeff != 1.0 => {
            coeff.signum() * Expr::product(rest.iter().cloned()).sign()
        }
        _ => Expr::from_canonical(Node::Call(func, vec![x.clone()])),
    }
}

fn call2(func: Func, a: &Expr, b: &Expr) -> Expr {
    if let (Some(x), Some(y)) = (a.as_const(), b.as_const()) {
        return Expr::constant(apply_func(func, &[x, y]));
    }
    if matches!(func, Func::Min | Func::Max) && a == b {
        return a.clone();
    }
    Expr::from_canonical(Node::Call(func, vec![a.clone(), b.clone()]))
}

/// The factors of a product grouped by base: sorted by base, the exponents of equal bases kept in the order they
/// came (so that their sum is added in the order of the factors, as written).
fn merge_bases(mut bases: Vec<(Expr, Expr)>) -> Vec<(Expr, Exponents)> {
    // Stable: equal bases keep their order.
    bases.sort_by(|a, b| a.0.cmp(&b.0));
    let mut out: Vec<(Expr, Exponents)> = Vec::with_capacity(bases.len());
    for (base, exponent) in bases {
        match out.last_mut() {
            Some((last, exps)) if *last == base => exps.push(exponent),
            _ => out.push((base, Exponents::One(exponent))),
        }
    }
    out
}

/// The exponents of one base in a product: usually one, which needs no sum.
enum Exponents {
    One(Expr),
    Many(Vec<Expr>),
}

impl Exponents {
    fn push(&mut self, e: Expr) {
        match self {
            Exponents::One(first) => *self = Exponents::Many(vec![first.clone(), e]),
            Exponents::Many(es) => es.push(e),
        }
    }

    fn total(self) -> Expr {
        match self {
            Exponents::One(e) => e,
            Exponents::Many(es) => Expr::sum(es),
        }
    }
}

/// The most terms a sum may have and still be merged into a sum or product that holds it: a longer sum stays one
/// term of the outer sum (`a + S`), and a numeric coefficient stays a factor of it (`c*S`). Merging copies every
/// term, so a chain of sums each holding the next (the efforts along a chain of junctions, each multiplied by a
/// transformer's ratio) would cost the square of the chain's length; kept whole, each link costs at most this
/// many terms and the chain is shared.
pub(super) const FLAT_SUM: usize = 32;

/// Adds `term` (each of its terms, for a sum of at most [`FLAT_SUM`] terms) to a sum being collected: a constant to `constant`, any other term
/// with its numeric coefficient.
fn collect_term(term: &Expr, constant: &mut f64, collected: &mut Vec<(f64, Expr)>) {
    match term.node() {
        Node::Const(c) => *constant += c,
        Node::Add(terms) if terms.len() <= FLAT_SUM => {
            for t in terms {
                collect_term(t, constant, collected);
            }
        }
        _ => collected.push((term.coeff_and_factors().0, term.clone())),
    }
}

/// True when two terms have the same coefficient-free factors (interned, so the same nodes).
fn same_factors(a: &Expr, b: &Expr) -> bool {
    Expr::same_nodes(a.coeff_and_factors().1, b.coeff_and_factors().1)
}

/// `coeff * rest` where `rest` is a canonical coefficient-free term (a non-sum, possibly a product).
fn scale_rest(rest: Expr, coeff: f64) -> Expr {
    if coeff == 1.0 {
        return rest;
    }
    let mut factors = vec![Expr::constant(coeff)];
    match rest.node() {
        Node::Mul(fs) => factors.extend(fs.iter().cloned()),
        _ => factors.push(rest),
    }
    Expr::from_canonical(Node::Mul(factors))
}

fn collect_factor(f: &Expr, coeff: &mut f64, bases: &mut Vec<(Expr, Expr)>) {
    match f.node() {
        Node::Const(c) => *coeff *= c,
        Node::Mul(fs) => {
            for x in fs {
                collect_factor(x, coeff, bases);
            }
        }
        Node::Pow(b, e) => bases.push((b.clone(), e.clone())),
        // A long sum keeps its sign (it stays whole as a term of sums too, where it meets its multiples).
        Node::Add(terms) if terms.len() <= FLAT_SUM => match split_content(f) {
            Some((content, primitive)) => {
                *coeff *= content;
                bases.push((primitive, Expr::one()));
            }
            None => bases.push((f.clone(), Expr::one())),
        },
        _ => bases.push((f.clone(), Expr::one())),
    }
}

/// A sum whose first non-constant term has a negative coefficient, as `(-1, -sum)`: `-2*x + 4` → `(-1, 2*x - 4)`.
/// `None` for other sums.
fn split_content(sum: &Expr) -> Option<(f64, Expr)> {
    let Node::Add(terms) = sum.node() else {
        return None;
    };
    let leading = terms
        .iter()
        .find(|t| t.as_const().is_none())?
        .coeff_and_factors()
        .0;
    if leading >= 0.0 || leading.is_nan() {
        return None;
    }
    let negated = Expr::sum(terms.iter().map(|t| match t.as_const() {
        Some(c) => Expr::constant(-c),
        None => {
            let (c, rest) = t.coeff_and_factors();
            scale_rest(rest_of(rest), -c)
        }
    }));
    Some((-1.0, negated))
}

/// The coefficient-free term made of `factors`.
impl Expr {
    /// `-self` for a canonical product: its factors with the coefficient negated. This is what `-self` builds,
    /// without collecting the factors again (they are already distinct, sorted and not a lone sum).
    pub(super) fn negated_product(&self) -> Expr {
        match self.node() {
            Node::Mul(_) => {
                let (coeff, rest) = self.coeff_and_factors();
                scale_rest(rest_of(rest), -coeff)
            }
            _ => -self,
        }
    }
}

fn rest_of(factors: &[Expr]) -> Expr {
    match factors {
        [single] => single.clone(),
        _ => Expr::from_canonical(Node::Mul(factors.to_vec())),
    }
}

impl From<f64> for Expr {
    fn from(v: f64) -> Expr {
        Expr::constant(v)
    }
}

impl From<Symbol> for Expr {
    fn from(s: Symbol) -> Expr {
        Expr::symbol(s)
    }
}

impl From<&Symbol> for Expr {
    fn from(s: &Symbol) -> Expr {
        Expr::symbol(s.clone())
    }
}

fn sub2(a: &Expr, b: &Expr) -> Expr {
    Expr::sum([a.clone(), -b])
}

fn div2(a: &Expr, b: &Expr) -> Expr {
    Expr::product([a.clone(), b.recip()])
}

/// Implements a binary operator for every combination of `Expr`, `&Expr` and `f64` operands.
macro_rules! binary_op {
    ($trait:ident, $method:ident, $f:expr) => {
        impl ops::$trait<&Expr> for &Expr {
            type Output = Expr;
            fn $method(self, rhs: &Expr) -> Expr {
                $f(self, rhs)
            }
        }
        impl ops::$trait<Expr> for Expr {
            type Output = Expr;
            fn $method(self, rhs: Expr) -> Expr {
                $f(&self, &rhs)
            }
        }
        impl ops::$trait<&Expr> for Expr {
            type Output = Expr;
            fn $method(self, rhs: &Expr) -> Expr {
                $f(&self, rhs)
            }
        }
        impl ops::$trait<Expr> for &Expr {
            type Output = Expr;
            fn $method(self, rhs: Expr) -> Expr {
                $f(self, &rhs)
            }
        }
        impl ops::$trait<f64> for &Expr {
            type Output = Expr;
            fn $method(self, rhs: f64) -> Expr {
                $f(self, &Expr::constant(rhs))
            }
        }
        impl ops::$trait<f64> for Expr {
            type Output = Expr;
            fn $method(self, rhs: f64) -> Expr {
                $f(&self, &Expr::constant(rhs))
            }
        }
        impl ops::$trait<Expr> for f64 {
            type Output = Expr;
            fn $method(self, rhs: Expr) -> Expr {
                $f(&Expr::constant(self), &rhs)
            }
        }
        impl ops::$trait<&Expr> for f64 {
            type Output = Expr;
            fn $method(self, rhs: &Expr) -> Expr {
                $f(&Expr::constant(self), rhs)
            }
        }
    };
}

binary_op!(Add, add, |a: &Expr, b: &Expr| Expr::sum([
    a.clone(),
    b.clone()
]));
binary_op!(Sub, sub, sub2);
binary_op!(Mul, mul, |a: &Expr, b: &Expr| Expr::product([
    a.clone(),
    b.clone()
]));
binary_op!(Div, div, div2);

impl ops::Neg for &Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        Expr::product([Expr::constant(-1.0), self.clone()])
    }
}

impl ops::Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        -&self
    }
}
