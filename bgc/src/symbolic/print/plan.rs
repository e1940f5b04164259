//! Which nodes a printer prints ahead of their users and keeps: the printing side of memoisation.
//!
//! A printer walks an expression top-down, which costs a recursion level per level of nesting and prints a shared
//! subexpression once per use. So before printing, the nodes are walked bottom-up (post-order, on an explicit
//! stack) and some are printed and kept:
//! - every node used more than once, which is then printed once and its text reused (a rope node, or a copy of the
//!   Rust code tree, whose size is that of the output anyway);
//! - on each path, at least every [`SPACING`]-th node, so that printing anything recurses at most about
//!   [`SPACING`] levels before it meets a kept node.
//!
//! Products with a negative coefficient and powers with a negative exponent are never kept: the printers print them
//! through a derived form (`-e`, `b^(-x)`) that reads their children directly. Counting, in the same way, how often
//! each kept node will be read tells whether its printed form can be moved into its one reader rather than copied,
//! which keeps printing a deep expression linear in the size of its text.

use super::super::dag::Dag;
use super::super::expr::{Expr, Node};
use super::super::intern::PassThroughState;
use super::negated;
use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

/// Nodes between kept ones on any path, at most.
pub(super) const SPACING: u32 = 16;

/// Expressions of at most this many nodes as a tree are printed straight through: printing them whole costs no
/// more than planning, and keeping changes only how the text is built, never the text.
const SMALL_TREE: usize = SPACING as usize;

/// The nodes to print ahead, in post-order, each with whether it is read more than once.
pub(super) fn plan(root: &Expr) -> Vec<(&Expr, bool)> {
    if root.node_count() <= SMALL_TREE {
        return Vec::new();
    }
    let dag = Dag::new([root]);
    let n = dag.len();
    let mut parents = vec![0u32; n];
    for e in &dag.order {
        e.node().for_each_child(|c| {
            if let Some(slot) = dag.index(c).and_then(|k| parents.get_mut(k)) {
                *slot += 1;
            }
        });
    }
    // Bottom-up: levels since the last kept node below, and the decision.
    let mut kept = vec![false; n];
    let mut unkept_height = vec![0u32; n];
    for (i, e) in dag.order.iter().enumerate() {
        let mut h = 0;
        e.node().for_each_child(|c| {
            if let Some(k) = dag.index(c) {
                let below = if kept.get(k).copied().unwrap_or(false) {
                    0
                } else {
                    unkept_height.get(k).copied().unwrap_or(0)
                };
                h = h.max(below + 1);
            }
        });
        let eligible = printed_directly(e);
        let shared = parents.get(i).copied().unwrap_or(0) > 1;
        if let (Some(k), Some(u)) = (kept.get_mut(i), unkept_height.get_mut(i)) {
            *k = eligible && (shared || h >= SPACING);
            *u = h;
        }
    }
    // Top-down: how often each node is read (a kept node prints once; another as often as it is read).
    let mut reads = vec![0u64; n];
    if let Some(last) = reads.last_mut() {
        *last = 1;
    }
    for (i, e) in dag.order.iter().enumerate().rev() {
        let runs = if kept.get(i).copied().unwrap_or(false) {
            1
        } else {
            reads.get(i).copied().unwrap_or(0)
        };
        e.node().for_each_child(|c| {
            if let Some(slot) = dag.index(c).and_then(|k| reads.get_mut(k)) {
                *slot = slot.saturating_add(runs);
            }
        });
    }
    dag.order
        .iter()
        .enumerate()
        .filter(|(i, _)| kept.get(*i).copied().unwrap_or(false))
        .map(|(i, e)| (*e, reads.get(i).copied().unwrap_or(0) > 1))
        .collect()
}

/// Whether printers print the node itself (not a derived form of it) and it is worth keeping.
fn printed_directly(e: &Expr) -> bool {
    match e.node() {
        Node::Const(_) | Node::Sym(_) => false,
        Node::Mul(_) => negated(e).is_none(),
        Node::Pow(..) => e.negative_power().is_none(),
        Node::Add(_) | Node::Call(..) => true,
    }
}

/// A printed form and how a kept copy of it is stored and read back.
pub(in crate::symbolic) trait Keep: Sized {
    type Stored;
    fn store(self) -> Self::Stored;
    /// A copy for one of several readers.
    fn reuse(stored: &Self::Stored) -> Self;
    /// The form itself, for its last reader.
    fn take(stored: Self::Stored) -> Self;
}

impl Keep for super::doc::Doc {
    type Stored = Rc<super::doc::Doc>;
    fn store(self) -> Rc<super::doc::Doc> {
        Rc::new(self)
    }
    fn reuse(stored: &Rc<super::doc::Doc>) -> Self {
        super::doc::Doc::shared(stored)
    }
    fn take(stored: Rc<super::doc::Doc>) -> Self {
        Rc::try_unwrap(stored).unwrap_or_else(|rc| super::doc::Doc::shared(&rc))
    }
}

struct Entry<S> {
    stored: S,
    strength: u8,
    reused: bool,
}

/// The printed forms of the kept nodes, with their binding strengths.
pub(in crate::symbolic) struct Kept<T: Keep> {
    entries: RefCell<HashMap<usize, Entry<T::Stored>, PassThroughState>>,
}

impl<T: Keep> Kept<T> {
    pub fn new() -> Kept<T> {
        Kept {
            entries: RefCell::new(HashMap::default()),
        }
    }

    pub fn insert(&self, e: &Expr, printed: (T, u8), reused: bool) {
        self.entries.borrow_mut().insert(
            e.address(),
            Entry {
                stored: printed.0.store(),
                strength: printed.1,
                reused,
            },
        );
    }

    /// The kept form of `e`, if any: a copy when it has several readers, else the form itself.
    pub fn fetch(&self, e: &Expr) -> Option<(T, u8)> {
        let mut entries = self.entries.borrow_mut();
        let entry = entries.get(&e.address())?;
        if entry.reused {
            return Some((T::reuse(&entry.stored), entry.strength));
        }
        let entry = entries.remove(&e.address())?;
        Some((T::take(entry.stored), entry.strength))
    }
}
