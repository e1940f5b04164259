//! Symbolic differentiation.
//!
//! Rules, with `u' = du/dx`:
//! - sums term by term; products by the product rule `Σᵢ fᵢ' Πⱼ≠ᵢ fⱼ`, or, with four or more factors that depend on
//!   `x`, one factor at a time over tails that products share (`product_derivative`);
//! - `(b^e)' = e b^(e-1) b'` when `e` does not depend on `x`, else `b^e (e' ln b + e b'/b)`;
//! - `sin' = cos`, `cos' = -sin`, `tan' = 1/cos²`, `asin' = 1/sqrt(1-u²)`, `acos' = -1/sqrt(1-u²)`,
//!   `atan' = 1/(1+u²)`, `atan2(y, x)' = (x y' - y x')/(x² + y²)`, `exp' = exp`, `ln' = 1/u`,
//!   `log10' = 1/(u ln 10)`, `tanh' = 1 - tanh²`, `sinh' = cosh`, `cosh' = sinh`;
//! - `abs(u)' = sign(u) u'` (at `u = 0` this gives 0, a subgradient);
//! - `sign(u)' = 0`: exact away from `u = 0`, where the true derivative does not exist;
//! - `min(a, b)' = (1 - s)/2 a' + (1 + s)/2 b'` and `max(a, b)' = (1 + s)/2 a' + (1 - s)/2 b'` with
//!   `s = sign(a - b)`: the derivative of the active argument, and the mean of both where `a = b`.

use super::dag::{Dag, Memo};
use super::expr::{Expr, ExprMap, Node, Symbol};
use crate::ir::Func;
use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::LN_10;

impl Expr {
    /// `d self / d x`, simplified. Each distinct node is differentiated once.
    pub fn diff(&self, x: &Symbol) -> Expr {
        diff_all(std::slice::from_ref(self), x, &mut ExprMap::default())
            .pop()
            .unwrap_or_else(Expr::zero)
    }

    /// `d self / d x` as [`Expr::diff`], with the derivatives of long products' tails kept in `tails` for later
    /// calls: a caller that differentiates many expressions one at a time (the time derivative of each storage in
    /// derivative causality) shares them as one call over all would.
    pub fn diff_sharing(&self, x: &Symbol, tails: &mut ProductTails) -> Expr {
        let one = std::slice::from_ref(self);
        if let Some(kept) = tails.0.get_mut(x) {
            return diff_all(one, x, kept).pop().unwrap_or_else(Expr::zero);
        }
        // A variable's map is kept once it holds a tail: most expressions have no long product, and a caller that
        // differentiates them one by one (a Jacobian row by row) then allocates nothing for it.
        let mut fresh = ExprMap::default();
        let d = diff_all(one, x, &mut fresh)
            .pop()
            .unwrap_or_else(Expr::zero);
        if !fresh.is_empty() {
            tails.0.insert(x.clone(), fresh);
        }
        d
    }

    /// The Jacobian `∂ exprsᵢ / ∂ varsⱼ`, row by row: the entries of [`Expr::sparse_jacobian`] with zeros
    /// elsewhere, so the work follows the non-zeros (only the zeros are written `rows × columns` times).
    pub fn jacobian(exprs: &[Expr], vars: &[Symbol]) -> Vec<Vec<Expr>> {
        let mut dense = vec![vec![Expr::zero(); vars.len()]; exprs.len()];
        for (i, j, entry) in Expr::sparse_jacobian(exprs, vars) {
            if let Some(slot) = dense.get_mut(i).and_then(|row| row.get_mut(j)) {
                *slot = entry;
            }
        }
        dense
    }

    /// The entries of the Jacobian `∂ exprsᵢ / ∂ varsⱼ` that are not the constant 0, as `(i, j, entry)` sorted by
    /// row then column. An expression is differentiated only by the variables it reads, and each variable is one
    /// walk over the rows that read it: the cost follows the non-zeros, not `exprs.len() * vars.len()`.
    pub fn sparse_jacobian(exprs: &[Expr], vars: &[Symbol]) -> Vec<(usize, usize, Expr)> {
        let mut columns: BTreeMap<&Symbol, Vec<usize>> = BTreeMap::new();
        for (j, v) in vars.iter().enumerate() {
            columns.entry(v).or_default().push(j);
        }
        let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); vars.len()];
        let mut out = Vec::new();
        for (i, read) in Expr::symbols_read(exprs).iter().enumerate() {
            let wrt: Vec<&Symbol> = read.iter().filter(|s| columns.contains_key(s)).collect();
            if wrt.len() > WIDE_ROW {
                // A row that reads many variables: its whole gradient in one walk of it.
                let Some(e) = exprs.get(i) else { continue };
                for (s, d) in wrt.iter().zip(gradient(e, &wrt)) {
                    for &j in columns.get(*s).into_iter().flatten() {
                        if !d.is_zero() {
                            out.push((i, j, d.clone()));
                        }
                    }
                }
                continue;
            }
            for j in wrt.iter().filter_map(|s| columns.get(*s)).flatten() {
                if let Some(rows) = rows_of.get_mut(*j) {
                    rows.push(i);
                }
            }
        }
        for ((j, v), rows) in vars.iter().enumerate().zip(&rows_of) {
            let picked: Vec<Expr> = rows.iter().filter_map(|&i| exprs.get(i).cloned()).collect();
            for (&i, d) in rows
                .iter()
                .zip(diff_all(&picked, v, &mut ExprMap::default()))
            {
                if !d.is_zero() {
                    out.push((i, j, d));
                }
            }
        }
        out.sort_by_key(|(i, j, _)| (*i, *j));
        out
    }

    /// `∂self/∂x` for each `x` of `wrt`, in one walk of `self` (reverse mode): what a row of more than
    /// [`WIDE_ROW`] variables costs in [`Expr::sparse_jacobian`], for a caller that has the variables at hand.
    pub fn gradient(&self, wrt: &[Symbol]) -> Vec<Expr> {
        gradient(self, &wrt.iter().collect::<Vec<_>>())
    }

    /// For each expression, the symbols it reads: one walk per expression over its distinct nodes.
    pub fn symbols_read(exprs: &[Expr]) -> Vec<BTreeSet<Symbol>> {
        exprs.iter().map(Expr::free_symbols).collect()
    }
}

/// Rows of a Jacobian that read more variables than this are differentiated in reverse mode (one walk for all of
/// the row's variables): by columns, each of the row's variables would walk the whole row, the square of its size
/// for a row that reads a variable in each of its terms (the rate of a mass held by many springs).
pub const WIDE_ROW: usize = 64;

/// `∂e/∂x` for each `x` of `wrt`, in one walk of `e` (reverse mode): each node's adjoint `∂e/∂node` is the sum,
/// over the nodes that hold it, of their adjoints times their partial derivative by it; a variable's derivative is
/// its node's adjoint. Only the nodes that read one of `wrt` get an adjoint.
fn gradient(e: &Expr, wrt: &[&Symbol]) -> Vec<Expr> {
    let dag = Dag::new([e]);
    let wanted: BTreeSet<&Symbol> = wrt.iter().copied().collect();
    let index = |c: &Expr| dag.index(c);
    let reads = dag.reading(|s| wanted.contains(s));
    let mut parts: Vec<Vec<Expr>> = vec![Vec::new(); dag.len()];
    if let Some(root) = index(e) {
        parts[root].push(Expr::one());
    }
    let mut of_symbol: BTreeMap<&Symbol, Expr> = BTreeMap::new();
    // Post-order puts every node after the nodes it holds: backwards, a node's adjoint is complete when reached.
    for i in (0..dag.len()).rev() {
        if !reads[i] || parts[i].is_empty() {
            continue;
        }
        let adjoint = Expr::sum(std::mem::take(&mut parts[i]));
        let n = dag.order[i];
        if let Some(s) = n.as_symbol() {
            of_symbol.insert(s, adjoint);
            continue;
        }
        if adjoint.is_zero() {
            continue;
        }
        let mut seen: Vec<&Expr> = Vec::new();
        n.node().for_each_child(|c| {
            if seen.iter().any(|s| s.same_node(c)) {
                return;
            }
            seen.push(c);
            if let Some(k) = index(c).filter(|&k| reads[k]) {
                parts[k].push(&adjoint * partial(n, c));
            }
        });
    }
    wrt.iter()
        .map(|s| of_symbol.get(s).cloned().unwrap_or_else(Expr::zero))
        .collect()
}

/// `∂n/∂c` for a node `n` and one of its children `c` (every occurrence of it).
fn partial(n: &Expr, c: &Expr) -> Expr {
    match n.node() {
        // The terms of a sum and the factors of a product are distinct, so `c` is one of them: a sum's partial is
        // 1 and a product's the other factors, without the product rule's walk of every term or factor (which
        // made a long sum's gradient cost the square of its length).
        Node::Add(_) => return Expr::one(),
        Node::Mul(fs) => return Expr::product(fs.iter().filter(|f| !f.same_node(c)).cloned()),
        _ => {}
    }
    // `diff_node` reads its variable only at a symbol, and `n` holds a child: any symbol serves, made once.
    static UNUSED: std::sync::LazyLock<Symbol> = std::sync::LazyLock::new(Symbol::time);
    diff_node(n, &UNUSED, &|u| u.same_node(c), &|u| {
        if u.same_node(c) {
            Expr::one()
        } else {
            Expr::zero()
        }
    })
}

/// `d e / d x` for each `e` of `exprs`, over one walk of their nodes: first which nodes depend on `x`, then the
/// derivative of each of those from its children's.
fn diff_all(exprs: &[Expr], x: &Symbol, tails: &mut ExprMap<Expr>) -> Vec<Expr> {
    let dag = Dag::new(exprs);
    let depends = dag.reading(|s| s == x);
    let mut memo: Memo<Expr> = Memo::new(&dag);
    for (i, e) in dag.order.iter().enumerate() {
        if !depends.get(i).copied().unwrap_or(false) {
            continue;
        }
        let dep = |u: &Expr| {
            dag.index(u)
                .and_then(|k| depends.get(k))
                .copied()
                .unwrap_or(false)
        };
        let d = |u: &Expr| memo.get(u).cloned().unwrap_or_else(Expr::zero);
        let derivative = match e.node() {
            Node::Mul(factors) if factors.iter().filter(|f| dep(f)).count() >= PEEL_FACTORS => {
                product_derivative(factors, &dep, &d, tails)
            }
            _ => diff_node(e, x, &dep, &d),
        };
        memo.set(i, derivative);
    }
    exprs
        .iter()
        .map(|e| memo.get(e).cloned().unwrap_or_else(Expr::zero))
        .collect()
}

/// The derivatives of the tails of long products by each variable, kept between calls of [`Expr::diff_sharing`]: a
/// product of four or more factors `gᵢ` that vary with the variable is differentiated one factor at a time,
/// `d(gᵢ Tᵢ₊₁) = dgᵢ · Tᵢ₊₁ + gᵢ · dTᵢ₊₁`, and products with a common tail `Tᵢ₊₁` share its derivative.
#[derive(Default)]
pub struct ProductTails(BTreeMap<Symbol, ExprMap<Expr>>);

/// Products with at least this many factors that depend on the variable are differentiated one factor at a time
/// ([`product_derivative`]). Shorter products keep the flat rule, whose sum of products reads as a textbook writes
/// it; the nested form pays only where products are long (no model of the repository has one of four varying
/// factors in its printed equations or its generated code).
const PEEL_FACTORS: usize = 4;

/// `d(c · g₁ g₂ ⋯ gₘ)` for the factors `gᵢ` that depend on the variable (in canonical order) and the others `c`:
/// `c · dT₁` with the tails `Tᵢ = gᵢ Tᵢ₊₁`, `dTᵢ = dgᵢ · Tᵢ₊₁ + gᵢ · dTᵢ₊₁`. The flat rule `Σᵢ dgᵢ Πⱼ≠ᵢ gⱼ` writes
/// `m` products of `m` factors for each product and shares nothing; the tails are nodes of their own, and their
/// derivatives are kept in `tails`, so products with a common tail (the flows along a chain of modulated
/// transformers, `v_k = n_{k+1} v_{k+1}`, whose moduli all vary with one angle) share its derivative. The tails
/// are looked up from the longest: a product whose first tail is known costs one tail, not all of them.
fn product_derivative(
    factors: &[Expr],
    depends: &dyn Fn(&Expr) -> bool,
    d: &dyn Fn(&Expr) -> Expr,
    tails: &mut ExprMap<Expr>,
) -> Expr {
    let (varying, constant): (Vec<&Expr>, Vec<&Expr>) = factors.iter().partition(|f| depends(f));
    let tail = |i: usize| Expr::product(varying.iter().skip(i).map(|g| (*g).clone()));
    // Down the tails to the first whose derivative is known (or the last factor alone), then back up.
    let mut opened = Vec::new();
    let mut i = 0;
    let mut t = tail(0);
    let mut dt = loop {
        if let Some(known) = tails.get(&t) {
            break known.clone();
        }
        match varying.get(i) {
            Some(g) if i + 1 == varying.len() => break d(g),
            Some(_) => {
                let next = tail(i + 1);
                opened.push((i, std::mem::replace(&mut t, next)));
                i += 1;
            }
            None => break Expr::zero(),
        }
    };
    while let Some((k, whole)) = opened.pop() {
        let Some(g) = varying.get(k) else { break };
        dt = d(g) * &t + *g * &dt;
        tails.insert(whole.clone(), dt.clone());
        t = whole;
    }
    Expr::product(constant.into_iter().cloned().chain(std::iter::once(dt)))
}

/// The derivative of the node `e`, given which children depend on `x` and their derivatives.
fn diff_node(
    e: &Expr,
    x: &Symbol,
    depends: &dyn Fn(&Expr) -> bool,
    d: &dyn Fn(&Expr) -> Expr,
) -> Expr {
    match e.node() {
        Node::Const(_) => Expr::zero(),
        Node::Sym(s) => Expr::constant(if s == x { 1.0 } else { 0.0 }),
        Node::Add(terms) => Expr::sum(terms.iter().map(d)),
        Node::Mul(factors) => Expr::sum((0..factors.len()).map(|i| {
            Expr::product(
                factors
                    .iter()
                    .enumerate()
                    .map(|(j, f)| if i == j { d(f) } else { f.clone() }),
            )
        })),
        Node::Pow(b, ex) => {
            if depends(ex) {
                e * (d(ex) * b.ln() + ex * d(b) / b)
            } else {
                ex * b.pow(&(ex - 1.0)) * d(b)
            }
        }
        Node::Call(func, args) => diff_call(*func, args, d),
    }
}

fn diff_call(func: Func, args: &[Expr], d: &dyn Fn(&Expr) -> Expr) -> Expr {
    let zero = Expr::zero();
    let u = args.first().unwrap_or(&zero);
    let v = args.get(1).unwrap_or(&zero);
    let du = d(u);
    match func {
        Func::Sin => u.cos() * du,
        Func::Cos => -(u.sin() * du),
        Func::Tan => du * u.cos().powi(-2),
        Func::Asin => du * (1.0 - u.powi(2)).pow(&Expr::constant(-0.5)),
        Func::Acos => -(du * (1.0 - u.powi(2)).pow(&Expr::constant(-0.5))),
        Func::Atan => du / (1.0 + u.powi(2)),
        Func::Atan2 => (v * du - u * d(v)) / (u.powi(2) + v.powi(2)),
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
            wu * du + wv * d(v)
        }
        Func::Tanh => du * (1.0 - u.tanh().powi(2)),
        Func::Sinh => u.cosh() * du,
        Func::Cosh => u.sinh() * du,
    }
}
