//! The expression type: shared immutable nodes, structural equality and hashing, and the canonical total order.
//!
//! An [`Expr`] is an `Arc` to an immutable node that also caches a structural hash, so cloning is a reference-count
//! increment, equality between different expressions is usually decided by the hash alone, and expressions can be
//! sent between threads. Nodes are only ever built by the simplifying constructors of `build.rs`, so every `Expr`
//! is in canonical form (see the invariants on [`Node`]).
//!
//! # The total order
//! Terms of sums and factors of products are sorted by [`Ord for Expr`](Expr#impl-Ord-for-Expr):
//! - constants come first, ordered by [`f64::total_cmp`];
//! - any other expression is seen as `coefficient × Π baseᵢ^expᵢ` (a product's own factors; `x^e` is one factor;
//!   anything else is one factor with exponent 1). Two expressions compare their factor lists lexicographically,
//!   each factor by base then exponent, then the shorter list first, then the coefficient.
//! - bases compare by kind (constant < symbol < call < sum < product < power), then structurally: symbols by
//!   [`Symbol`]'s order (kind, then name), calls by function then arguments, sums by their terms.
//!
//! So `x` < `x^2` < `x*y` < `y`, and `2*x` sits next to `x`: like terms are adjacent, which is what collection needs.

use crate::ir::Func;
use std::cmp::Ordering;
use std::fmt;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::Arc;

/// What a symbol stands for. The declaration order is the sort order, so in a product parameters come before
/// inputs, time and states (`k*q_spring`, not `q_spring*k`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SymbolKind {
    Param,
    Input,
    Time,
    State,
    Intermediate,
    Output,
}

/// A named variable of an expression. Two symbols are the same when both name and kind agree.
#[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Symbol {
    kind: SymbolKind,
    name: Arc<str>,
}

impl Symbol {
    pub fn new(name: impl Into<Arc<str>>, kind: SymbolKind) -> Symbol {
        Symbol {
            kind,
            name: name.into(),
        }
    }

    pub fn param(name: impl Into<Arc<str>>) -> Symbol {
        Symbol::new(name, SymbolKind::Param)
    }

    pub fn input(name: impl Into<Arc<str>>) -> Symbol {
        Symbol::new(name, SymbolKind::Input)
    }

    pub fn state(name: impl Into<Arc<str>>) -> Symbol {
        Symbol::new(name, SymbolKind::State)
    }

    pub fn intermediate(name: impl Into<Arc<str>>) -> Symbol {
        Symbol::new(name, SymbolKind::Intermediate)
    }

    pub fn output(name: impl Into<Arc<str>>) -> Symbol {
        Symbol::new(name, SymbolKind::Output)
    }

    /// Time, named `t`.
    pub fn time() -> Symbol {
        Symbol::new("t", SymbolKind::Time)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn kind(&self) -> SymbolKind {
        self.kind
    }
}

impl fmt::Debug for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{:?}", self.name, self.kind)
    }
}

impl fmt::Display for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)
    }
}

/// One node of a canonical expression. Read it with [`Expr::node`]; build expressions with the constructors of
/// [`Expr`] (which simplify), never from a `Node` directly.
///
/// Invariants of canonical form:
/// - `Const` is never `-0.0` (stored as `0.0`) and every NaN is the one `f64::NAN`.
/// - `Add` has at least two terms, no `Add` among them, at most one `Const` (first, non-zero), no two terms that
///   differ only by their numeric coefficient, and the terms are sorted.
/// - `Mul` has at least two factors, no `Mul` among them, at most one `Const` (first, neither 0 nor 1), no two
///   factors with the same base, the factors sorted, and it is never `c * (a + b)` (a numeric coefficient times a
///   single sum is distributed); a sum among its factors has a positive coefficient on its first non-constant
///   term.
/// - `Pow` has an exponent that is not 0 or 1; when the exponent is an integer constant the base is neither a product
///   nor a power (those are distributed / merged), and a sum base is normalised as in a product.
///   `sqrt(x)` is `Pow(x, 0.5)`.
/// - `Call` never has all-constant arguments (they are folded) and never has `Func::Sqrt`.
#[derive(Clone, Debug)]
pub enum Node {
    Const(f64),
    Sym(Symbol),
    Add(Vec<Expr>),
    Mul(Vec<Expr>),
    Pow(Expr, Expr),
    Call(Func, Vec<Expr>),
}

struct Inner {
    node: Node,
    hash: u64,
}

/// A canonical symbolic expression; cheap to clone (an `Arc`).
#[derive(Clone)]
pub struct Expr(Arc<Inner>);

impl Expr {
    /// Wraps a node that already satisfies the canonical invariants. Only the simplifying constructors call this.
    pub(super) fn from_canonical(node: Node) -> Expr {
        let node = match node {
            Node::Const(c) => Node::Const(normalize_const(c)),
            other => other,
        };
        let hash = structural_hash(&node);
        Expr(Arc::new(Inner { node, hash }))
    }

    /// The top node, for inspecting an expression.
    pub fn node(&self) -> &Node {
        &self.0.node
    }

    /// The value if this is a constant.
    pub fn as_const(&self) -> Option<f64> {
        match self.node() {
            Node::Const(c) => Some(*c),
            _ => None,
        }
    }

    /// The symbol if this is a bare symbol.
    pub fn as_symbol(&self) -> Option<&Symbol> {
        match self.node() {
            Node::Sym(s) => Some(s),
            _ => None,
        }
    }

    /// Exactly the constant 0.
    pub fn is_zero(&self) -> bool {
        self.as_const() == Some(0.0)
    }

    /// Exactly the constant 1.
    pub fn is_one(&self) -> bool {
        self.as_const() == Some(1.0)
    }

    /// Number of nodes in the tree (shared subtrees counted each time): a size measure for choosing pivots.
    pub fn node_count(&self) -> usize {
        1 + match self.node() {
            Node::Const(_) | Node::Sym(_) => 0,
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => {
                xs.iter().map(Expr::node_count).sum()
            }
            Node::Pow(b, e) => b.node_count() + e.node_count(),
        }
    }

    /// The numeric coefficient and the remaining factors: `3*x*y` → `(3, [x, y])`, `x` → `(1, [x])`.
    /// Not meaningful for constants (returns `(1, [c])`).
    pub(super) fn coeff_and_factors(&self) -> (f64, &[Expr]) {
        match self.node() {
            Node::Mul(fs) => match fs.split_first() {
                Some((first, rest)) => match first.as_const() {
                    Some(c) => (c, rest),
                    None => (1.0, fs),
                },
                None => (1.0, fs),
            },
            _ => (1.0, std::slice::from_ref(self)),
        }
    }

    /// `(base, exponent)` when this is a power with a visibly negative exponent (a negative constant, or a product
    /// with a negative coefficient): the printers put it in a denominator and evaluation divides by it.
    pub(super) fn negative_power(&self) -> Option<(&Expr, &Expr)> {
        let Node::Pow(b, e) = self.node() else {
            return None;
        };
        let negative = match e.node() {
            Node::Const(c) => *c < 0.0,
            Node::Mul(_) => e.coeff_and_factors().0 < 0.0,
            _ => false,
        };
        negative.then_some((b, e))
    }

    /// A factor as `(base, exponent)`; `None` means exponent 1.
    pub(super) fn base_exp(&self) -> (&Expr, Option<&Expr>) {
        match self.node() {
            Node::Pow(b, e) => (b, Some(e)),
            _ => (self, None),
        }
    }
}

fn normalize_const(c: f64) -> f64 {
    if c.is_nan() {
        f64::NAN
    } else if c == 0.0 {
        0.0
    } else {
        c
    }
}

fn structural_hash(node: &Node) -> u64 {
    // `DefaultHasher::new()` uses fixed keys, so hashes are the same in every run.
    let mut h = DefaultHasher::new();
    match node {
        Node::Const(c) => {
            0u8.hash(&mut h);
            c.to_bits().hash(&mut h);
        }
        Node::Sym(s) => {
            1u8.hash(&mut h);
            s.hash(&mut h);
        }
        Node::Add(xs) => {
            2u8.hash(&mut h);
            for x in xs {
                x.0.hash.hash(&mut h);
            }
        }
        Node::Mul(xs) => {
            3u8.hash(&mut h);
            for x in xs {
                x.0.hash.hash(&mut h);
            }
        }
        Node::Pow(b, e) => {
            4u8.hash(&mut h);
            b.0.hash.hash(&mut h);
            e.0.hash.hash(&mut h);
        }
        Node::Call(f, xs) => {
            5u8.hash(&mut h);
            f.hash(&mut h);
            for x in xs {
                x.0.hash.hash(&mut h);
            }
        }
    }
    h.finish()
}

impl PartialEq for Expr {
    fn eq(&self, other: &Expr) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
            || (self.0.hash == other.0.hash && self.cmp(other) == Ordering::Equal)
    }
}

impl Eq for Expr {}

impl Hash for Expr {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.0.hash.hash(state);
    }
}

impl PartialOrd for Expr {
    fn partial_cmp(&self, other: &Expr) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Expr {
    fn cmp(&self, other: &Expr) -> Ordering {
        if Arc::ptr_eq(&self.0, &other.0) {
            return Ordering::Equal;
        }
        match (self.node(), other.node()) {
            (Node::Const(a), Node::Const(b)) => a.total_cmp(b),
            (Node::Const(_), _) => Ordering::Less,
            (_, Node::Const(_)) => Ordering::Greater,
            _ => {
                let (ca, fa) = self.coeff_and_factors();
                let (cb, fb) = other.coeff_and_factors();
                fa.iter()
                    .zip(fb)
                    .map(|(x, y)| cmp_factor(x, y))
                    .find(|o| o.is_ne())
                    .unwrap_or_else(|| fa.len().cmp(&fb.len()))
                    .then_with(|| ca.total_cmp(&cb))
            }
        }
    }
}

fn cmp_factor(x: &Expr, y: &Expr) -> Ordering {
    let (bx, ex) = x.base_exp();
    let (by, ey) = y.base_exp();
    cmp_base(bx, by).then_with(|| match (ex, ey) {
        (None, None) => Ordering::Equal,
        (None, Some(e)) => cmp_with_one(e).reverse(),
        (Some(e), None) => cmp_with_one(e),
        (Some(a), Some(b)) => a.cmp(b),
    })
}

/// `e` compared with the constant 1.
fn cmp_with_one(e: &Expr) -> Ordering {
    match e.as_const() {
        Some(c) => c.total_cmp(&1.0),
        None => Ordering::Greater,
    }
}

fn rank(e: &Expr) -> u8 {
    match e.node() {
        Node::Const(_) => 0,
        Node::Sym(_) => 1,
        Node::Call(..) => 2,
        Node::Add(_) => 3,
        Node::Mul(_) => 4,
        Node::Pow(..) => 5,
    }
}

fn cmp_base(x: &Expr, y: &Expr) -> Ordering {
    rank(x)
        .cmp(&rank(y))
        .then_with(|| match (x.node(), y.node()) {
            (Node::Const(a), Node::Const(b)) => a.total_cmp(b),
            (Node::Sym(a), Node::Sym(b)) => a.cmp(b),
            (Node::Call(f, xs), Node::Call(g, ys)) => f.cmp(g).then_with(|| cmp_lists(xs, ys)),
            (Node::Add(xs), Node::Add(ys)) => cmp_lists(xs, ys),
            (Node::Mul(_), Node::Mul(_)) => x.cmp(y),
            (Node::Pow(b1, e1), Node::Pow(b2, e2)) => b1.cmp(b2).then_with(|| e1.cmp(e2)),
            _ => Ordering::Equal,
        })
}

fn cmp_lists(xs: &[Expr], ys: &[Expr]) -> Ordering {
    xs.iter()
        .zip(ys)
        .map(|(x, y)| x.cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or_else(|| xs.len().cmp(&ys.len()))
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expr({self})")
    }
}
