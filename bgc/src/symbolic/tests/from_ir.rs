//! Conversion from the IR's expressions.

use super::super::{Expr, Symbol, SymbolicError, from_ir};
use super::{c, p};
use crate::ir::{self, Func};
use crate::syntax::ast::BinOp;

fn bin(op: BinOp, a: ir::Expr, b: ir::Expr) -> ir::Expr {
    ir::Expr::Binary(op, Box::new(a), Box::new(b))
}

#[test]
fn operators_calls_and_leaves_convert() {
    // e = b0*sign(f) + b2*f - k/m^2 with params 0..4 = b0, b2, k, m.
    let names = ["b0", "b2", "k", "m"];
    let f = ir::Expr::Input(0);
    let e = bin(
        BinOp::Sub,
        bin(
            BinOp::Add,
            bin(
                BinOp::Mul,
                ir::Expr::Param(0),
                ir::Expr::Call(Func::Sign, vec![f.clone()]),
            ),
            bin(BinOp::Mul, ir::Expr::Param(1), f.clone()),
        ),
        bin(
            BinOp::Div,
            ir::Expr::Param(2),
            bin(BinOp::Pow, ir::Expr::Param(3), ir::Expr::Const(2.0)),
        ),
    );
    let leaf = |l: &ir::Expr| match l {
        ir::Expr::Param(i) => names.get(*i).map(|n| p(n)),
        ir::Expr::Input(0) => Some(Expr::symbol(Symbol::input("f"))),
        _ => None,
    };
    let fs = Expr::symbol(Symbol::input("f"));
    let want = p("b0") * fs.sign() + p("b2") * &fs - p("k") / p("m").powi(2);
    assert_eq!(from_ir(&e, &leaf), Ok(want));
    assert_eq!(
        from_ir(&ir::Expr::Neg(Box::new(ir::Expr::Const(2.0))), &leaf),
        Ok(c(-2.0))
    );
}

#[test]
fn unmapped_leaves_and_wrong_arity_are_errors() {
    let none = |_: &ir::Expr| None;
    assert_eq!(
        from_ir(&ir::Expr::Time, &none),
        Err(SymbolicError::UnmappedLeaf {
            leaf: "Time".to_string()
        })
    );
    let bad = ir::Expr::Call(Func::Atan2, vec![ir::Expr::Const(1.0)]);
    assert_eq!(
        from_ir(&bad, &none),
        Err(SymbolicError::Arity {
            func: "atan2",
            expected: 2,
            found: 1
        })
    );
}
