//! Numeric evaluation, free symbols and substitution.
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
use super::expr::{Expr, Node, Symbol};
use super::print::sum_print_order;
use crate::ir::Func;
use std::collections::{BTreeMap, BTreeSet};

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

    fn eval_dyn(&self, env: &dyn Fn(&Symbol) -> Option<f64>) -> Result<f64, SymbolicError> {
        Ok(match self.node() {
            Node::Const(c) => *c,
            Node::Sym(s) => env(s).ok_or_else(|| SymbolicError::UnboundSymbol {
                name: s.name().to_string(),
                kind: s.kind(),
            })?,
            Node::Add(xs) => {
                // In the printers' order, so that generated code rounds the same way.
                let mut acc = 0.0;
                for x in sum_print_order(xs) {
                    acc += x.eval_dyn(env)?;
                }
                acc
            }
            Node::Mul(_) => self.eval_fraction(env)?,
            Node::Pow(..) if self.negative_power().is_some() => self.eval_fraction(env)?,
            Node::Pow(b, e) => pow_f64(b.eval_dyn(env)?, e.eval_dyn(env)?),
            Node::Call(f, xs) => {
                let mut args = [f64::NAN; 2];
                for (slot, x) in args.iter_mut().zip(xs) {
                    *slot = x.eval_dyn(env)?;
                }
                apply_func(*f, &args[..xs.len().min(2)])
            }
        })
    }

    /// A product (or a power with a negative exponent) as the printers lay it out: `(coeff * num...) / (den...)`.
    fn eval_fraction(&self, env: &dyn Fn(&Symbol) -> Option<f64>) -> Result<f64, SymbolicError> {
        let (coeff, factors) = match self.node() {
            Node::Mul(_) => self.coeff_and_factors(),
            _ => (1.0, std::slice::from_ref(self)),
        };
        let mut num = coeff;
        let mut den = 1.0;
        for f in factors {
            match f.negative_power() {
                Some((b, e)) => den *= pow_f64(b.eval_dyn(env)?, -e.eval_dyn(env)?),
                None => num *= f.eval_dyn(env)?,
            }
        }
        Ok(num / den)
    }

    /// The symbols the expression depends on, in [`Symbol`] order.
    pub fn free_symbols(&self) -> BTreeSet<Symbol> {
        let mut out = BTreeSet::new();
        self.collect_symbols(&mut out);
        out
    }

    fn collect_symbols(&self, out: &mut BTreeSet<Symbol>) {
        match self.node() {
            Node::Const(_) => {}
            Node::Sym(s) => {
                out.insert(s.clone());
            }
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => {
                xs.iter().for_each(|x| x.collect_symbols(out));
            }
            Node::Pow(b, e) => {
                b.collect_symbols(out);
                e.collect_symbols(out);
            }
        }
    }

    /// Whether `symbol` occurs in the expression.
    pub fn depends_on(&self, symbol: &Symbol) -> bool {
        self.depends_on_any(std::slice::from_ref(symbol))
    }

    /// Whether any of `symbols` occurs in the expression.
    pub fn depends_on_any(&self, symbols: &[Symbol]) -> bool {
        match self.node() {
            Node::Const(_) => false,
            Node::Sym(s) => symbols.contains(s),
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => {
                xs.iter().any(|x| x.depends_on_any(symbols))
            }
            Node::Pow(b, e) => b.depends_on_any(symbols) || e.depends_on_any(symbols),
        }
    }

    /// Replaces every symbol in `map` by its expression, all at once (a replacement is not substituted again), and
    /// simplifies the result.
    pub fn substitute(&self, map: &BTreeMap<Symbol, Expr>) -> Expr {
        self.substitute_with(&|s: &Symbol| map.get(s).cloned())
    }

    /// Replaces each symbol for which `f` returns an expression, all at once, and simplifies the result.
    pub fn substitute_with(&self, f: &dyn Fn(&Symbol) -> Option<Expr>) -> Expr {
        match self.node() {
            Node::Const(_) => self.clone(),
            Node::Sym(s) => f(s).unwrap_or_else(|| self.clone()),
            _ => self.map_children(&|c| c.substitute_with(f)),
        }
    }

    /// Rebuilds the node from its children transformed by `f`, simplifying.
    pub(super) fn map_children(&self, f: &dyn Fn(&Expr) -> Expr) -> Expr {
        match self.node() {
            Node::Const(_) | Node::Sym(_) => self.clone(),
            Node::Add(xs) => Expr::sum(xs.iter().map(f)),
            Node::Mul(xs) => Expr::product(xs.iter().map(f)),
            Node::Pow(b, e) => f(b).pow(&f(e)),
            Node::Call(func, xs) => {
                let args: Vec<Expr> = xs.iter().map(f).collect();
                // The arity is that of the original call, so `call` cannot refuse it.
                Expr::call(*func, &args).unwrap_or_else(|| self.clone())
            }
        }
    }
}
