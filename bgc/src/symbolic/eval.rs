//! Numeric evaluation, free symbols and substitution, each a walk of the distinct nodes (see `dag.rs`).
//!
//! Evaluation follows IEEE arithmetic with the same formulas and operation order as the generated Rust (see
//! `print/rust.rs`): sums in print order, products as `(coefficient * numerator factors) / (denominator factors)`,
//! so a model evaluated here and the compiled model agree to the last bit. In particular:
//! - the elementary functions are those of the `libm` crate, which generated code calls too (rather than the
//!   platform's C library behind `f64::sin`, whose last bit may differ between platforms);
//! - `x^n` for an integer constant `n` is `bgc_powi` (binary powering), `x^0.5` is `libm::sqrt`, other powers
//!   `libm::pow`;
//! - `sign(x)` is 1 for `x > 0`, -1 for `x < 0`, 0 for `x = ±0` (unlike `f64::signum`, which gives 1 for +0) and NaN
//!   for NaN;
//! - `min`/`max` return NaN when either argument is NaN (IEEE 754-2019 `minimum`/`maximum`), unlike `f64::min`,
//!   which would hide a NaN produced upstream (and would let the simplified form of an expression differ from the
//!   original where the original's NaN was masked).
//!
//! `sign`, `min`, `max` and the integer power are the helpers generated code defines (`print/rust_helpers.rs`),
//! compiled here from the same file.
//!
//! NaN and infinities propagate as IEEE values; checking them is the caller's business.

use super::SymbolicError;
use super::dag::{Dag, Memo};
use super::expr::{Expr, Node, Symbol};
use super::intern::PassThroughState;
use super::print::sum_print_order;
use crate::ir::Func;
use std::collections::{BTreeMap, BTreeSet, HashSet};

// `bgc_sign`, `bgc_min`, `bgc_max`, `bgc_powi`: the very code generated modules define.
include!("print/rust_helpers.rs");

/// Applies `func` to numeric arguments. A missing argument reads as NaN (the constructors guarantee the arity).
pub(super) fn apply_func(func: Func, args: &[f64]) -> f64 {
    let a = args.first().copied().unwrap_or(f64::NAN);
    let b = args.get(1).copied().unwrap_or(f64::NAN);
    match func {
        Func::Sin => libm::sin(a),
        Func::Cos => libm::cos(a),
        Func::Tan => libm::tan(a),
        Func::Asin => libm::asin(a),
        Func::Acos => libm::acos(a),
        Func::Atan => libm::atan(a),
        Func::Atan2 => libm::atan2(a, b),
        Func::Exp => libm::exp(a),
        Func::Ln => libm::log(a),
        Func::Log10 => libm::log10(a),
        Func::Sqrt => libm::sqrt(a),
        Func::Abs => libm::fabs(a),
        Func::Sign => sign(a),
        Func::Min => min(a, b),
        Func::Max => max(a, b),
        Func::Tanh => libm::tanh(a),
        Func::Sinh => libm::sinh(a),
        Func::Cosh => libm::cosh(a),
    }
}

/// `sign` with `sign(±0) = 0` and `sign(NaN) = NaN`.
pub fn sign(x: f64) -> f64 {
    bgc_sign(x)
}

/// The smaller argument, NaN if either is NaN (unlike `f64::min`, which returns the other argument).
pub fn min(a: f64, b: f64) -> f64 {
    bgc_min(a, b)
}

/// The larger argument, NaN if either is NaN (unlike `f64::max`).
pub fn max(a: f64, b: f64) -> f64 {
    bgc_max(a, b)
}

/// `b^e` as the generated code computes it.
pub(super) fn pow_f64(b: f64, e: f64) -> f64 {
    match as_i32(e) {
        Some(n) => bgc_powi(b, n),
        None if e == 0.5 => libm::sqrt(b),
        None => libm::pow(b, e),
    }
}

/// `e` as an `i32` when it is an integer in range.
pub(super) fn as_i32(e: f64) -> Option<i32> {
    if e.fract() == 0.0 && e.abs() <= f64::from(i32::MAX) {
        // Exact: the value is an integer within i32's range.
        Some(e as i32)
    } else {
        None
    }
}

impl Expr {
    /// Evaluates with `env` giving each symbol's value; an unbound symbol is an error.
    pub fn eval<F: Fn(&Symbol) -> Option<f64>>(&self, env: F) -> Result<f64, SymbolicError> {
        self.eval_dyn(&env)
    }

    /// Evaluates with the values in `env`.
    pub fn eval_map(&self, env: &BTreeMap<Symbol, f64>) -> Result<f64, SymbolicError> {
        self.eval_dyn(&|s: &Symbol| env.get(s).copied())
    }

    /// Each distinct node once, children first; `env` is asked once per distinct symbol.
    fn eval_dyn(&self, env: &dyn Fn(&Symbol) -> Option<f64>) -> Result<f64, SymbolicError> {
        let dag = Dag::new([self]);
        let mut values: Vec<f64> = Vec::with_capacity(dag.len());
        for e in &dag.order {
            let value = {
                let val = |x: &Expr| {
                    dag.index(x)
                        .and_then(|i| values.get(i))
                        .copied()
                        .unwrap_or(f64::NAN)
                };
                match e.node() {
                    Node::Const(c) => *c,
                    Node::Sym(s) => env(s).ok_or_else(|| SymbolicError::UnboundSymbol {
                        name: s.name().to_string(),
                        kind: s.kind(),
                    })?,
                    // In the printers' order, so that generated code rounds the same way.
                    Node::Add(xs) => sum_print_order(xs)
                        .into_iter()
                        .fold(0.0, |acc, x| acc + val(x)),
                    Node::Mul(_) => fraction_value(e, &val),
                    Node::Pow(..) if e.negative_power().is_some() => fraction_value(e, &val),
                    Node::Pow(b, x) => pow_f64(val(b), val(x)),
                    Node::Call(f, xs) => {
                        let mut args = [f64::NAN; 2];
                        for (slot, x) in args.iter_mut().zip(xs) {
                            *slot = val(x);
                        }
                        apply_func(*f, &args[..xs.len().min(2)])
                    }
                }
            };
            values.push(value);
        }
        Ok(values.last().copied().unwrap_or(f64::NAN))
    }

    /// For each expression, the first constant in it that is not finite (children before parents, in their order):
    /// an `inf` or `NaN` folded from a part that reads no symbol, such as `1/(a − a)`. One walk of their distinct
    /// nodes together.
    pub fn non_finite_constants(exprs: &[Expr]) -> Vec<Option<f64>> {
        let dag = Dag::new(exprs);
        let mut held: Vec<Option<f64>> = vec![None; dag.len()];
        for (i, e) in dag.order.iter().enumerate() {
            let mut found = None;
            e.node().for_each_child(|c| {
                found = found.or_else(|| dag.index(c).and_then(|k| held[k]));
            });
            held[i] = found.or_else(|| e.as_const().filter(|v| !v.is_finite()));
        }
        exprs
            .iter()
            .map(|e| dag.index(e).and_then(|k| held[k]))
            .collect()
    }

    /// The symbols the expression depends on, in [`Symbol`] order.
    pub fn free_symbols(&self) -> BTreeSet<Symbol> {
        Dag::new([self])
            .order
            .into_iter()
            .filter_map(Expr::as_symbol)
            .cloned()
            .collect()
    }

    /// The symbols read inside the calls of `funcs` (`min`, `max`, ...), with the first such call met that reads
    /// any: one walk of the distinct nodes, and one more of each such call. `None` when no such call reads a
    /// symbol.
    pub fn symbols_under_calls(&self, funcs: &[Func]) -> Option<(Func, BTreeSet<Symbol>)> {
        let mut found: Option<(Func, BTreeSet<Symbol>)> = None;
        for e in Dag::new([self]).order {
            if let Node::Call(f, _) = e.node()
                && funcs.contains(f)
            {
                let read = e.free_symbols();
                match &mut found {
                    Some((_, all)) => all.extend(read),
                    None if !read.is_empty() => found = Some((*f, read)),
                    None => {}
                }
            }
        }
        found
    }

    /// Whether `symbol` occurs in the expression.
    pub fn depends_on(&self, symbol: &Symbol) -> bool {
        self.depends_on_any(std::slice::from_ref(symbol))
    }

    /// Whether any of `symbols` occurs in the expression: a walk of the distinct nodes that stops at the first.
    pub fn depends_on_any(&self, symbols: &[Symbol]) -> bool {
        let mut seen: HashSet<usize, PassThroughState> = HashSet::default();
        let mut pending = vec![self];
        while let Some(e) = pending.pop() {
            if !seen.insert(e.address()) {
                continue;
            }
            if let Some(s) = e.as_symbol()
                && symbols.contains(s)
            {
                return true;
            }
            e.node().for_each_child(|c| pending.push(c));
        }
        false
    }

    /// Replaces every symbol in `map` by its expression, all at once (a replacement is not substituted again), and
    /// simplifies the result.
    pub fn substitute(&self, map: &BTreeMap<Symbol, Expr>) -> Expr {
        self.substitute_with(&|s: &Symbol| map.get(s).cloned())
    }

    /// Replaces each symbol for which `f` returns an expression, all at once, and simplifies the result. Each
    /// distinct node is rebuilt once; a node none of whose symbols is replaced is kept as it is.
    pub fn substitute_with(&self, f: &dyn Fn(&Symbol) -> Option<Expr>) -> Expr {
        Expr::substitute_all(std::slice::from_ref(self), f)
            .pop()
            .unwrap_or_else(|| self.clone())
    }

    /// [`Expr::substitute_with`] of several expressions at once: each distinct node of all of them is rebuilt
    /// once, so expressions that share a large subexpression (the power of each of 30,000 sources holding their
    /// common flow) cost its size once, not once each.
    pub fn substitute_all(exprs: &[Expr], f: &dyn Fn(&Symbol) -> Option<Expr>) -> Vec<Expr> {
        let dag = Dag::new(exprs);
        let mut memo = Memo::new(&dag);
        for (i, e) in dag.order.iter().enumerate() {
            let out = match e.node() {
                Node::Const(_) => (*e).clone(),
                Node::Sym(s) => f(s).unwrap_or_else(|| (*e).clone()),
                _ => e.map_children(&|c| memo.get(c).cloned().unwrap_or_else(|| c.clone())),
            };
            memo.set(i, out);
        }
        exprs
            .iter()
            .map(|e| memo.get(e).cloned().unwrap_or_else(|| e.clone()))
            .collect()
    }

    /// For each expression, whether a symbol of it satisfies `pred`: one walk of the distinct nodes of all.
    pub fn each_depends_on(exprs: &[Expr], pred: &dyn Fn(&Symbol) -> bool) -> Vec<bool> {
        let dag = Dag::new(exprs);
        let reads = dag.reading(pred);
        exprs
            .iter()
            .map(|e| dag.index(e).is_some_and(|i| reads[i]))
            .collect()
    }

    /// Rebuilds the node from its children transformed by `f`, simplifying; the node itself when `f` changes no
    /// child (canonical form is rebuilt unchanged, so this only saves the work).
    pub(super) fn map_children(&self, f: &dyn Fn(&Expr) -> Expr) -> Expr {
        let mut changed = false;
        let mut g = |c: &Expr| {
            let out = f(c);
            changed |= out != *c;
            out
        };
        let rebuilt = match self.node() {
            Node::Const(_) | Node::Sym(_) => return self.clone(),
            Node::Add(xs) => {
                let terms: Vec<Expr> = xs.iter().map(&mut g).collect();
                changed.then(|| Expr::sum(terms))
            }
            Node::Mul(xs) => {
                let factors: Vec<Expr> = xs.iter().map(&mut g).collect();
                changed.then(|| Expr::product(factors))
            }
            Node::Pow(b, e) => {
                let (b, e) = (g(b), g(e));
                changed.then(|| b.pow(&e))
            }
            Node::Call(func, xs) => {
                let args: Vec<Expr> = xs.iter().map(&mut g).collect();
                // The arity is that of the original call, so `call` cannot refuse it.
                changed.then(|| Expr::call(*func, &args).unwrap_or_else(|| self.clone()))
            }
        };
        rebuilt.unwrap_or_else(|| self.clone())
    }
}

/// A product (or a power with a negative exponent) as the printers lay it out: `(coeff * num...) / (den...)`.
fn fraction_value(e: &Expr, val: &dyn Fn(&Expr) -> f64) -> f64 {
    let (coeff, factors) = match e.node() {
        Node::Mul(_) => e.coeff_and_factors(),
        _ => (1.0, std::slice::from_ref(e)),
    };
    let mut num = coeff;
    let mut den = 1.0;
    for f in factors {
        match f.negative_power() {
            Some((b, x)) => den *= pow_f64(val(b), -val(x)),
            None => num *= val(f),
        }
    }
    num / den
}
