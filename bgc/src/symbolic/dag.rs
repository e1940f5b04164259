//! Walks of the expression DAG: every distinct node once, children before parents, on an explicit stack.
//!
//! The memoised operations (evaluation, substitution, differentiation, printing) run over [`Dag::order`] and keep one
//! result per node, looked up by [`Dag::index`]: their cost is linear in the number of distinct nodes, however
//! often a node is shared and however deep the expression is.

use super::expr::Expr;
use super::intern::PassThroughState;
use std::collections::HashMap;

/// The distinct nodes reachable from some roots, in post-order.
pub(super) struct Dag<'a> {
    /// Each node after all of its children; every node once.
    pub order: Vec<&'a Expr>,
    index: HashMap<usize, usize, PassThroughState>,
}

impl<'a> Dag<'a> {
    pub fn new(roots: impl IntoIterator<Item = &'a Expr>) -> Dag<'a> {
        Dag::new_pruned(roots, |_| true)
    }

    /// As [`Dag::new`], but the children of a node for which `descend` is false are not visited (the node is).
    pub fn new_pruned(
        roots: impl IntoIterator<Item = &'a Expr>,
        descend: impl Fn(&Expr) -> bool,
    ) -> Dag<'a> {
        let roots: Vec<&'a Expr> = roots.into_iter().collect();
        // Sized for the expressions as trees (their distinct nodes are at most that), up to a bound: most walks
        // are of small expressions, and growing a table step by step costs more than walking it.
        let capacity = roots
            .iter()
            .fold(0usize, |n, r| n.saturating_add(r.node_count()))
            .min(4096);
        let mut dag = Dag {
            order: Vec::with_capacity(capacity),
            index: HashMap::with_capacity_and_hasher(capacity, PassThroughState::default()),
        };
        // Nodes on the stack are marked with `usize::MAX` until they are placed in the order.
        let mut stack: Vec<(&'a Expr, usize)> = Vec::new();
        for root in roots {
            match dag.index.entry(root.address()) {
                std::collections::hash_map::Entry::Occupied(_) => continue,
                std::collections::hash_map::Entry::Vacant(slot) => {
                    slot.insert(usize::MAX);
                }
            }
            stack.push((root, 0));
            while let Some((e, next)) = stack.last_mut() {
                let e: &'a Expr = e;
                let child = if descend(e) {
                    e.node().child(*next)
                } else {
                    None
                };
                match child {
                    Some(c) => {
                        *next += 1;
                        if let std::collections::hash_map::Entry::Vacant(slot) =
                            dag.index.entry(c.address())
                        {
                            slot.insert(usize::MAX);
                            stack.push((c, 0));
                        }
                    }
                    None => {
                        dag.index.insert(e.address(), dag.order.len());
                        dag.order.push(e);
                        stack.pop();
                    }
                }
            }
        }
        dag
    }

    /// The position of `e` in [`Dag::order`]; `None` for a node not reached.
    pub fn index(&self, e: &Expr) -> Option<usize> {
        self.index
            .get(&e.address())
            .copied()
            .filter(|&i| i != usize::MAX)
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Per node of [`Dag::order`]: whether it reads a symbol for which `pred` holds (a symbol itself, or a node
    /// with such a child).
    pub fn reading(&self, pred: impl Fn(&super::expr::Symbol) -> bool) -> Vec<bool> {
        let mut reads = vec![false; self.len()];
        for (i, e) in self.order.iter().enumerate() {
            let mut r = e.as_symbol().is_some_and(&pred);
            e.node()
                .for_each_child(|c| r |= self.index(c).is_some_and(|k| reads[k]));
            reads[i] = r;
        }
        reads
    }
}

/// One value per node of a [`Dag`], filled in post-order.
pub(super) struct Memo<'d, 'a, T> {
    dag: &'d Dag<'a>,
    values: Vec<Option<T>>,
}

impl<'d, 'a, T: Clone> Memo<'d, 'a, T> {
    pub fn new(dag: &'d Dag<'a>) -> Memo<'d, 'a, T> {
        Memo {
            dag,
            values: vec![None; dag.len()],
        }
    }

    pub fn set(&mut self, i: usize, value: T) {
        if let Some(slot) = self.values.get_mut(i) {
            *slot = Some(value);
        }
    }

    /// The value of `e`, when `e` is a node of the walk already computed.
    pub fn get(&self, e: &Expr) -> Option<&T> {
        self.dag
            .index(e)
            .and_then(|i| self.values.get(i))
            .and_then(Option::as_ref)
    }
}

impl Expr {
    /// The number of distinct nodes of the expressions together: their size as stored.
    pub fn distinct_nodes(exprs: &[Expr]) -> usize {
        Dag::new(exprs).len()
    }
}
