//! The rounding scale of an expression: what its evaluation is accurate relative to.

use super::dag::{Dag, Memo};
use super::expr::{Expr, Node};

impl Expr {
    /// A bound on the rounding error of evaluating `self`, in units of the unit roundoff: what its evaluation is
    /// accurate relative to however much its terms cancel. First-order propagation over the distinct nodes:
    ///
    /// - a sum: the sum of its terms' bounds, `m(a + b) = m(a) + m(b)`;
    /// - a product: each factor's bound times the other factors' magnitudes, `m(a·b) = m(a)·|b| + |a|·m(b)` (a
    ///   constant factor is exact: `m(3·a) = 3·m(a)`);
    /// - a positive integer power: `m(bⁿ) = n·|b|ⁿ⁻¹·m(b)`;
    /// - anything else (a leaf, another power, a call) its magnitude as a whole, `|e|`.
    ///
    /// So `a·(b + c)` with `b ≈ −c` is accurate to ε·|a|·(|b| + |c|), not to ε·|a·(b + c)|, while a cancelling sum
    /// that is cubed counts its error once, `3·|s|²·m(s)`, not as `m(s)³`: raising every bound of a factor to the
    /// power (or multiplying the bounds of two cancelling factors) overstated the error by orders of magnitude, and
    /// a loop's Newton iteration then stopped at a residual that was not zero. One walk of the distinct nodes.
    pub fn magnitude(&self) -> Expr {
        let dag = Dag::new([self]);
        let mut memo: Memo<'_, '_, Expr> = Memo::new(&dag);
        for (i, e) in dag.order.iter().enumerate() {
            let of = |c: &Expr| memo.get(c).cloned().unwrap_or_else(|| c.abs());
            let out = match e.node() {
                Node::Add(terms) => Expr::sum(terms.iter().map(of)),
                // A constant factor is exact: only the others carry errors (and the rounding of the product is
                // within each of their terms, as a bound is at least its value).
                Node::Mul(factors) => Expr::sum(
                    (0..factors.len())
                        .filter(|&k| factors[k].as_const().is_none())
                        .map(|k| {
                            let others = factors
                                .iter()
                                .enumerate()
                                .filter(|&(j, _)| j != k)
                                .map(|(_, f)| f.abs());
                            Expr::product(std::iter::once(of(&factors[k])).chain(others))
                        }),
                ),
                Node::Pow(base, exponent) => match exponent.as_const() {
                    Some(n) if n >= 1.0 && n.fract() == 0.0 => Expr::product([
                        Expr::constant(n),
                        base.abs().pow(&Expr::constant(n - 1.0)),
                        of(base),
                    ]),
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
        // m(a)·|b + c| + |a|·(|b| + |c|) + 3·(2·|b|·|b|)
        let sum: f64 = 1.0 + (-1.0 + 1e-9);
        let want = 2.0 * sum.abs() + 2.0 * (1.0 + 1.0 - 1e-9) + 6.0;
        assert!((value(&e.magnitude(), &at) - want).abs() < 1e-12);
        assert!(value(&e, &at).abs() < 3.0 + 1e-8);
        // (b + c)^2 counts the sum's error once: 2·|b + c|·(|b| + |c|); a reciprocal and a call as they are.
        let sq = (&b + &c).powi(2);
        let want = 2.0 * sum.abs() * (2.0 - 1e-9);
        assert!((value(&sq.magnitude(), &at) - want).abs() < 1e-12 * want);
        let rest = (&b + &c).recip() + (&b + &c).sin();
        let want = 1.0 / sum + sum.sin();
        assert!((value(&rest.magnitude(), &at) - want).abs() < 1e-12 * want);
    }

    /// A cancelling sum cubed: its error is counted once, `3·|s|²·m(s)` (1.47 here), not as `m(s)³` (1.0e6),
    /// which made a loop's Newton iteration stop with a residual of 0.03 (tests/equations_differential_nonlinear).
    #[test]
    fn a_power_of_a_cancelling_sum_counts_its_error_once() {
        let [a, b] = ["a", "b"].map(|n| Expr::symbol(Symbol::param(n)));
        let s = &a - &b;
        let cube = s.powi(3);
        let at = [("a", 50.07), ("b", 50.0)];
        let d: f64 = 50.07 - 50.0;
        let want = 3.0 * d * d * 100.07;
        let got = value(&cube.magnitude(), &at);
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        assert!(got < 2.0, "{got}");
    }
}
