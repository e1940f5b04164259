//! The rounding scale of an expression: what its evaluation is accurate relative to.

use super::dag::{Dag, Memo};
use super::expr::{Expr, Node};

impl Expr {
    /// `self` with every sum taken over the magnitudes of its terms and every product over the magnitudes of its
    /// factors (a positive integer power as the product it is): `|a|·(|b| + |c|)` for `a·(b + c)`. Other nodes
    /// (other powers, calls) are taken in magnitude as a whole.
    ///
    /// Its value bounds the partial results that are rounded when `self` is evaluated, so an evaluation is accurate
    /// to a few ε times it however much the terms cancel, inside a product as well as at the top (`a·(b + c)` with
    /// `b ≈ −c` is accurate to ε·|a|·(|b| + |c|), not to ε·|a·(b + c)|). One walk of the distinct nodes.
    pub fn magnitude(&self) -> Expr {
        let dag = Dag::new([self]);
        let mut memo: Memo<'_, '_, Expr> = Memo::new(&dag);
        for (i, e) in dag.order.iter().enumerate() {
            let of = |c: &Expr| memo.get(c).cloned().unwrap_or_else(|| c.abs());
            let out = match e.node() {
                Node::Add(terms) => Expr::sum(terms.iter().map(of)),
                Node::Mul(factors) => Expr::product(factors.iter().map(of)),
                Node::Pow(base, exponent) => match exponent.as_const() {
                    Some(n) if n >= 1.0 && n.fract() == 0.0 => of(base).pow(exponent),
                    _ => e.abs(),
                },
                _ => e.abs(),
            };
            memo.set(i, out);
        }
        memo.get(self).cloned().unwrap_or_else(|| self.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::Symbol;
    use std::collections::HashMap;

    fn value(e: &Expr, at: &[(&str, f64)]) -> f64 {
        let vars: HashMap<Symbol, f64> = at.iter().map(|&(n, v)| (Symbol::param(n), v)).collect();
        e.eval(|s: &Symbol| vars.get(s).copied())
            .unwrap_or(f64::NAN)
    }

    #[test]
    fn cancellation_inside_a_product_keeps_the_size_of_its_terms() {
        let [a, b, c] = ["a", "b", "c"].map(|n| Expr::symbol(Symbol::param(n)));
        let e = &a * (&b + &c) - 3.0 * (&b * &b);
        let at = [("a", -2.0), ("b", 1.0), ("c", -1.0 + 1e-9)];
        // |a|·(|b| + |c|) + 3·|b|²
        let want = 2.0 * (1.0 + 1.0 - 1e-9) + 3.0;
        assert!((value(&e.magnitude(), &at) - want).abs() < 1e-12);
        assert!(value(&e, &at).abs() < 3.0 + 1e-8);
        // (b + c)^2 as the square of its terms' magnitudes; a reciprocal and a call as they are.
        let sq = (&b + &c).powi(2);
        assert!((value(&sq.magnitude(), &at) - (2.0f64 - 1e-9).powi(2)).abs() < 1e-12);
        let rest = (&b + &c).recip() + (&b + &c).sin();
        let sum: f64 = 1.0 + (-1.0 + 1e-9);
        let want = 1.0 / sum + sum.sin();
        assert!((value(&rest.magnitude(), &at) - want).abs() < 1e-12 * want);
    }
}
