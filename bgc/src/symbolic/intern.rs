//! The hash-consing table: one node per distinct expression.
//!
//! Every node is built through [`intern`], which looks the node up by its structural hash and returns the node
//! already built when one with the same operation and the same (identical) children exists. Children are interned
//! before their parents, so comparing a candidate with a stored node is shallow: the operation, the constant or
//! symbol, and the identity of each child. Equal expressions are therefore one node, and equality is identity.
//!
//! The table is process-wide, so that expressions need no context threaded through every call and stay
//! `Send + Sync`; it holds weak references, so it never keeps an expression alive. It is split into shards by hash,
//! each behind its own mutex, to keep threads that build expressions at once from queueing on one lock. Entries of
//! nodes that died are swept when a shard has doubled since its last sweep, which keeps the table within a constant
//! factor of the live nodes at amortised constant cost per insertion.
//!
//! Nothing here runs user code or drops a node while a shard is locked: a node found in the table is returned, and
//! the candidate (holding only clones of children that the caller also holds) is dropped after the lock is released.

use super::expr::{Inner, Node};
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::{Arc, LazyLock, Mutex, PoisonError, Weak};

const SHARDS: usize = 16;

/// Entries a shard may hold before its first sweep.
const MIN_SWEEP: usize = 1024;

/// A hasher for keys that are already well-mixed 64-bit hashes: it passes them through.
#[derive(Default)]
pub(super) struct PassThrough(u64);

impl Hasher for PassThrough {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        // Only reached for keys other than `u64`/`usize`: fold the bytes in (FNV-1a).
        for b in bytes {
            self.0 = (self.0 ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = v;
    }

    fn write_usize(&mut self, v: usize) {
        // Addresses: spread the low bits (alignment zeros) over the whole word.
        self.0 = (v as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

pub(super) type PassThroughState = BuildHasherDefault<PassThrough>;

/// The nodes with one structural hash: almost always one.
enum Bucket {
    One(Weak<Inner>),
    Many(Vec<Weak<Inner>>),
}

#[derive(Default)]
struct Shard {
    map: HashMap<u64, Bucket, PassThroughState>,
    entries: usize,
    sweep_at: usize,
}

impl Shard {
    /// The live node equal to `node` under `hash` with the candidate handed back (to be dropped by the caller), or
    /// the candidate made a node and recorded under `hash`: one probe of the map either way.
    fn find_or_insert(
        &mut self,
        hash: u64,
        node: Node,
        tree_size: u64,
    ) -> (Arc<Inner>, Option<Node>) {
        let matches = |w: &Weak<Inner>| w.upgrade().filter(|a| shallow_eq(&a.node, &node));
        let fresh = |node| {
            Arc::new(Inner {
                node,
                hash,
                tree_size,
            })
        };
        let made = match self.map.entry(hash) {
            Entry::Vacant(slot) => {
                let made = fresh(node);
                slot.insert(Bucket::One(Arc::downgrade(&made)));
                made
            }
            Entry::Occupied(mut slot) => {
                let bucket = slot.get_mut();
                let found = match bucket {
                    Bucket::One(w) => matches(w),
                    Bucket::Many(ws) => ws.iter().find_map(matches),
                };
                if let Some(found) = found {
                    return (found, Some(node));
                }
                let made = fresh(node);
                let weak = Arc::downgrade(&made);
                match bucket {
                    Bucket::One(old) if old.strong_count() == 0 => *old = weak,
                    Bucket::One(old) => *bucket = Bucket::Many(vec![old.clone(), weak]),
                    Bucket::Many(ws) => {
                        ws.retain(|w| w.strong_count() > 0);
                        ws.push(weak);
                    }
                }
                made
            }
        };
        self.entries += 1;
        if self.entries >= self.sweep_at.max(MIN_SWEEP) {
            self.sweep();
        }
        (made, None)
    }

    /// Drops the entries of dead nodes.
    fn sweep(&mut self) {
        self.map.retain(|_, bucket| match bucket {
            Bucket::One(w) => w.strong_count() > 0,
            Bucket::Many(ws) => {
                ws.retain(|w| w.strong_count() > 0);
                !ws.is_empty()
            }
        });
        self.entries = self
            .map
            .values()
            .map(|b| match b {
                Bucket::One(_) => 1,
                Bucket::Many(ws) => ws.len(),
            })
            .sum();
        self.sweep_at = 2 * self.entries;
    }
}

static TABLE: LazyLock<[Mutex<Shard>; SHARDS]> =
    LazyLock::new(|| std::array::from_fn(|_| Mutex::new(Shard::default())));

/// The one node equal to `node` (whose structural hash is `hash`), built now if it did not exist.
pub(super) fn intern(node: Node, hash: u64, tree_size: u64) -> Arc<Inner> {
    let shard = &TABLE[(hash >> 60) as usize % SHARDS];
    // A panic cannot leave a shard inconsistent (each update is one map operation), so a poisoned lock is usable.
    let mut guard = shard.lock().unwrap_or_else(PoisonError::into_inner);
    let (found, candidate) = guard.find_or_insert(hash, node, tree_size);
    drop(guard);
    drop(candidate);
    found
}

/// Equality of two nodes whose children are interned: same operation, same leaf, identical children.
fn shallow_eq(a: &Node, b: &Node) -> bool {
    match (a, b) {
        (Node::Const(x), Node::Const(y)) => x.to_bits() == y.to_bits(),
        (Node::Sym(x), Node::Sym(y)) => x == y,
        (Node::Add(xs), Node::Add(ys)) | (Node::Mul(xs), Node::Mul(ys)) => {
            super::Expr::same_nodes(xs, ys)
        }
        (Node::Pow(b1, e1), Node::Pow(b2, e2)) => b1.same_node(b2) && e1.same_node(e2),
        (Node::Call(f, xs), Node::Call(g, ys)) => f == g && super::Expr::same_nodes(xs, ys),
        _ => false,
    }
}
