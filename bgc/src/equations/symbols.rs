//! The symbols of the equations stage and the few operations it needs beyond those of [`crate::symbolic`].
//!
//! The stage builds its expressions in the shared engine ([`Expr`], a hash-consed DAG). Its leaves are
//! [`Symbol::indexed`] symbols: a kind and an index into the stage's own tables (parameters, inputs, states, bond
//! variables, outputs, and the unknowns that exist only while it derives: tear variables, state and input
//! derivatives). [`Sym`] is that identity as a plain value, for matching; [`super::Equations::sym_name`] names it.
//! Because a symbol carries no name, equal quantities are one symbol whatever they are called, two quantities are
//! never confused by their names, and names can be decided after the expressions are built (the readable names of
//! bond variables are).
//!
//! Every operation here walks the distinct nodes of the DAG on explicit stacks, never by recursion: the depth of
//! an expression can grow with the model.

use crate::ir::Func;
use crate::symbolic::{Expr, ExprMap, ExprSet, Node, ProductTails, Symbol, SymbolKind, WIDE_ROW};
use std::cell::RefCell;

/// A leaf of the stage's expressions. The variants are declared in the order of their [`SymbolKind`]s, so that
/// `Sym`'s order is that of its symbols.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Sym {
    /// A model parameter.
    Param(usize),
    /// A model input.
    Input(usize),
    /// Time.
    Time,
    /// A state (index into the equations' state list).
    State(usize),
    /// An intermediate bond variable (index into the equations' variable table).
    Var(usize),
    /// The value of an earlier output (index into the equations' outputs): an output defined through earlier
    /// outputs refers to them instead of copying their expressions, and consumers evaluate outputs in order.
    Output(usize),
    /// A tear variable of an algebraic loop (the variable index it stands for).
    Tear(usize),
    /// The time derivative of a state (an unknown while derivative causality is resolved).
    StateDot(usize),
    /// The time derivative of an input. Kept only in the power of an element next to a storage in derivative
    /// causality (energy terms); a rate or output that keeps one is refused.
    InputDot(usize),
}

/// The index of a tear that stands for no variable: the unknown while a law is inverted or integrated.
pub(crate) const PLACEHOLDER: usize = Symbol::MAX_INDEX;

impl Sym {
    /// The engine's symbol of `self`.
    pub fn symbol(self) -> Symbol {
        let (kind, index) = match self {
            Sym::Param(i) => (SymbolKind::Param, i),
            Sym::Input(i) => (SymbolKind::Input, i),
            Sym::InputDot(i) => (SymbolKind::InputRate, i),
            Sym::State(i) => (SymbolKind::State, i),
            Sym::StateDot(i) => (SymbolKind::StateRate, i),
            Sym::Var(i) => (SymbolKind::Intermediate, i),
            Sym::Tear(i) => (SymbolKind::Tear, i),
            Sym::Output(i) => (SymbolKind::Output, i),
            Sym::Time => return Symbol::time(),
        };
        Symbol::indexed(kind, index)
    }

    /// `self` as an expression.
    pub fn expr(self) -> Expr {
        Expr::symbol(self.symbol())
    }

    /// The stage's symbol that `s` is, if it is one.
    pub fn of(s: &Symbol) -> Option<Sym> {
        let kind = s.kind();
        if kind == SymbolKind::Time {
            return Some(Sym::Time);
        }
        let i = s.index()?;
        Some(match kind {
            SymbolKind::Param => Sym::Param(i),
            SymbolKind::Input => Sym::Input(i),
            SymbolKind::InputRate => Sym::InputDot(i),
            SymbolKind::State => Sym::State(i),
            SymbolKind::StateRate => Sym::StateDot(i),
            SymbolKind::Intermediate => Sym::Var(i),
            SymbolKind::Tear => Sym::Tear(i),
            SymbolKind::Output => Sym::Output(i),
            SymbolKind::Time => Sym::Time,
        })
    }
}

/// Expressions of at most this many nodes as trees are walked as trees (their depth is at most this), larger ones
/// over their distinct nodes.
const SMALL: usize = 64;

/// Reading the stage's symbols out of an expression.
pub trait SymExt {
    /// The stage's symbol if this is a bare one.
    fn as_sym(&self) -> Option<Sym>;
    /// The value if this is a constant.
    fn num(&self) -> Option<f64>;
    /// The distinct symbols of the stage in the expression, in the engine's symbol order.
    fn syms(&self) -> Vec<Sym>;
    /// Visits each distinct symbol once.
    fn for_each_sym(&self, f: &mut dyn FnMut(Sym));
    /// True when some symbol satisfies `pred`.
    fn any_sym(&self, pred: &dyn Fn(Sym) -> bool) -> bool;
    /// True when `s` occurs.
    fn contains(&self, s: Sym) -> bool;
}

impl SymExt for Expr {
    fn as_sym(&self) -> Option<Sym> {
        self.as_symbol().and_then(Sym::of)
    }

    fn num(&self) -> Option<f64> {
        self.as_const()
    }

    fn syms(&self) -> Vec<Sym> {
        if self.node_count() <= SMALL {
            // A small tree: walked as a tree, without the bookkeeping of a walk of distinct nodes.
            let mut out = Vec::new();
            let mut stack = vec![self];
            while let Some(e) = stack.pop() {
                match e.node() {
                    Node::Const(_) => {}
                    Node::Sym(s) => out.extend(Sym::of(s)),
                    Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => stack.extend(xs),
                    Node::Pow(b, x) => stack.extend([b, x]),
                }
            }
            out.sort_unstable();
            out.dedup();
            return out;
        }
        self.free_symbols().iter().filter_map(Sym::of).collect()
    }

    fn for_each_sym(&self, f: &mut dyn FnMut(Sym)) {
        self.syms().into_iter().for_each(f);
    }

    fn any_sym(&self, pred: &dyn Fn(Sym) -> bool) -> bool {
        self.syms().into_iter().any(pred)
    }

    fn contains(&self, s: Sym) -> bool {
        if self.node_count() <= SMALL {
            return self.syms().contains(&s);
        }
        self.depends_on(&s.symbol())
    }
}

/// The distinct nodes reachable from `roots`, each after its children, found on an explicit stack.
pub fn post_order(roots: &[Expr]) -> Vec<Expr> {
    let mut seen = ExprSet::default();
    let mut order = Vec::new();
    let mut stack: Vec<(Expr, usize)> = Vec::new();
    for root in roots {
        if !seen.insert(root.clone()) {
            continue;
        }
        stack.push((root.clone(), 0));
        while let Some((e, next)) = stack.last_mut() {
            match child(e, *next) {
                Some(c) => {
                    *next += 1;
                    if seen.insert(c.clone()) {
                        stack.push((c, 0));
                    }
                }
                None => {
                    order.push(e.clone());
                    stack.pop();
                }
            }
        }
    }
    order
}

/// The `i`-th child of `e`.
fn child(e: &Expr, i: usize) -> Option<Expr> {
    match e.node() {
        Node::Const(_) | Node::Sym(_) => None,
        Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => xs.get(i).cloned(),
        Node::Pow(b, x) => [b, x].get(i).map(|c| (*c).clone()),
    }
}

/// The expression of one symbol.
pub fn leaf(s: Sym) -> Expr {
    s.expr()
}

/// A constant.
pub fn num(v: f64) -> Expr {
    Expr::constant(v)
}

/// `a + b + ...`.
pub fn add(terms: Vec<Expr>) -> Expr {
    Expr::sum(terms)
}

/// `a · b · ...`.
pub fn mul(factors: Vec<Expr>) -> Expr {
    Expr::product(factors)
}

/// `base ^ exponent`.
pub fn pow(base: Expr, exponent: Expr) -> Expr {
    base.pow(&exponent)
}

pub fn neg(a: Expr) -> Expr {
    -a
}

pub fn sub(a: Expr, b: Expr) -> Expr {
    a - b
}

pub fn div(a: Expr, b: Expr) -> Expr {
    a / b
}

pub fn recip(a: Expr) -> Expr {
    a.recip()
}

/// A function call, folded when its arguments are numbers. The stage calls functions with the arity the
/// language checked; a wrong one gives NaN.
pub fn call(f: Func, args: Vec<Expr>) -> Expr {
    Expr::call(f, &args).unwrap_or_else(|| Expr::constant(f64::NAN))
}

/// Replaces symbols: `f(s)` gives the replacement or `None` to keep `s`. Each distinct symbol is asked once and
/// each distinct node rebuilt once.
pub fn subst(e: &Expr, f: &mut dyn FnMut(Sym) -> Option<Expr>) -> Expr {
    if e.node_count() <= SMALL {
        return subst_small(e, f);
    }
    let f = RefCell::new(f);
    e.substitute_with(&|s: &Symbol| Sym::of(s).and_then(|t| (f.borrow_mut())(t)))
}

/// [`subst`] of several expressions at once, each distinct node of all of them once (see
/// [`Expr::substitute_all`]).
pub fn subst_all(es: &[Expr], f: &mut dyn FnMut(Sym) -> Option<Expr>) -> Vec<Expr> {
    let f = RefCell::new(f);
    by_size(
        es,
        |e| subst_small(e, &mut *f.borrow_mut()),
        |large| {
            Expr::substitute_all(large, &|s: &Symbol| {
                Sym::of(s).and_then(|t| (f.borrow_mut())(t))
            })
        },
    )
}

/// For each expression, whether one of its symbols satisfies `pred`: small trees each on their own, the large
/// ones in one walk of their distinct nodes.
pub fn each_has_sym(es: &[Expr], pred: &dyn Fn(Sym) -> bool) -> Vec<bool> {
    by_size(
        es,
        |e| e.any_sym(pred),
        |large| Expr::each_depends_on(large, &|s: &Symbol| Sym::of(s).is_some_and(pred)),
    )
}

/// `small` of each tree of at most [`SMALL`] nodes, walked as a tree without a table (most terms of a large model
/// are), and `large` of all the others at once, so that what they share is visited once; in the order of `es`.
fn by_size<T>(
    es: &[Expr],
    mut small: impl FnMut(&Expr) -> T,
    large: impl FnOnce(&[Expr]) -> Vec<T>,
) -> Vec<T> {
    let big: Vec<Expr> = es
        .iter()
        .filter(|e| e.node_count() > SMALL)
        .cloned()
        .collect();
    let mut big_done = large(&big).into_iter();
    es.iter()
        .map(|e| match e.node_count() <= SMALL {
            true => small(e),
            false => big_done.next().unwrap_or_else(|| small(e)),
        })
        .collect()
}

/// [`subst`] of a small tree (depth at most [`SMALL`]), rebuilding only what changes.
fn subst_small(e: &Expr, f: &mut dyn FnMut(Sym) -> Option<Expr>) -> Expr {
    // The children from the first one that changes; `None`, and nothing allocated, when none does.
    let all = |xs: &[Expr], f: &mut dyn FnMut(Sym) -> Option<Expr>| -> Option<Vec<Expr>> {
        let (first, changed) = xs.iter().enumerate().find_map(|(i, x)| {
            let y = subst_small(x, f);
            (y != *x).then_some((i, y))
        })?;
        let mut ys = Vec::with_capacity(xs.len());
        ys.extend_from_slice(&xs[..first]);
        ys.push(changed);
        ys.extend(xs[first + 1..].iter().map(|x| subst_small(x, f)));
        Some(ys)
    };
    match e.node() {
        Node::Const(_) => e.clone(),
        Node::Sym(s) => Sym::of(s).and_then(&mut *f).unwrap_or_else(|| e.clone()),
        Node::Add(xs) => all(xs, f).map_or_else(|| e.clone(), Expr::sum),
        Node::Mul(xs) => all(xs, f).map_or_else(|| e.clone(), Expr::product),
        Node::Pow(b, x) => {
            let (b2, x2) = (subst_small(b, f), subst_small(x, f));
            if b2 == *b && x2 == *x {
                e.clone()
            } else {
                b2.pow(&x2)
            }
        }
        Node::Call(func, xs) => all(xs, f).map_or_else(|| e.clone(), |ys| call(*func, ys)),
    }
}

/// Why an expression could not be differentiated.
#[derive(Clone, Debug, PartialEq)]
pub struct NotDifferentiable(pub Func);

/// `∂e/∂s`. `min` and `max` of an argument holding `s` are refused: the equations stage does not differentiate
/// through a switch (a law in derivative causality must be smooth).
pub fn diff(e: &Expr, s: Sym) -> Result<Expr, NotDifferentiable> {
    diff_sharing(e, s, &mut ProductTails::default())
}

/// [`diff`], with the derivatives of long products' tails kept in `tails` between calls.
fn diff_sharing(e: &Expr, s: Sym, tails: &mut ProductTails) -> Result<Expr, NotDifferentiable> {
    let x = s.symbol();
    if !e.depends_on(&x) {
        return Ok(Expr::zero());
    }
    if let Some((f, read)) = e.symbols_under_calls(&[Func::Min, Func::Max])
        && read.contains(&x)
    {
        return Err(NotDifferentiable(f));
    }
    Ok(e.diff_sharing(&x, tails))
}

/// `∂e/∂s` for each `s` of `wrt`, which should be symbols that `e` reads (an unread one costs a walk and gives 0).
/// More than [`WIDE_ROW`] of them are differentiated in one reverse-mode walk of `e` ([`Expr::gradient`]); fewer,
/// symbol by symbol as [`diff`] does. Symbol by symbol, a row that reads many symbols is walked once per symbol:
/// the square of its size, and the cube of a block of loops whose residuals each read every tear.
/// Refused as [`diff`] refuses: a symbol of `wrt` read under `min` or `max`.
pub fn gradient(e: &Expr, wrt: &[Sym]) -> Result<Vec<Expr>, NotDifferentiable> {
    gradient_sharing(e, wrt, &mut ProductTails::default())
}

/// [`gradient`], with the derivatives of long products' tails kept in `tails` between calls
/// ([`Expr::diff_sharing`]).
pub fn gradient_sharing(
    e: &Expr,
    wrt: &[Sym],
    tails: &mut ProductTails,
) -> Result<Vec<Expr>, NotDifferentiable> {
    if wrt.len() <= WIDE_ROW {
        return wrt.iter().map(|&s| diff_sharing(e, s, tails)).collect();
    }
    let vars: Vec<Symbol> = wrt.iter().map(|s| s.symbol()).collect();
    if let Some((f, under)) = e.symbols_under_calls(&[Func::Min, Func::Max])
        && vars.iter().any(|v| under.contains(v))
    {
        return Err(NotDifferentiable(f));
    }
    Ok(e.gradient(&vars))
}

/// Why an expression could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// A symbol without a value.
    Unbound(Sym),
    /// A symbol that is not one of the stage's.
    Foreign(String),
}

/// Evaluates with values of the symbols from `value`.
pub fn eval(e: &Expr, value: &dyn Fn(Sym) -> Option<f64>) -> Result<f64, EvalError> {
    e.eval(|s: &Symbol| Sym::of(s).and_then(value))
        .map_err(|_| {
            e.free_symbols()
                .iter()
                .find_map(|s| match Sym::of(s) {
                    Some(t) if value(t).is_none() => Some(EvalError::Unbound(t)),
                    None => Some(EvalError::Foreign(s.to_string())),
                    _ => None,
                })
                .unwrap_or_else(|| EvalError::Foreign(e.to_string()))
        })
}

/// `e = a·s + b` with `a`, `b` free of `s`, or `None` when `e` is not affine in `s`.
pub fn affine_in(e: &Expr, s: Sym) -> Option<(Expr, Expr)> {
    // Functions such as sign have a zero derivative almost everywhere: the derivative test alone would take
    // `sign(s)` for a constant. `s` must appear only under sums, products and integer powers.
    if !algebraic_in(e, s) {
        return None;
    }
    let a = diff(e, s).ok()?;
    if a.contains(s) {
        return None;
    }
    let b = subst(e, &mut |t| (t == s).then(Expr::zero));
    Some((a, b))
}

/// True when `s` appears in `e` only under sums, products and integer powers.
fn algebraic_in(e: &Expr, s: Sym) -> bool {
    let x = s.symbol();
    let mut holds: ExprMap<bool> = ExprMap::default();
    for n in post_order(std::slice::from_ref(e)) {
        let has = |c: &Expr| holds.get(c).copied().unwrap_or(false);
        let (contains, ok) = match n.node() {
            Node::Const(_) => (false, true),
            Node::Sym(t) => (*t == x, true),
            Node::Add(xs) | Node::Mul(xs) => (xs.iter().any(has), true),
            Node::Pow(b, p) => {
                let integer = p.as_const().is_some_and(|v| v.fract() == 0.0);
                (has(b) || has(p), !has(p) && (!has(b) || integer))
            }
            Node::Call(_, xs) => {
                let any = xs.iter().any(has);
                (any, !any)
            }
        };
        if !ok {
            return false;
        }
        holds.insert(n, contains);
    }
    true
}

/// Products of sums multiplied out (`a (b + c)` → `a b + a c`) through sums and products, except a product that
/// would make more than 64 terms, which stays as it is.
pub fn expand(e: &Expr) -> Expr {
    Expander::default().expand(e)
}

/// True when a product with a sum among its factors is reachable through sums and products (what [`expand`]
/// multiplies out). A walk of the tree: for small expressions only.
fn has_product_of_sum(e: &Expr) -> bool {
    let mut stack = vec![e];
    while let Some(n) = stack.pop() {
        match n.node() {
            Node::Add(ts) => stack.extend(ts),
            Node::Mul(fs) => {
                if fs.iter().any(|f| matches!(f.node(), Node::Add(_))) {
                    return true;
                }
                stack.extend(fs);
            }
            _ => {}
        }
    }
    false
}

/// Products whose expansion would have more terms than this are left as they are.
const MAX_TERMS: usize = 64;

/// The remembered expansions hold at most this many entries; the memory starts over beyond it.
const MEMO_MAX: usize = 1 << 20;

/// Multiplies out products of sums, remembering the expansion of every node it met: a value held inside the next
/// one (as along a chain of elements) is looked up, not expanded again. The result is that of expanding from
/// scratch: the expansion of a node does not depend on where it sits.
#[derive(Default)]
pub struct Expander {
    memo: ExprMap<Expr>,
}

impl Expander {
    pub fn expand(&mut self, e: &Expr) -> Expr {
        if e.node_count() <= SMALL && !has_product_of_sum(e) {
            // Nothing to multiply out (most values): no need to remember anything.
            return e.clone();
        }
        if self.memo.len() > MEMO_MAX {
            self.memo.clear();
        }
        // Only sums and products are descended into; anything else is kept as it is.
        let mut stack: Vec<(Expr, bool)> = vec![(e.clone(), false)];
        while let Some((n, children_done)) = stack.pop() {
            if self.memo.contains_key(&n) {
                continue;
            }
            let items = match n.node() {
                Node::Add(xs) | Node::Mul(xs) => xs,
                _ => {
                    self.memo.insert(n.clone(), n);
                    continue;
                }
            };
            if !children_done {
                let pending: Vec<Expr> = items
                    .iter()
                    .filter(|c| !self.memo.contains_key(*c))
                    .cloned()
                    .collect();
                stack.push((n.clone(), true));
                stack.extend(pending.into_iter().map(|c| (c, false)));
                continue;
            }
            let out = self.combine(&n);
            self.memo.insert(n, out);
        }
        self.memo.get(e).cloned().unwrap_or_else(|| e.clone())
    }

    /// The expansion of a sum or product whose children are expanded: one flat sum, however long (the engine
    /// keeps a long sum whole inside another, which would keep its terms from meeting their like terms here).
    fn combine(&self, n: &Expr) -> Expr {
        let get = |c: &Expr| self.memo.get(c).cloned().unwrap_or_else(|| c.clone());
        match n.node() {
            Node::Add(ts) => {
                let mut terms = Vec::with_capacity(ts.len());
                ts.iter().for_each(|t| flat_terms(&get(t), 1.0, &mut terms));
                Expr::sum(terms)
            }
            Node::Mul(fs) => {
                let mut coeff = 1.0;
                let mut terms = vec![Expr::one()];
                for f in fs {
                    let f = get(f);
                    match f.node() {
                        Node::Const(c) => coeff *= c,
                        Node::Add(_) => {
                            let mut inner = Vec::new();
                            flat_terms(&f, 1.0, &mut inner);
                            if terms.len() * inner.len() > MAX_TERMS {
                                return n.clone();
                            }
                            terms = terms
                                .iter()
                                .flat_map(|t| inner.iter().map(move |i| t * i))
                                .collect();
                        }
                        _ => terms.iter_mut().for_each(|t| *t = &*t * &f),
                    }
                }
                let mut out = Vec::with_capacity(terms.len());
                terms.iter().for_each(|t| flat_terms(t, coeff, &mut out));
                Expr::sum(out)
            }
            _ => n.clone(),
        }
    }
}

/// The terms of `e` times `coeff`, through sums and numeric multiples of sums at any depth, appended to `out`.
fn flat_terms(e: &Expr, coeff: f64, out: &mut Vec<Expr>) {
    let mut stack = vec![(e.clone(), coeff)];
    while let Some((e, c)) = stack.pop() {
        match e.node() {
            Node::Add(ts) => stack.extend(ts.iter().rev().map(|t| (t.clone(), c))),
            Node::Mul(fs) => {
                if let [k, sum] = fs.as_slice()
                    && let (Some(k), Node::Add(_)) = (k.as_const(), sum.node())
                {
                    stack.push((sum.clone(), c * k));
                } else {
                    out.push(&e * c);
                }
            }
            _ => out.push(&e * c),
        }
    }
}

/// The states below `n` that `e` reads, each once, in increasing order.
pub fn states_read(e: &Expr, n: usize) -> Vec<usize> {
    let mut out: Vec<usize> = e
        .syms()
        .into_iter()
        .filter_map(|s| match s {
            Sym::State(k) if k < n => Some(k),
            _ => None,
        })
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x() -> Expr {
        Sym::Param(0).expr()
    }
    fn y() -> Expr {
        Sym::Param(1).expr()
    }

    #[test]
    fn symbols_carry_the_stage_identity() {
        for s in [
            Sym::Param(0),
            Sym::Input(12),
            Sym::InputDot(3),
            Sym::State(105),
            Sym::StateDot(7),
            Sym::Var(40),
            Sym::Tear(2),
            Sym::Output(9),
            Sym::Time,
        ] {
            assert_eq!(Sym::of(&s.symbol()), Some(s));
            assert_eq!(s.expr().as_sym(), Some(s));
        }
        assert_ne!(Sym::Var(1).expr(), Sym::Tear(1).expr());
    }

    /// A row that reads more than `WIDE_ROW` symbols is differentiated in one reverse-mode walk: the same values as
    /// symbol by symbol, and a switch over one of them is refused alike.
    #[test]
    fn the_gradient_of_a_wide_row_is_that_of_each_symbol() {
        let n = WIDE_ROW + 36;
        let v = |k: usize| Sym::Tear(k).expr();
        // r = Σ_k (k + 1) z_k z_{k+1} + sin(z_0 z_{n−1}) / (1 + z_3²): products, a sum, a call and a quotient.
        let mut terms: Vec<Expr> = (0..n - 1)
            .map(|k| mul(vec![num((k + 1) as f64), v(k), v(k + 1)]))
            .collect();
        terms.push(div(
            call(Func::Sin, vec![mul(vec![v(0), v(n - 1)])]),
            add(vec![num(1.0), pow(v(3), num(2.0))]),
        ));
        let r = add(terms);
        let wrt: Vec<Sym> = (0..n).map(Sym::Tear).collect();
        let wide = gradient(&r, &wrt).unwrap_or_default();
        assert_eq!(wide.len(), n);
        let at = |s: Sym| match s {
            Sym::Tear(k) => Some(0.3 + 0.01 * k as f64),
            _ => None,
        };
        for (k, d) in wide.iter().enumerate() {
            let one = diff(&r, Sym::Tear(k)).unwrap_or_else(|_| Expr::zero());
            let (got, want) = match (eval(d, &at), eval(&one, &at)) {
                (Ok(got), Ok(want)) => (got, want),
                other => panic!("z_{k}: {other:?}"),
            };
            assert!(
                (got - want).abs() <= 1e-14 * want.abs().max(1.0),
                "z_{k}: {got} vs {want}"
            );
        }
        let switch = add(vec![r, call(Func::Max, vec![v(5), num(0.0)])]);
        assert_eq!(gradient(&switch, &wrt), Err(NotDifferentiable(Func::Max)));
    }

    #[test]
    fn derivatives_match_finite_differences() {
        // e = x^3 sin(x y) + exp(x)/y
        let e = add(vec![
            mul(vec![
                pow(x(), num(3.0)),
                call(Func::Sin, vec![mul(vec![x(), y()])]),
            ]),
            div(call(Func::Exp, vec![x()]), y()),
        ]);
        let d = diff(&e, Sym::Param(0)).unwrap_or_else(|_| Expr::zero());
        let at = |xv: f64| {
            move |s: Sym| match s {
                Sym::Param(0) => Some(xv),
                Sym::Param(1) => Some(0.7),
                _ => None,
            }
        };
        let h = 1e-6;
        let fd = (eval(&e, &at(1.3 + h)).unwrap_or(0.0) - eval(&e, &at(1.3 - h)).unwrap_or(0.0))
            / (2.0 * h);
        let exact = eval(&d, &at(1.3)).unwrap_or(f64::NAN);
        assert!(
            (fd - exact).abs() < 1e-6 * exact.abs().max(1.0),
            "{fd} vs {exact}"
        );
        // A switch is not differentiated.
        let switch = call(Func::Max, vec![x(), y()]);
        assert_eq!(
            diff(&switch, Sym::Param(0)),
            Err(NotDifferentiable(Func::Max))
        );
    }

    #[test]
    fn remembered_expansions_are_those_from_scratch() {
        let n = add(vec![
            Expr::one(),
            mul(vec![num(0.1), call(Func::Cos, vec![x()])]),
        ]);
        let mut expander = Expander::default();
        let mut value = y();
        for k in 0..12 {
            let term = mul(vec![num(f64::from(k)), call(Func::Sin, vec![x()]), y()]);
            value = add(vec![term, mul(vec![n.clone(), value])]);
            let remembered = expander.expand(&value);
            assert_eq!(remembered, expand(&value), "level {k}");
            assert_eq!(expander.expand(&value), remembered, "level {k}");
        }
        // (x + 1)(y + 2) = x y + 2 x + y + 2
        let product = mul(vec![add(vec![x(), num(1.0)]), add(vec![y(), num(2.0)])]);
        let expected = add(vec![
            mul(vec![x(), y()]),
            mul(vec![num(2.0), x()]),
            y(),
            num(2.0),
        ]);
        assert_eq!(expand(&product), expected);
    }

    #[test]
    fn affine_split() {
        let e = add(vec![mul(vec![x(), y()]), num(3.0)]);
        let (a, b) = affine_in(&e, Sym::Param(0)).unwrap_or((Expr::zero(), Expr::zero()));
        assert_eq!(a, y());
        assert_eq!(b, num(3.0));
        assert!(affine_in(&pow(x(), num(2.0)), Sym::Param(0)).is_none());
        // sign(x) has a zero derivative but is not affine.
        let coulomb = add(vec![call(Func::Sign, vec![x()]), mul(vec![y(), x()])]);
        assert!(affine_in(&coulomb, Sym::Param(0)).is_none());
    }
}
