//! Conversion of the IR's resolved expressions into symbolic ones.
//!
//! Operators and calls translate directly (`a - b` → `a + (-1)*b`, `a / b` → `a * b^-1`); every leaf other than a
//! constant (time, parameters, inputs, outputs, vars, efforts, flows, momenta, displacements, field ports) is
//! handed to the caller's closure, which decides what it stands for (a symbol, or an expression already derived).

use super::SymbolicError;
use super::expr::Expr;
use crate::ir;
use crate::syntax::ast::BinOp;

/// Converts `e`, mapping each non-constant leaf through `leaf`; a leaf it returns `None` for is an error.
pub fn from_ir(
    e: &ir::Expr,
    leaf: &dyn Fn(&ir::Expr) -> Option<Expr>,
) -> Result<Expr, SymbolicError> {
    Ok(match e {
        ir::Expr::Const(c) => Expr::constant(*c),
        ir::Expr::Neg(x) => -from_ir(x, leaf)?,
        ir::Expr::Binary(op, a, b) => {
            let a = from_ir(a, leaf)?;
            let b = from_ir(b, leaf)?;
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => a.pow(&b),
            }
        }
        ir::Expr::Call(func, args) => {
            let args = args
                .iter()
                .map(|a| from_ir(a, leaf))
                .collect::<Result<Vec<_>, _>>()?;
            Expr::call(*func, &args).ok_or(SymbolicError::Arity {
                func: func.name(),
                expected: func.arity(),
                found: args.len(),
            })?
        }
        ir::Expr::Time
        | ir::Expr::Param(_)
        | ir::Expr::Input(_)
        | ir::Expr::Output(_)
        | ir::Expr::Var(_)
        | ir::Expr::Effort(_)
        | ir::Expr::Flow(_)
        | ir::Expr::Momentum(_)
        | ir::Expr::Displacement(_)
        | ir::Expr::FieldPort { .. } => leaf(e).ok_or_else(|| SymbolicError::UnmappedLeaf {
            leaf: format!("{e:?}"),
        })?,
    })
}
