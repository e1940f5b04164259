//! The expression type: nodes shared by hash-consing, identity equality, structural hashing, and freeing without
//! recursion.
//!
//! An [`Expr`] is an `Arc` to an immutable node in the hash-consing table (`intern.rs`): equal expressions are one
//! node, so equality is a pointer comparison, cloning is a reference-count increment, and a subexpression used in
//! many places is stored once. Each node caches its structural hash (the same in every run, so that hash maps of
//! expressions iterate alike) and its size as a tree. Nodes are only ever built by the simplifying constructors of
//! `build.rs`, so every `Expr` is in canonical form (see the invariants on [`Node`]); the canonical order of terms
//! and factors is in `order.rs`.
//!
//! Expressions are `Send + Sync` and can be built from any thread: the table is process-wide.

use super::intern::intern;
use crate::ir::Func;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, LazyLock};

/// What a symbol stands for. The declaration order is the sort order, so in a product parameters come before
/// inputs, time and states (`k*q_spring`, not `q_spring*k`).
///
/// The last three kinds are the equations stage's unknowns while it derives: the tear variable of a nonlinear
/// algebraic loop, and the time derivatives of states and inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SymbolKind {
    Param,
    Input,
    Time,
    State,
    Intermediate,
    Output,
    Tear,
    StateRate,
    InputRate,
}

/// A variable of an expression: a kind and either a name, or an index into a table of its kind that its user keeps
/// (the equations stage numbers its parameters, states, bond variables, ... and names them when it prints).
/// Two symbols are the same when kind, name and index agree; they sort by kind, then name, then index.
///
/// A symbol is three words, not five: every node of every expression holds one, so its size is the size of the
/// hash-consing table. The kind and the index share a word (`packed`).
#[derive(Clone)]
pub struct Symbol {
    name: Arc<str>,
    /// The kind in the top byte; below it the index plus one, or zero for a named symbol.
    packed: u64,
}

/// Bits of `Symbol::packed` below the kind.
const INDEX_BITS: u32 = 56;
const INDEX_MASK: u64 = (1 << INDEX_BITS) - 1;

/// The kinds in declaration order, so that a kind comes back from its number.
const KINDS: [SymbolKind; 9] = [
    SymbolKind::Param,
    SymbolKind::Input,
    SymbolKind::Time,
    SymbolKind::State,
    SymbolKind::Intermediate,
    SymbolKind::Output,
    SymbolKind::Tear,
    SymbolKind::StateRate,
    SymbolKind::InputRate,
];

// `KINDS[k as usize]` is `k`.
const _: () = {
    let mut i = 0;
    while i < KINDS.len() {
        assert!(KINDS[i] as usize == i);
        i += 1;
    }
};

impl Symbol {
    /// The largest index of a symbol made by [`Symbol::indexed`] (2^56 − 2).
    pub const MAX_INDEX: usize = (INDEX_MASK - 1) as usize;

    pub fn new(name: impl Into<Arc<str>>, kind: SymbolKind) -> Symbol {
        Symbol {
            name: name.into(),
            packed: (kind as u64) << INDEX_BITS,
        }
    }

    /// The symbol numbered `index` among those of `kind`, without a name (it prints as `kind#index`, so its user
    /// prints it with its own names, e.g. through [`crate::symbolic::to_text_with`]).
    ///
    /// The index is at most [`Symbol::MAX_INDEX`]: a position in a table its user holds in memory is below 2^48
    /// (the address space), and a placeholder index beyond every table is `MAX_INDEX` itself.
    pub fn indexed(kind: SymbolKind, index: usize) -> Symbol {
        static EMPTY: LazyLock<Arc<str>> = LazyLock::new(|| Arc::from(""));
        debug_assert!(
            index <= Symbol::MAX_INDEX,
            "symbol index {index} out of range"
        );
        Symbol {
            name: EMPTY.clone(),
            packed: ((kind as u64) << INDEX_BITS) | ((index as u64 + 1) & INDEX_MASK),
        }
    }

    /// The index of a symbol made by [`Symbol::indexed`].
    pub fn index(&self) -> Option<usize> {
        match self.packed & INDEX_MASK {
            0 => None,
            plus_one => Some((plus_one - 1) as usize),
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
        KINDS[(self.packed >> INDEX_BITS) as usize]
    }
}

impl PartialEq for Symbol {
    fn eq(&self, other: &Symbol) -> bool {
        self.packed == other.packed && self.name == other.name
    }
}

impl Eq for Symbol {}

impl Hash for Symbol {
    /// The fields in the order and form of the unpacked symbol (kind, name, optional index), so that structural
    /// hashes, and with them the order of every map of expressions, do not depend on the packing.
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.kind().hash(state);
        self.name.hash(state);
        self.index().hash(state);
    }
}

impl PartialOrd for Symbol {
    fn partial_cmp(&self, other: &Symbol) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Symbol {
    fn cmp(&self, other: &Symbol) -> std::cmp::Ordering {
        (self.kind(), &self.name, self.index()).cmp(&(other.kind(), &other.name, other.index()))
    }
}

impl fmt::Debug for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.index() {
            Some(i) => write!(f, "{:?}#{i}", self.kind()),
            None => write!(f, "{}:{:?}", self.name, self.kind()),
        }
    }
}

impl fmt::Display for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.index() {
            Some(i) => write!(f, "{:?}#{i}", self.kind()),
            None => f.write_str(&self.name),
        }
    }
}

/// One node of a canonical expression. Read it with [`Expr::node`]; build expressions with the constructors of
/// [`Expr`] (which simplify), never from a `Node` directly.
///
/// Invariants of canonical form:
/// - `Const` is never `-0.0` (stored as `0.0`) and every NaN is the one `f64::NAN`.
/// - `Add` has at least two terms, no `Add` of at most `FLAT_SUM` (32) terms among them (longer ones stay whole),
///   at most one `Const` (first, non-zero), no two terms that differ only by their numeric coefficient, and the
///   terms are sorted.
/// - `Mul` has at least two factors, no `Mul` among them, at most one `Const` (first, neither 0 nor 1), no two
///   factors with the same base, the factors sorted, and it is never `c * (a + b)` for a sum of at most `FLAT_SUM`
///   terms (a numeric coefficient times such a single sum is distributed); a sum of at most `FLAT_SUM` terms among
///   its factors has a positive coefficient on its first non-constant term (a longer one keeps its sign, as it does
///   as a term of a sum, so that `S + S = 2*S`).
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

pub(super) struct Inner {
    pub(super) node: Node,
    pub(super) hash: u64,
    /// The number of nodes of the expression as a tree (shared subexpressions counted each time), saturating.
    pub(super) tree_size: u64,
}

/// A canonical symbolic expression: a handle to its node in the hash-consing table; cheap to clone (an `Arc`).
#[derive(Clone)]
pub struct Expr(Arc<Inner>);

impl Expr {
    /// The one node equal to `node`, which already satisfies the canonical invariants. Only the simplifying
    /// constructors call this.
    pub(super) fn from_canonical(node: Node) -> Expr {
        let node = match node {
            Node::Const(c) => match small_constant(c) {
                Some(e) => return e,
                None => Node::Const(normalize_const(c)),
            },
            other => other,
        };
        Expr::intern(node)
    }

    fn intern(node: Node) -> Expr {
        let hash = structural_hash(&node);
        let mut tree_size = 1u64;
        node.for_each_child(|c| tree_size = tree_size.saturating_add(c.0.tree_size));
        Expr(intern(node, hash, tree_size))
    }

    /// Whether both are the same node, i.e. (by hash-consing) equal expressions.
    pub(super) fn same_node(&self, other: &Expr) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// Two lists of the same nodes, in the same order.
    #[inline]
    pub(super) fn same_nodes(xs: &[Expr], ys: &[Expr]) -> bool {
        xs.len() == ys.len() && xs.iter().zip(ys).all(|(x, y)| x.same_node(y))
    }

    /// The node's address: an identity that lasts as long as the node.
    pub(super) fn address(&self) -> usize {
        Arc::as_ptr(&self.0) as usize
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

    /// Number of nodes in the tree (shared subtrees counted each time, saturating at `usize::MAX`): a size
    /// measure for choosing pivots. Kept in the node, so this costs nothing.
    pub fn node_count(&self) -> usize {
        usize::try_from(self.0.tree_size).unwrap_or(usize::MAX)
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

/// The multiples of ½ from −[`SMALL_CONSTANT_MAX`] to [`SMALL_CONSTANT_MAX`], interned once per process: the
/// signs, `2` of `q²/2` and `−1` of every division are built millions of times in a large model, and taking them
/// from here spares each a lock and a table probe.
const SMALL_CONSTANT_MAX: f64 = 8.0;

fn small_constant(c: f64) -> Option<Expr> {
    static TABLE: LazyLock<Vec<Expr>> = LazyLock::new(|| {
        let halves = (4.0 * SMALL_CONSTANT_MAX) as i32;
        (0..=halves)
            .map(|k| Expr::intern(Node::Const(f64::from(k - halves / 2) / 2.0)))
            .collect()
    });
    let twice = 2.0 * c;
    // `-0.0` is `0.0` here, as `normalize_const` makes it.
    if twice.fract() != 0.0 || c.abs() > SMALL_CONSTANT_MAX {
        return None;
    }
    let index = (twice + 2.0 * SMALL_CONSTANT_MAX) as usize;
    TABLE.get(index).cloned()
}

fn structural_hash(node: &Node) -> u64 {
    // A fixed mixing function: hashes are the same in every run. Children contribute their cached hashes, so this
    // is constant work per child.
    let mut h = Mixer::default();
    match node {
        Node::Const(c) => {
            h.word(0);
            h.word(c.to_bits());
        }
        Node::Sym(s) => {
            h.word(1);
            s.hash(&mut h);
        }
        Node::Add(xs) => {
            h.word(2);
            xs.iter().for_each(|x| h.word(x.0.hash));
        }
        Node::Mul(xs) => {
            h.word(3);
            xs.iter().for_each(|x| h.word(x.0.hash));
        }
        Node::Pow(b, e) => {
            h.word(4);
            h.word(b.0.hash);
            h.word(e.0.hash);
        }
        Node::Call(f, xs) => {
            h.word(5);
            f.hash(&mut h);
            xs.iter().for_each(|x| h.word(x.0.hash));
        }
    }
    h.finish()
}

/// A multiply-rotate hash over 64-bit words with a final avalanche, so that every bit of the result (the table's
/// shard is chosen by the top bits, its bucket by the low ones) depends on every input bit.
#[derive(Default)]
struct Mixer(u64);

impl Mixer {
    fn word(&mut self, w: u64) {
        self.0 = (self.0.rotate_left(26) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Hasher for Mixer {
    fn finish(&self) -> u64 {
        // The finaliser of MurmurHash3.
        let mut x = self.0;
        x ^= x >> 33;
        x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
        x ^= x >> 33;
        x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        x ^ (x >> 33)
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..chunk.len()].copy_from_slice(chunk);
            self.word(u64::from_le_bytes(w));
        }
    }

    fn write_u8(&mut self, v: u8) {
        self.word(u64::from(v));
    }

    fn write_u64(&mut self, v: u64) {
        self.word(v);
    }

    fn write_usize(&mut self, v: usize) {
        self.word(v as u64);
    }
}

impl PartialEq for Expr {
    /// Identity: hash-consing makes equal expressions one node.
    fn eq(&self, other: &Expr) -> bool {
        self.same_node(other)
    }
}

impl Eq for Expr {}

impl Hash for Expr {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.0.hash.hash(state);
    }
}

/// A map keyed by expressions that hashes each key by its structural hash as it is (already well mixed), not
/// again through `std`'s SipHash: the codegen and equation passes look up millions of nodes.
pub type ExprMap<V> = std::collections::HashMap<Expr, V, super::intern::PassThroughState>;

/// A set of expressions, hashed as [`ExprMap`] hashes its keys.
pub type ExprSet = std::collections::HashSet<Expr, super::intern::PassThroughState>;

impl Node {
    /// Calls `f` on each child, in order.
    pub(super) fn for_each_child<'a>(&'a self, mut f: impl FnMut(&'a Expr)) {
        match self {
            Node::Const(_) | Node::Sym(_) => {}
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => xs.iter().for_each(f),
            Node::Pow(b, e) => {
                f(b);
                f(e);
            }
        }
    }

    /// The `i`-th child.
    pub(super) fn child(&self, i: usize) -> Option<&Expr> {
        match self {
            Node::Const(_) | Node::Sym(_) => None,
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => xs.get(i),
            Node::Pow(b, e) => match i {
                0 => Some(b),
                1 => Some(e),
                _ => None,
            },
        }
    }

    /// Moves the children out, leaving a leaf.
    fn take_children(&mut self, out: &mut Vec<Expr>) {
        match std::mem::replace(self, Node::Const(0.0)) {
            Node::Const(_) | Node::Sym(_) => {}
            Node::Add(xs) | Node::Mul(xs) | Node::Call(_, xs) => out.extend(xs),
            Node::Pow(b, e) => {
                out.push(b);
                out.push(e);
            }
        }
    }
}

impl Drop for Inner {
    /// Frees the nodes only this one kept alive with a work list, not by recursion, so that dropping a deep
    /// expression cannot overflow the stack.
    fn drop(&mut self) {
        if matches!(self.node, Node::Const(_) | Node::Sym(_)) {
            return;
        }
        let mut pending = Vec::new();
        self.node.take_children(&mut pending);
        while let Some(e) = pending.pop() {
            if let Some(mut inner) = Arc::into_inner(e.0) {
                inner.node.take_children(&mut pending);
            }
        }
    }
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expr({self})")
    }
}
