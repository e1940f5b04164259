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
use hashbrown::HashTable;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::{Arc, LazyLock, Mutex, PoisonError, Weak};

const SHARDS: usize = 16;

/// Entries a shard may hold before its first sweep.
const MIN_SWEEP: usize = 1024;

/// A hasher for keys that are already well-mixed 64-bit hashes: it passes them through.
#[derive(Default)]
pub struct PassThrough(u64);

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

pub type PassThroughState = BuildHasherDefault<PassThrough>;

/// A node of the table, with its structural hash: the table grows and sweeps without reading the nodes, and a
/// lookup upgrades only the entries whose whole hash matches.
struct Entry {
    hash: u64,
    node: Weak<Inner>,
}

#[derive(Default)]
struct Shard {
    /// The entries, several for one hash when distinct nodes collide (or dead ones wait for the sweep).
    table: HashTable<Entry>,
    sweep_at: usize,
}

impl Shard {
    /// The live node equal to `node` under `hash` with the candidate handed back (to be dropped by the caller), or
    /// the candidate made a node and recorded under `hash` (in the entry of a dead node with the same hash, if
    /// the probe sequence holds one).
    fn find_or_insert(
        &mut self,
        hash: u64,
        node: Node,
        tree_size: u64,
    ) -> (Arc<Inner>, Option<Node>) {
        let mut found = None;
        self.table.find(hash, |e| {
            e.hash == hash && {
                found = e.node.upgrade().filter(|a| shallow_eq(&a.node, &node));
                found.is_some()
            }
        });
        if let Some(found) = found {
            return (found, Some(node));
        }
        let made = Arc::new(Inner {
            node,
            hash,
            tree_size,
        });
        let entry = Entry {
            hash,
            node: Arc::downgrade(&made),
        };
        // A node that is built, dropped and built again (a constant, a temporary of a pass) would leave a dead
        // entry behind each time, all on one probe sequence: reuse one of them.
        let dead = |e: &Entry| e.hash == hash && e.node.strong_count() == 0;
        if let Some(old) = self.table.find_mut(hash, dead) {
            *old = entry;
        } else {
            self.table.insert_unique(hash, entry, |e| e.hash);
            if self.table.len() >= self.sweep_at.max(MIN_SWEEP) {
                self.sweep();
            }
        }
        (made, None)
    }

    /// Drops the entries of dead nodes.
    fn sweep(&mut self) {
        self.table.retain(|e| e.node.strong_count() > 0);
        self.sweep_at = 2 * self.table.len();
    }
}

/// A shard's lock and table header on cache lines of their own: two threads interning in neighbouring shards at
/// once would otherwise pass one line back and forth on every lock and unlock.
#[repr(align(128))]
struct Padded(Mutex<Shard>);

static TABLE: LazyLock<[Padded; SHARDS]> =
    LazyLock::new(|| std::array::from_fn(|_| Padded(Mutex::new(Shard::default()))));

/// The one node equal to `node` (whose structural hash is `hash`), built now if it did not exist.
pub(super) fn intern(node: Node, hash: u64, tree_size: u64) -> Arc<Inner> {
    // The shard from bits the shard's table does not use: it indexes by the low bits and tags each entry with the
    // top seven.
    let shard = &TABLE[(hash >> 32) as usize % SHARDS].0;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(shard: &mut Shard, hash: u64, v: f64) -> (Arc<Inner>, bool) {
        let (node, candidate) = shard.find_or_insert(hash, Node::Const(v), 1);
        (node, candidate.is_none())
    }

    #[test]
    fn a_node_built_and_dropped_again_and_again_reuses_its_entry() {
        let mut shard = Shard::default();
        let keep = constant(&mut shard, 7, 0.5).0;
        for _ in 0..10_000 {
            let (node, new) = constant(&mut shard, 9, 1.5);
            assert!(new, "the node was dropped, so it is built again");
            drop(node);
        }
        // The live node and one entry for the dropped one, whose slot each rebuild reused.
        assert_eq!(shard.table.len(), 2);
        let (again, new) = constant(&mut shard, 7, 0.5);
        assert!(!new && Arc::ptr_eq(&again, &keep));
    }

    #[test]
    fn nodes_whose_hashes_collide_stay_distinct_and_are_found() {
        let mut shard = Shard::default();
        let nodes: Vec<Arc<Inner>> = (0..50)
            .map(|k| constant(&mut shard, 42, f64::from(k)).0)
            .collect();
        for (k, node) in nodes.iter().enumerate() {
            let (found, new) = constant(&mut shard, 42, k as f64);
            assert!(!new && Arc::ptr_eq(&found, node), "node {k}");
        }
        // A dead node with the same hash does not hide a live one behind it.
        let (dead, _) = constant(&mut shard, 42, 100.0);
        drop(dead);
        let (found, new) = constant(&mut shard, 42, 49.0);
        assert!(!new && Arc::ptr_eq(&found, &nodes[49]));
    }

    #[test]
    fn the_table_stays_within_a_constant_factor_of_the_live_nodes() {
        let mut shard = Shard::default();
        let live: Vec<Arc<Inner>> = (0..100)
            .map(|k| constant(&mut shard, k, k as f64).0)
            .collect();
        for k in 0..100_000u64 {
            drop(constant(&mut shard, 1_000 + k, k as f64));
        }
        assert!(
            shard.table.len() <= 2 * MIN_SWEEP,
            "{} entries",
            shard.table.len()
        );
        assert_eq!(
            live.iter().filter(|n| Arc::strong_count(n) == 1).count(),
            100
        );
    }
}
