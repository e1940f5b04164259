//! Multiplying out products of sums, with a memory of what was multiplied out before.
//!
//! The resolver multiplies out every value it computes ([`super::super::resolve`]), and a value is built from the
//! values of the variables it uses, each multiplied out (or found too large to be) already. Along a chain of
//! elements each value holds the previous one, so expanding it afresh repeats the work of every earlier value: a
//! chain of `N` modulated transformers cost `N³`. An [`Expander`] remembers the expansion of every subexpression of
//! some size it has met, so a value held inside the next one is looked up, not expanded again. The result is that
//! of expanding from scratch: the expansion of a subexpression does not depend on where it sits.

use super::{Ex, add, mul};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

/// Products whose expansion would have more terms than this are left as they are.
const MAX_TERMS: usize = 64;

/// Subexpressions of fewer nodes than this are expanded again rather than remembered.
const MEMO_MIN_NODES: usize = 8;

/// The remembered expressions hold at most this many nodes; the memory starts over beyond it.
const MEMO_MAX_NODES: usize = 1 << 22;

/// Expands products of sums, remembering the results (see the module documentation).
#[derive(Default)]
pub struct Expander {
    /// Hash of a subexpression → (subexpression, its expansion).
    memo: HashMap<u64, Vec<(Ex, Ex)>>,
    /// The number of nodes of the remembered subexpressions.
    nodes: usize,
}

/// What [`Expander`] knows of one node, in pre-order: its hash, whether a product of sums is reachable from it,
/// and the number of nodes of its subtree (so the next sibling's entry is `size` entries on).
#[derive(Clone, Copy)]
struct Info {
    hash: u64,
    product_of_sum: bool,
    size: usize,
}

impl Expander {
    /// Products of sums multiplied out (`a (b + c)` → `a b + a c`), except a product that would make more than
    /// 64 terms, which stays as it is.
    pub fn expand(&mut self, e: &Ex) -> Ex {
        if !super::has_product_of_sum(e) {
            return e.clone();
        }
        let mut info = Vec::new();
        annotate(e, &mut info);
        self.at(e, &info, 0)
    }

    fn at(&mut self, e: &Ex, info: &[Info], i: usize) -> Ex {
        let Some(&node) = info.get(i) else {
            return e.clone();
        };
        if !node.product_of_sum {
            // Nothing to multiply out: the expression is already in canonical form (most resolved values are).
            return e.clone();
        }
        let remembered = node.size >= MEMO_MIN_NODES;
        if remembered
            && let Some((_, out)) = self
                .memo
                .get(&node.hash)
                .and_then(|list| list.iter().find(|(seen, _)| same(seen, e)))
        {
            return out.clone();
        }
        let out = self.compute(e, info, i);
        if remembered {
            if self.nodes + 2 * node.size > MEMO_MAX_NODES {
                self.memo.clear();
                self.nodes = 0;
            }
            self.nodes += 2 * node.size;
            self.memo
                .entry(node.hash)
                .or_default()
                .push((e.clone(), out.clone()));
        }
        out
    }

    fn compute(&mut self, e: &Ex, info: &[Info], i: usize) -> Ex {
        let mut child = i + 1;
        let next = |child: &mut usize| {
            let at = *child;
            *child += info.get(at).map_or(1, |n| n.size);
            at
        };
        match e {
            Ex::Add(ts) => {
                let mut out = Vec::with_capacity(ts.len());
                for t in ts {
                    let k = next(&mut child);
                    out.push(self.at(t, info, k));
                }
                add(out)
            }
            Ex::Mul(fs) => {
                let mut terms = vec![Ex::one()];
                for f in fs {
                    let k = next(&mut child);
                    match self.at(f, info, k) {
                        Ex::Add(inner) => {
                            if terms.len() * inner.len() > MAX_TERMS {
                                return e.clone();
                            }
                            terms = terms
                                .iter()
                                .flat_map(|t| {
                                    inner.iter().map(move |i| mul(vec![t.clone(), i.clone()]))
                                })
                                .collect();
                        }
                        other => terms
                            .iter_mut()
                            .for_each(|t| *t = mul(vec![t.clone(), other.clone()])),
                    }
                }
                add(terms)
            }
            _ => e.clone(),
        }
    }
}

/// Appends the [`Info`] of `e` and of its subtree, in pre-order.
fn annotate(e: &Ex, info: &mut Vec<Info>) {
    let slot = info.len();
    info.push(Info {
        hash: 0,
        product_of_sum: false,
        size: 1,
    });
    let mut h = Fx::default();
    std::mem::discriminant(e).hash(&mut h);
    let mut product_of_sum = false;
    let mut children = |items: &[Ex], info: &mut Vec<Info>, h: &mut Fx| {
        for item in items {
            let at = info.len();
            annotate(item, info);
            let c = info[at];
            h.write_u64(c.hash);
            product_of_sum |=
                c.product_of_sum || (matches!(e, Ex::Mul(_)) && matches!(item, Ex::Add(_)));
        }
    };
    match e {
        Ex::Num(v) => h.write_u64(v.to_bits()),
        Ex::S(s) => s.hash(&mut h),
        Ex::Add(items) | Ex::Mul(items) => children(items, info, &mut h),
        Ex::Call(f, items) => {
            f.hash(&mut h);
            children(items, info, &mut h);
        }
        Ex::Pow(b, x) => {
            for part in [&**b, &**x] {
                let at = info.len();
                annotate(part, info);
                h.write_u64(info[at].hash);
            }
        }
    }
    // Only sums and products are walked by the expansion: a product of sums under a power or a call stays.
    let product_of_sum = product_of_sum && matches!(e, Ex::Add(_) | Ex::Mul(_));
    let size = info.len() - slot;
    info[slot] = Info {
        hash: h.finish(),
        product_of_sum,
        size,
    };
}

/// Structural equality with numbers compared bit for bit (`0` and `-0` are different keys, so different inputs).
fn same(a: &Ex, b: &Ex) -> bool {
    match (a, b) {
        (Ex::Num(x), Ex::Num(y)) => x.to_bits() == y.to_bits(),
        (Ex::S(x), Ex::S(y)) => x == y,
        (Ex::Add(xs), Ex::Add(ys)) | (Ex::Mul(xs), Ex::Mul(ys)) => all_same(xs, ys),
        (Ex::Call(f, xs), Ex::Call(g, ys)) => f == g && all_same(xs, ys),
        (Ex::Pow(b1, x1), Ex::Pow(b2, x2)) => same(b1, b2) && same(x1, x2),
        _ => false,
    }
}

fn all_same(xs: &[Ex], ys: &[Ex]) -> bool {
    xs.len() == ys.len() && xs.iter().zip(ys).all(|(x, y)| same(x, y))
}

/// A fast multiplicative hash (the memory's keys are checked by [`same`], so collisions cost only time).
#[derive(Default)]
struct Fx(u64);

impl Hasher for Fx {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}
