//! Symbolic differentiation.
//!
//! Rules, with `u' = du/dx`:
//! - sums term by term; products by the product rule `Σᵢ fᵢ' Πⱼ≠ᵢ fⱼ`;
//! - `(b^e)' = e b^(e-1) b'` when `e` does not depend on `x`, else `b^e (e' ln b + e b'/b)`;
//! - `sin' = cos`, `cos' = -sin`, `tan' = 1/cos²`, `asin' = 1/sqrt(1-u²)`, `acos' = -1/sqrt(1-u²)`,
//!   `atan' = 1/(1+u²)`, `atan2(y, x)' = (x y' - y x')/(x² + y²)`, `exp' = exp`, `ln' = 1/u`,
//!   `log10' = 1/(u ln 10)`, `tanh' = 1 - tanh²`, `sinh' = cosh`, `cosh' = sinh`;
//! - `abs(u)' = sign(u) u'` (at `u = 0` this gives 0, a subgradient);
//! - `sign(u)' = 0`: exact away from `u = 0`, where the true derivative does not exist;
//! - `min(a, b)' = (1 - s)/2 a' + (1 + s)/2 b'` and `max(a, b)' = (1 + s)/2 a' + (1 - s)/2 b'` with
//!   `s = sign(a - b)`: the derivative of the active argument, and the mean of both where `a = b`.

use super::expr::{Expr, Node, Symbol};
use crate::ir::Func;
use std::f64::consts::LN_10;

impl Expr {
    /// `d self / d x`, simplified.
    pub fn diff(&self, x: &Symbol) -> Expr {
        if !self.depends_on(x) {
            return Expr::zero();
        }
        match self.node() {
            Node::Const(_) => Expr::zero(),
            Node::Sym(s) => Expr::constant(if s == x { 1.0 } else { 0.0 }),
            Node::Add(terms) => Expr::sum(terms.iter().map(|t| t.diff(x))),
            Node::Mul(factors) => Expr::sum((0..factors.len()).map(|i| {
                Expr::product(
                    factors.iter().enumerate().map(
                        |(j, f)| {
                            if i == j { f.diff(x) } else { f.clone() }
                        },
                    ),
                )
            })),
            Node::Pow(b, e) => {
                if e.depends_on(x) {
                    self * (e.diff(x) * b.ln() + e * b.diff(x) / b)
                } else {
                    e * b.pow(&(e - 1.0)) * b.diff(x)
                }
            }
            Node::Call(func, args) => diff_call(*func, args, x),
        }
    }

    /// The Jacobian `∂ exprsᵢ / ∂ varsⱼ`, row by row.
    pub fn jacobian(exprs: &[Expr], vars: &[Symbol]) -> Vec<Vec<Expr>> {
        exprs
            .iter()
            .map(|e| vars.iter().map(|v| e.diff(v)).collect())
            .collect()
    }
}

fn diff_call(func: Func, args: &[Expr], x: &Symbol) -> Expr {
    let zero = Expr::zero();
    let u = args.first().unwrap_or(&zero);
    let v = args.get(1).unwrap_or(&zero);
    let du = u.diff(x);
    match func {
        Func::Sin => u.cos() * du,
        Func::Cos => -(u.sin() * du),
        Func::Tan => du * u.cos().powi(-2),
        Func::Asin => du * (1.0 - u.powi(2)).pow(&Expr::constant(-0.5)),
        Func::Acos => -(du * (1.0 - u.powi(2)).pow(&Expr::constant(-0.5))),
        Func::Atan => du / (1.0 + u.powi(2)),
        Func::Atan2 => (v * du - u * v.diff(x)) / (u.powi(2) + v.powi(2)),
        Func::Exp => u.exp() * du,
        Func::Ln => du / u,
        Func::Log10 => du / (u * LN_10),
        Func::Sqrt => du * 0.5 * u.pow(&Expr::constant(-0.5)),
        Func::Abs => u.sign() * du,
        Func::Sign => Expr::zero(),
        Func::Min | Func::Max => {
            let s = (u - v).sign();
            let (wu, wv) = if func == Func::Min {
                ((1.0 - &s) * 0.5, (1.0 + &s) * 0.5)
            } else {
                ((1.0 + &s) * 0.5, (1.0 - &s) * 0.5)
            };
            wu * du + wv * v.diff(x)
        }
        Func::Tanh => du * (1.0 - u.tanh().powi(2)),
        Func::Sinh => u.cosh() * du,
        Func::Cosh => u.sinh() * du,
    }
}
