//! Symbolic expressions compiled into flat stack programs for fast repeated evaluation.
//!
//! An [`Expr`] tree of the equations stage is walked once into a postfix list of `Op`s; evaluating it is then a
//! loop over that list with a small value stack and no allocation per call (the stack is reused). Only the symbols
//! a simulation has values for are accepted: parameters, states, inputs and time. Every index is checked when the
//! program is compiled, and evaluation uses checked access anyway, so a program never panics: a missing value reads
//! as NaN, which the integrator reports as a non-finite derivative.

use crate::equations::symbols::Sym;
use crate::ir::Func;
use crate::symbolic::{Expr, Node};

/// One instruction of a program.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Num(f64),
    Param(usize),
    State(usize),
    Input(usize),
    Time,
    /// Adds the top `n` values.
    Add(usize),
    /// Multiplies the top `n` values.
    Mul(usize),
    Pow,
    /// Calls a function on the top `n` values.
    Call(Func, usize),
}

/// Why an expression cannot be compiled.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CompileError {
    /// A symbol that has no value during a simulation (an input derivative, an unresolved intermediate).
    #[error("it uses `{0}`, which has no value during a simulation")]
    Unsupported(String),
    /// A symbol whose index is out of range of the value tables.
    #[error("it refers to {0}, which does not exist")]
    OutOfRange(String),
}

/// The sizes of the value tables a program reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub params: usize,
    pub states: usize,
    pub inputs: usize,
}

/// The values a program reads.
#[derive(Clone, Copy, Debug)]
pub struct Values<'a> {
    pub params: &'a [f64],
    pub states: &'a [f64],
    pub inputs: &'a [f64],
    pub t: f64,
}

/// A compiled expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    ops: Vec<Op>,
    /// The deepest the value stack gets.
    depth: usize,
}

impl Program {
    /// Compiles `e` for values laid out as `layout`; `name` is used to print unsupported symbols.
    pub fn compile(
        e: &Expr,
        layout: Layout,
        name: &dyn Fn(Sym) -> String,
    ) -> Result<Program, CompileError> {
        let mut ops = Vec::new();
        let mut depth = 0;
        let mut max_depth = 0;
        emit(e, layout, name, &mut ops, &mut depth, &mut max_depth)?;
        Ok(Program {
            ops,
            depth: max_depth,
        })
    }

    /// Evaluates the program; `stack` is scratch space reused between calls.
    pub fn eval(&self, v: &Values<'_>, stack: &mut Vec<f64>) -> f64 {
        stack.clear();
        stack.reserve(self.depth);
        for op in &self.ops {
            match *op {
                Op::Num(x) => stack.push(x),
                Op::Param(i) => stack.push(v.params.get(i).copied().unwrap_or(f64::NAN)),
                Op::State(i) => stack.push(v.states.get(i).copied().unwrap_or(f64::NAN)),
                Op::Input(i) => stack.push(v.inputs.get(i).copied().unwrap_or(f64::NAN)),
                Op::Time => stack.push(v.t),
                Op::Add(n) => {
                    let start = stack.len().saturating_sub(n);
                    let s: f64 = stack.drain(start..).sum();
                    stack.push(s);
                }
                Op::Mul(n) => {
                    let start = stack.len().saturating_sub(n);
                    let p: f64 = stack.drain(start..).product();
                    stack.push(p);
                }
                Op::Pow => {
                    let x = stack.pop().unwrap_or(f64::NAN);
                    let b = stack.pop().unwrap_or(f64::NAN);
                    stack.push(if x.fract() == 0.0 && x.abs() < 64.0 {
                        b.powi(x as i32)
                    } else {
                        b.powf(x)
                    });
                }
                Op::Call(f, n) => {
                    let start = stack.len().saturating_sub(n);
                    let args: [f64; 2] = match n {
                        1 => [stack.get(start).copied().unwrap_or(f64::NAN), 0.0],
                        _ => [
                            stack.get(start).copied().unwrap_or(f64::NAN),
                            stack.get(start + 1).copied().unwrap_or(f64::NAN),
                        ],
                    };
                    stack.truncate(start);
                    let value = args
                        .get(..n.min(2))
                        .and_then(|a| f.eval(a))
                        .unwrap_or(f64::NAN);
                    stack.push(value);
                }
            }
        }
        stack.pop().unwrap_or(f64::NAN)
    }
}

fn emit(
    e: &Expr,
    layout: Layout,
    name: &dyn Fn(Sym) -> String,
    ops: &mut Vec<Op>,
    depth: &mut usize,
    max_depth: &mut usize,
) -> Result<(), CompileError> {
    let push = |ops: &mut Vec<Op>, op: Op, depth: &mut usize, max_depth: &mut usize| {
        ops.push(op);
        *depth += 1;
        *max_depth = (*max_depth).max(*depth);
    };
    match e.node() {
        Node::Const(x) => push(ops, Op::Num(*x), depth, max_depth),
        Node::Sym(symbol) => {
            let Some(s) = Sym::of(symbol) else {
                return Err(CompileError::Unsupported(symbol.to_string()));
            };
            let (op, ok) = match s {
                Sym::Param(i) => (Op::Param(i), i < layout.params),
                Sym::State(i) => (Op::State(i), i < layout.states),
                Sym::Input(i) => (Op::Input(i), i < layout.inputs),
                Sym::Time => (Op::Time, true),
                other => return Err(CompileError::Unsupported(name(other))),
            };
            if !ok {
                return Err(CompileError::OutOfRange(name(s)));
            }
            push(ops, op, depth, max_depth);
        }
        Node::Add(ts) | Node::Mul(ts) => {
            for t in ts {
                emit(t, layout, name, ops, depth, max_depth)?;
            }
            let n = ts.len();
            ops.push(if matches!(e.node(), Node::Add(_)) {
                Op::Add(n)
            } else {
                Op::Mul(n)
            });
            *depth = *depth + 1 - n.min(*depth + 1);
            if n == 0 {
                *max_depth = (*max_depth).max(*depth);
            }
        }
        Node::Pow(b, x) => {
            emit(b, layout, name, ops, depth, max_depth)?;
            emit(x, layout, name, ops, depth, max_depth)?;
            ops.push(Op::Pow);
            *depth = depth.saturating_sub(1);
        }
        Node::Call(f, args) => {
            if args.is_empty() || args.len() > 2 {
                return Err(CompileError::Unsupported(format!(
                    "{} with {} arguments",
                    f.name(),
                    args.len()
                )));
            }
            for a in args {
                emit(a, layout, name, ops, depth, max_depth)?;
            }
            ops.push(Op::Call(*f, args.len()));
            *depth = *depth + 1 - args.len();
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::equations::symbols::{self, add, call, div, mul, pow};

    fn name(s: Sym) -> String {
        format!("{s:?}")
    }

    const LAYOUT: Layout = Layout {
        params: 2,
        states: 2,
        inputs: 1,
    };

    #[test]
    fn agrees_with_the_tree_evaluator() {
        // (k x0^2)/2 + sin(u t) * atan2(x1, c) - x1^3 / k
        let k = symbols::leaf(Sym::Param(0));
        let c = symbols::leaf(Sym::Param(1));
        let x0 = symbols::leaf(Sym::State(0));
        let x1 = symbols::leaf(Sym::State(1));
        let u = symbols::leaf(Sym::Input(0));
        let t = symbols::leaf(Sym::Time);
        let e = add(vec![
            div(
                mul(vec![k.clone(), pow(x0, symbols::num(2.0))]),
                symbols::num(2.0),
            ),
            mul(vec![
                call(Func::Sin, vec![mul(vec![u, t])]),
                call(Func::Atan2, vec![x1.clone(), c]),
            ]),
            mul(vec![symbols::num(-1.0), div(pow(x1, symbols::num(3.0)), k)]),
        ]);
        let p = Program::compile(&e, LAYOUT, &name).unwrap();
        let (params, states, inputs) = ([3.0, 0.5], [1.5, -0.7], [2.0]);
        let values = Values {
            params: &params,
            states: &states,
            inputs: &inputs,
            t: 0.3,
        };
        let value = |s: Sym| match s {
            Sym::Param(i) => params.get(i).copied(),
            Sym::State(i) => states.get(i).copied(),
            Sym::Input(i) => inputs.get(i).copied(),
            Sym::Time => Some(0.3),
            _ => None,
        };
        let expected = symbols::eval(&e, &value).unwrap();
        let hand = 3.0 * 1.5f64.powi(2) / 2.0 + (0.6f64).sin() * (-0.7f64).atan2(0.5)
            - (-0.7f64).powi(3) / 3.0;
        let mut stack = Vec::new();
        assert!((p.eval(&values, &mut stack) - expected).abs() < 1e-14);
        assert!((expected - hand).abs() < 1e-12);
    }

    #[test]
    fn refuses_symbols_without_values() {
        let e = add(vec![symbols::leaf(Sym::InputDot(0)), symbols::num(1.0)]);
        assert!(matches!(
            Program::compile(&e, LAYOUT, &name),
            Err(CompileError::Unsupported(_))
        ));
        let e = symbols::leaf(Sym::State(5));
        assert!(matches!(
            Program::compile(&e, LAYOUT, &name),
            Err(CompileError::OutOfRange(_))
        ));
    }
}
