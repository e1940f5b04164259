//! Evaluation of constant expressions: parameter defaults, overrides and element values with the parameters at
//! their defaults. Anything that is not a constant (a state, an input, `t`) makes the value unknown (`None`).

use crate::ir::{Expr, Param};

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
