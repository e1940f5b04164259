//! Named shared subexpressions for entries (of Jacobians, state spaces and energy terms) that would print as huge
//! trees.
//!
//! The engine stores a subexpression used in many places once, but printed code repeats it at every use: the
//! derivative of a chain of outputs `yᵢ = sin(yᵢ₋₁²) + cos(yᵢ₋₁)` is a DAG of a few nodes per level and a tree
//! that doubles with each level. Such an entry (large as a tree and many times larger than as stored) is printed
//! over `let`s of its shared nodes ([`crate::symbolic::cse`]), so the generated function grows with the DAG. Entries
//! of ordinary size print as before.

use crate::symbolic::{Expr, Symbol, cse};
use std::collections::BTreeMap;

/// The definitions `(name, value)` a function binds before its entries, children first.
pub(crate) type Lets = Vec<(Symbol, Expr)>;

/// An entry is shared out when its tree has more nodes than this ...
const LARGE_TREE: usize = 1000;
/// ... and more than this many times its distinct nodes.
const REPEATS: usize = 4;

fn repeats(e: &Expr) -> bool {
    let tree = e.node_count();
    tree > LARGE_TREE && tree / REPEATS > Expr::distinct_nodes(std::slice::from_ref(e))
}

/// Rewrites the entries that would print as huge trees over named shared subexpressions `{prefix}1`,
/// `{prefix}2`, ... and returns their definitions (none when no entry is large).
pub(crate) fn share<'a>(prefix: &str, entries: impl Iterator<Item = &'a mut Expr>) -> Lets {
    let picked: Vec<&mut Expr> = entries.filter(|e| repeats(e)).collect();
    if picked.is_empty() {
        return Vec::new();
    }
    let exprs: Vec<Expr> = picked.iter().map(|e| (**e).clone()).collect();
    let (definitions, rewritten) = cse(&exprs);
    let names: Vec<Symbol> = (1..=definitions.len())
        .map(|k| Symbol::intermediate(format!("{prefix}{k}")))
        .collect();
    let rename: BTreeMap<Symbol, Expr> = definitions
        .iter()
        .zip(&names)
        .map(|((s, _), name)| (s.clone(), Expr::symbol(name.clone())))
        .collect();
    for (slot, e) in picked.into_iter().zip(rewritten) {
        *slot = e.substitute(&rename);
    }
    definitions
        .into_iter()
        .zip(names)
        .map(|((_, value), name)| (name, value.substitute(&rename)))
        .collect()
}
