//! Evaluation of constant expressions: parameter defaults, overrides and element values with the parameters at
//! their defaults. Anything that is not a constant (a state, an input, `t`) makes the value unknown (`None`).

use crate::ir::{Expr, Param};
use crate::syntax::ast::BinOp;

/// The value of `e` with every parameter at its default, or `None` when `e` depends on something else.
pub(crate) fn eval(e: &Expr, params: &[Param]) -> Option<f64> {
    e.eval_const(&|id| params.get(id).map(|p| p.default))
}

/// True when `e` is made of numbers and functions only (no parameter, input or state).
pub(crate) fn is_literal(e: &Expr) -> bool {
    match e {
        Expr::Const(_) => true,
        Expr::Neg(a) => is_literal(a),
        Expr::Binary(_, a, b) => is_literal(a) && is_literal(b),
        Expr::Call(_, args) => args.iter().all(is_literal),
        _ => false,
    }
}

/// The parameters `e` uses, in order of first use.
pub(crate) fn params_of(e: &Expr, out: &mut Vec<usize>) {
    match e {
        Expr::Param(id) if !out.contains(id) => out.push(*id),
        Expr::Neg(a) => params_of(a, out),
        Expr::Binary(_, a, b) => {
            params_of(a, out);
            params_of(b, out);
        }
        Expr::Call(_, args) => args.iter().for_each(|a| params_of(a, out)),
        _ => {}
    }
}

/// Why the top node of `e` has no finite value whatever the parameters, as a label: a division by a literal zero
/// (`d*f/0`), or a part made of numbers only that is infinite or NaN while its operands are finite (`1/0`, `ln(0)`,
/// `sqrt(-1)`, `1e300*1e300`). Only the top node is looked at, so each such part is reported once, where it is.
pub(crate) fn not_finite(e: &Expr) -> Option<String> {
    let literal = |x: &Expr| {
        if is_literal(x) {
            x.eval_const(&|_| None)
        } else {
            None
        }
    };
    let operands: Vec<&Expr> = match e {
        Expr::Binary(BinOp::Div, _, b) if literal(b) == Some(0.0) => {
            return Some("this divides by zero".into());
        }
        Expr::Binary(_, a, b) => vec![a, b],
        Expr::Call(_, args) => args.iter().collect(),
        _ => return None,
    };
    let finite = operands
        .into_iter()
        .all(|x| literal(x).is_some_and(f64::is_finite));
    let v = literal(e)?;
    (finite && !v.is_finite()).then(|| format!("this is {v}"))
}
