//! Evaluation of constant expressions: parameter defaults, overrides and element values with the parameters at
//! their defaults. Anything that is not a constant (a state, an input, `t`) makes the value unknown (`None`).

use crate::ir::{Expr, Func, Param};
use crate::syntax::ast::BinOp;

/// The value of `e` with every parameter at its default, or `None` when `e` depends on something else.
pub(crate) fn eval(e: &Expr, params: &[Param]) -> Option<f64> {
    Some(match e {
        Expr::Const(v) => *v,
        Expr::Param(id) => params.get(*id)?.default,
        Expr::Neg(a) => -eval(a, params)?,
        Expr::Binary(op, a, b) => {
            let (a, b) = (eval(a, params)?, eval(b, params)?);
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => a.powf(b),
            }
        }
        Expr::Call(f, args) => {
            let a = eval(args.first()?, params)?;
            let b = || args.get(1).and_then(|x| eval(x, params));
            match f {
                Func::Sin => a.sin(),
                Func::Cos => a.cos(),
                Func::Tan => a.tan(),
                Func::Asin => a.asin(),
                Func::Acos => a.acos(),
                Func::Atan => a.atan(),
                Func::Atan2 => a.atan2(b()?),
                Func::Exp => a.exp(),
                Func::Ln => a.ln(),
                Func::Log10 => a.log10(),
                Func::Sqrt => a.sqrt(),
                Func::Abs => a.abs(),
                // sign(0) = 0, as in the equations stage.
                Func::Sign => {
                    if a > 0.0 {
                        1.0
                    } else if a < 0.0 {
                        -1.0
                    } else {
                        0.0
                    }
                }
                Func::Min => a.min(b()?),
                Func::Max => a.max(b()?),
                Func::Tanh => a.tanh(),
                Func::Sinh => a.sinh(),
                Func::Cosh => a.cosh(),
            }
        }
        _ => return None,
    })
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
