//! Expressions compiled for evaluation at many points: the Jacobians of a model evaluated at every step of an
//! integration.
//!
//! [`Expr::eval`] walks the expression's nodes and works out the printed order of each sum as it goes, which
//! builds expressions; [`Compiled`] does that walk once, for several expressions together (what they share is
//! computed once per point), and keeps a flat list of operations on the values of earlier ones. The operations and
//! their order are those of [`Expr::eval`] (sums in print order, products as `coefficient · numerator /
//! denominator`, the same powers and `libm` functions), so each value is the one `eval` gives, to the bit.

use super::dag::Dag;
use super::eval::{apply_func, pow_f64};
use super::expr::{Expr, Node, Symbol};
use super::print::sum_print_order;
use crate::ir::Func;

/// One operation; operands are indices of earlier operations.
#[derive(Clone, Debug)]
enum Op {
    Const(f64),
    /// The value of `symbols[k]`.
    Sym(usize),
    /// A sum, its terms in print order.
    Sum(Vec<usize>),
    /// `coeff · Π num / Π pow(base, −exponent)`.
    Fraction {
        coeff: f64,
        num: Vec<usize>,
        den: Vec<(usize, usize)>,
    },
    Pow(usize, usize),
    Call(Func, Vec<usize>),
}

/// Expressions ready to be evaluated at many points.
#[derive(Clone, Debug)]
pub struct Compiled {
    /// The symbols the expressions read, in the order [`Compiled::eval`] takes their values.
    symbols: Vec<Symbol>,
    ops: Vec<Op>,
    /// The operation that gives each expression.
    roots: Vec<usize>,
}

impl Compiled {
    /// `exprs` compiled.
    pub fn new(exprs: &[Expr]) -> Compiled {
        let dag = Dag::new(exprs);
        // Operation 0 is NaN, the value of an operand the walk did not reach (it always reaches them all).
        let slot = |e: &Expr| dag.index(e).map_or(0, |i| i + 1);
        let mut symbols: Vec<Symbol> = Vec::new();
        let mut ops = Vec::with_capacity(dag.len() + 1);
        ops.push(Op::Const(f64::NAN));
        for e in &dag.order {
            let op = match e.node() {
                Node::Const(c) => Op::Const(*c),
                Node::Sym(s) => match symbols.iter().position(|k| k == s) {
                    Some(k) => Op::Sym(k),
                    None => {
                        symbols.push(s.clone());
                        Op::Sym(symbols.len() - 1)
                    }
                },
                Node::Add(xs) => Op::Sum(sum_print_order(xs).into_iter().map(slot).collect()),
                Node::Mul(_) => fraction(e, &slot),
                Node::Pow(..) if e.negative_power().is_some() => fraction(e, &slot),
                Node::Pow(b, x) => Op::Pow(slot(b), slot(x)),
                Node::Call(f, xs) => Op::Call(*f, xs.iter().map(slot).collect()),
            };
            ops.push(op);
        }
        Compiled {
            symbols,
            roots: exprs.iter().map(slot).collect(),
            ops,
        }
    }

    /// The symbols whose values [`Compiled::eval`] takes, in that order.
    pub fn symbols(&self) -> &[Symbol] {
        &self.symbols
    }

    /// The value of each expression, given the values of [`Compiled::symbols`] (a missing one reads as NaN).
    pub fn eval(&self, symbol_values: &[f64]) -> Vec<f64> {
        let mut v: Vec<f64> = Vec::with_capacity(self.ops.len());
        for op in &self.ops {
            let at = |i: usize| v.get(i).copied().unwrap_or(f64::NAN);
            let value = match op {
                Op::Const(c) => *c,
                Op::Sym(k) => symbol_values.get(*k).copied().unwrap_or(f64::NAN),
                Op::Sum(terms) => terms.iter().fold(0.0, |acc, &i| acc + at(i)),
                Op::Fraction { coeff, num, den } => {
                    let n = num.iter().fold(*coeff, |acc, &i| acc * at(i));
                    let d = den
                        .iter()
                        .fold(1.0, |acc, &(b, x)| acc * pow_f64(at(b), -at(x)));
                    n / d
                }
                Op::Pow(b, x) => pow_f64(at(*b), at(*x)),
                Op::Call(f, args) => {
                    let mut a = [f64::NAN; 2];
                    for (slot, &i) in a.iter_mut().zip(args) {
                        *slot = at(i);
                    }
                    apply_func(*f, &a[..args.len().min(2)])
                }
            };
            v.push(value);
        }
        self.roots
            .iter()
            .map(|&r| v.get(r).copied().unwrap_or(f64::NAN))
            .collect()
    }
}

/// A product (or a power with a negative exponent) as the evaluator computes it: the coefficient times the
/// numerator factors, divided by the denominator's powers.
fn fraction(e: &Expr, slot: &dyn Fn(&Expr) -> usize) -> Op {
    let (coeff, factors) = match e.node() {
        Node::Mul(_) => e.coeff_and_factors(),
        _ => (1.0, std::slice::from_ref(e)),
    };
    let mut num = Vec::new();
    let mut den = Vec::new();
    for f in factors {
        match f.negative_power() {
            Some((b, x)) => den.push((slot(b), slot(x))),
            None => num.push(slot(f)),
        }
    }
    Op::Fraction { coeff, num, den }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compiled_values_are_those_of_eval_to_the_bit() {
        let (x, y) = (Symbol::state("x"), Symbol::param("y"));
        let (ex, ey) = (Expr::symbol(x.clone()), Expr::symbol(y.clone()));
        let exprs = vec![
            &ex * &ey / (ex.powi(2) + 3.0) - ey.sin(),
            (ex.clone() - &ey).exp() * 0.1 + ey.sqrt() - 1.0 / &ey,
            Expr::constant(2.5),
            Expr::atan2(&ey, &ex).pow(&ex),
        ];
        let compiled = Compiled::new(&exprs);
        for (xv, yv) in [(0.3, 1.7), (-2.0, 0.01), (5.0, 3.0)] {
            let values: Vec<f64> = compiled
                .symbols()
                .iter()
                .map(|s| if *s == x { xv } else { yv })
                .collect();
            let got = compiled.eval(&values);
            for (e, g) in exprs.iter().zip(got) {
                let want = e
                    .eval(|s| Some(if *s == x { xv } else { yv }))
                    .unwrap_or(f64::NAN);
                assert_eq!(g.to_bits(), want.to_bits(), "{e}: {g} against {want}");
            }
        }
    }
}
