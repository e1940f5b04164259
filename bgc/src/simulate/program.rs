//! Symbolic expressions compiled into flat stack programs for fast repeated evaluation.
//!
//! An [`Expr`] of the equations stage is walked once into a postfix list of `Op`s; evaluating it is then a loop
//! over that list with a small value stack and no allocation per call (the stack is reused). The expression is a
//! DAG: a node that it holds more than once is computed once, kept in a slot at the bottom of the stack and read
//! from there again, so a program is as long as the distinct nodes, not the tree (which can be the square of
//! them, or exponential in them). The walk is on an explicit stack, however deep the expression. Only the symbols
//! a simulation has values for are accepted: parameters, states, inputs and time. Every index is checked when the
//! program is compiled, and evaluation uses checked access anyway, so a program never panics: a missing value reads
//! as NaN, which the integrator reports as a non-finite derivative.

use crate::equations::symbols::Sym;
use crate::ir::Func;
use crate::symbolic::{Expr, ExprMap, Node};

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
    /// Copies the top value into slot `k` (it stays on top).
    Store(usize),
    /// Pushes the value of slot `k`.
    Load(usize),
    /// Pops a finished value and appends it to the inputs (a [`ProgramSeq`]'s next result).
    Out,
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
    /// The deepest the value stack gets above the slots.
    depth: usize,
    /// The slots of the shared nodes, at the bottom of the stack.
    slots: usize,
}

impl Program {
    /// Compiles `e` for values laid out as `layout`; `name` is used to print unsupported symbols.
    pub fn compile(
        e: &Expr,
        layout: Layout,
        name: &dyn Fn(Sym) -> String,
    ) -> Result<Program, CompileError> {
        let mut emitter = Emitter::new(std::slice::from_ref(e), layout, name);
        emitter.root(e)?;
        Ok(emitter.program())
    }

    /// Evaluates the program; `stack` is scratch space reused between calls.
    pub fn eval(&self, v: &Values<'_>, stack: &mut Vec<f64>) -> f64 {
        let mut inputs = v.inputs;
        self.run(v, &mut inputs, stack)
    }

    /// The interpreter: reads the inputs from `inputs` (not `v.inputs`), where [`Op::Out`] appends.
    fn run<I: Inputs>(&self, v: &Values<'_>, inputs: &mut I, stack: &mut Vec<f64>) -> f64 {
        stack.clear();
        if self.slots > 0 {
            stack.resize(self.slots, f64::NAN);
        }
        stack.reserve(self.depth);
        for op in &self.ops {
            match *op {
                Op::Num(x) => stack.push(x),
                Op::Param(i) => stack.push(v.params.get(i).copied().unwrap_or(f64::NAN)),
                Op::State(i) => stack.push(v.states.get(i).copied().unwrap_or(f64::NAN)),
                Op::Input(i) => stack.push(inputs.input(i)),
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
                Op::Store(k) => {
                    let top = stack.last().copied().unwrap_or(f64::NAN);
                    if let Some(slot) = stack.get_mut(k) {
                        *slot = top;
                    }
                }
                Op::Load(k) => stack.push(stack.get(k).copied().unwrap_or(f64::NAN)),
                Op::Out => inputs.append(stack.pop().unwrap_or(f64::NAN)),
            }
        }
        stack.pop().unwrap_or(f64::NAN)
    }
}

/// Expressions compiled into one program, evaluated in order: a node that they hold more than once, in one of
/// them or in several, is computed once. Each value is appended to the inputs, where the later expressions read
/// it (outputs defined through earlier outputs), so outputs whose expressions hold one another (the efforts
/// along a gear train) cost their distinct nodes together, not each its own tree.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramSeq(Program);

impl ProgramSeq {
    /// Compiles `es` in order; a failure gives the index of the expression that could not be compiled.
    pub fn compile(
        es: &[Expr],
        layout: Layout,
        name: &dyn Fn(Sym) -> String,
    ) -> Result<ProgramSeq, (usize, CompileError)> {
        let mut emitter = Emitter::new(es, layout, name);
        for (i, e) in es.iter().enumerate() {
            emitter.root(e).map_err(|err| (i, err))?;
            emitter.push(Op::Out, 0, 1);
        }
        Ok(ProgramSeq(emitter.program()))
    }

    /// Evaluates the expressions in order at `v` (whose `inputs` are not read), appending each value to `inputs`.
    pub fn eval_appending(&self, v: &Values<'_>, inputs: &mut Vec<f64>, stack: &mut Vec<f64>) {
        self.0.run(v, inputs, stack);
    }
}

/// Where a program reads its inputs, and where [`Op::Out`] puts its results.
trait Inputs {
    fn input(&self, k: usize) -> f64;
    fn append(&mut self, value: f64);
}

impl Inputs for &[f64] {
    fn input(&self, k: usize) -> f64 {
        self.get(k).copied().unwrap_or(f64::NAN)
    }

    /// A single expression has no results to append.
    fn append(&mut self, _: f64) {}
}

impl Inputs for Vec<f64> {
    fn input(&self, k: usize) -> f64 {
        self.get(k).copied().unwrap_or(f64::NAN)
    }

    fn append(&mut self, value: f64) {
        self.push(value);
    }
}

/// For each distinct node of `roots`, how many times the nodes above it hold it (each root once more).
fn uses(roots: &[Expr]) -> ExprMap<usize> {
    let mut uses: ExprMap<usize> = ExprMap::default();
    let mut stack: Vec<&Expr> = roots.iter().collect();
    while let Some(e) = stack.pop() {
        if let Some(n) = uses.get_mut(e) {
            *n += 1;
            continue;
        }
        uses.insert(e.clone(), 1);
        stack.extend((0..).map_while(|i| operand(e, i)));
    }
    uses
}

/// The compilation of one expression, or of several into one program.
struct Emitter<'a> {
    layout: Layout,
    name: &'a dyn Fn(Sym) -> String,
    uses: ExprMap<usize>,
    /// The slot of each shared node already computed.
    slot_of: ExprMap<usize>,
    ops: Vec<Op>,
    depth: usize,
    max_depth: usize,
}

impl<'a> Emitter<'a> {
    fn new(roots: &[Expr], layout: Layout, name: &'a dyn Fn(Sym) -> String) -> Emitter<'a> {
        Emitter {
            layout,
            name,
            uses: uses(roots),
            slot_of: ExprMap::default(),
            ops: Vec::new(),
            depth: 0,
            max_depth: 0,
        }
    }

    /// Emits the ops that leave the value of `root` on top of the stack.
    fn root(&mut self, root: &Expr) -> Result<(), CompileError> {
        // Each frame: a node whose children are being emitted, and how many are done.
        let mut frames: Vec<(&Expr, usize)> = Vec::new();
        self.start(root, &mut frames)?;
        while let Some((e, next)) = frames.last_mut() {
            let e: &Expr = e;
            if let Some(child) = operand(e, *next) {
                *next += 1;
                self.start(child, &mut frames)?;
                continue;
            }
            frames.pop();
            self.finish(e);
        }
        Ok(())
    }

    fn program(self) -> Program {
        Program {
            ops: self.ops,
            depth: self.max_depth,
            slots: self.slot_of.len(),
        }
    }

    /// Emits a leaf or the read of a node computed before, or opens a frame for an operation.
    fn start<'e>(
        &mut self,
        e: &'e Expr,
        frames: &mut Vec<(&'e Expr, usize)>,
    ) -> Result<(), CompileError> {
        if let Some(&k) = self.slot_of.get(e) {
            self.push(Op::Load(k), 1, 0);
            return Ok(());
        }
        match e.node() {
            Node::Const(x) => self.push(Op::Num(*x), 1, 0),
            Node::Sym(symbol) => {
                let op = self.leaf(symbol)?;
                self.push(op, 1, 0);
            }
            Node::Call(f, args) if args.is_empty() || args.len() > 2 => {
                return Err(CompileError::Unsupported(format!(
                    "{} with {} arguments",
                    f.name(),
                    args.len()
                )));
            }
            _ => frames.push((e, 0)),
        }
        Ok(())
    }

    /// Emits the operation of `e` on its operands' values, and keeps the value in a slot when `e` is shared.
    fn finish(&mut self, e: &Expr) {
        match e.node() {
            Node::Add(ts) => self.push(Op::Add(ts.len()), 1, ts.len()),
            Node::Mul(ts) => self.push(Op::Mul(ts.len()), 1, ts.len()),
            Node::Pow(..) => self.push(Op::Pow, 1, 2),
            Node::Call(f, args) => self.push(Op::Call(*f, args.len()), 1, args.len()),
            Node::Const(_) | Node::Sym(_) => {}
        }
        if self.uses.get(e).is_some_and(|&n| n > 1) {
            let k = self.slot_of.len();
            self.slot_of.insert(e.clone(), k);
            self.ops.push(Op::Store(k));
        }
    }

    /// Appends `op`, which takes `popped` values and pushes `pushed`.
    fn push(&mut self, op: Op, pushed: usize, popped: usize) {
        self.ops.push(op);
        self.depth = self.depth.saturating_sub(popped) + pushed;
        self.max_depth = self.max_depth.max(self.depth).max(1);
    }

    fn leaf(&self, symbol: &crate::symbolic::Symbol) -> Result<Op, CompileError> {
        let Some(s) = Sym::of(symbol) else {
            return Err(CompileError::Unsupported(symbol.to_string()));
        };
        let layout = self.layout;
        let (op, ok) = match s {
            Sym::Param(i) => (Op::Param(i), i < layout.params),
            Sym::State(i) => (Op::State(i), i < layout.states),
            Sym::Input(i) => (Op::Input(i), i < layout.inputs),
            Sym::Time => (Op::Time, true),
            other => return Err(CompileError::Unsupported((self.name)(other))),
        };
        if ok {
            Ok(op)
        } else {
            Err(CompileError::OutOfRange((self.name)(s)))
        }
    }
}

/// Operand `i` of a node, in evaluation order.
fn operand(e: &Expr, i: usize) -> Option<&Expr> {
    match (e.node(), i) {
        (Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs), _) => xs.get(i),
        (Node::Pow(b, _), 0) => Some(b),
        (Node::Pow(_, x), 1) => Some(x),
        _ => None,
    }
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

    /// `s_{k+1} = sin(s_k) s_k + s_k` from `s_0 = x_0`, `levels` times: each level holds the one below three
    /// times. With its value at `x_0`, by `f64` arithmetic.
    fn shared_chain(levels: usize, x0: f64) -> (Expr, f64) {
        let (mut e, mut value) = (symbols::leaf(Sym::State(0)), x0);
        for _ in 0..levels {
            e = add(vec![
                mul(vec![call(Func::Sin, vec![e.clone()]), e.clone()]),
                e,
            ]);
            value = value.sin() * value + value;
        }
        (e, value)
    }

    /// The values of a program that reads only states and inputs.
    fn at<'a>(states: &'a [f64], inputs: &'a [f64]) -> Values<'a> {
        Values {
            params: &[],
            states,
            inputs,
            t: 0.0,
        }
    }

    /// A node held several times is computed once: in [`shared_chain`] 12 levels are 3^12 nodes as a tree, and as
    /// a program about a dozen per level.
    #[test]
    fn a_shared_node_is_computed_once() {
        let (e, want) = shared_chain(12, 0.3);
        let p = Program::compile(&e, LAYOUT, &name).unwrap();
        assert!(p.ops.len() < 12 * 16, "{} ops", p.ops.len());
        let got = p.eval(&at(&[0.3, 0.0], &[0.0]), &mut Vec::new());
        assert!((got - want).abs() <= 1e-15 * want.abs(), "{got} vs {want}");
    }

    /// Expressions compiled together share their nodes: `S`, held by both, is computed once, and the second reads
    /// the first's value where it was appended to the inputs.
    #[test]
    fn a_sequence_computes_what_its_expressions_share_once() {
        let (shared, _) = shared_chain(10, 0.0);
        let layout = Layout {
            params: 0,
            states: 2,
            inputs: 3,
        };
        let first = mul(vec![shared.clone(), symbols::leaf(Sym::State(1))]);
        let second = add(vec![shared, symbols::leaf(Sym::Input(1))]);
        let seq = ProgramSeq::compile(&[first.clone(), second.clone()], layout, &name).unwrap();
        let (p1, p2) = (
            Program::compile(&first, layout, &name).unwrap(),
            Program::compile(&second, layout, &name).unwrap(),
        );
        let states = [0.3, -1.7];
        let y1 = p1.eval(&at(&states, &[0.5]), &mut Vec::new());
        let y2 = p2.eval(&at(&states, &[0.5, y1]), &mut Vec::new());
        let mut inputs = vec![0.5];
        seq.eval_appending(&at(&states, &[]), &mut inputs, &mut Vec::new());
        assert_eq!(inputs, vec![0.5, y1, y2]);
        let (together, apart) = (seq.0.ops.len(), p1.ops.len() + p2.ops.len());
        assert!(
            together + 80 < apart,
            "{together} ops together, {apart} apart"
        );
    }

    /// An expression as deep as a model is long (the efforts along a gear train each hold the next) is compiled
    /// on an explicit stack: 50,000 nested calls on a test thread's stack.
    #[test]
    fn a_deep_expression_compiles_without_recursion() {
        let mut e = symbols::leaf(Sym::State(1));
        let mut want = 0.9f64;
        for _ in 0..50_000 {
            e = call(Func::Sin, vec![e]);
            want = want.sin();
        }
        let p = Program::compile(&e, LAYOUT, &name).unwrap();
        assert_eq!(p.eval(&at(&[0.0, 0.9], &[0.0]), &mut Vec::new()), want);
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
