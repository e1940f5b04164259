//! Energy terms printed over named shared subexpressions, when printing each in full would repeat them.
//!
//! Energy terms are explicit in states, inputs and parameters. When one large subexpression is in many terms
//! (a junction's flow `(u0 + ... + u29999)/r` in the power of each of 30,000 sources, or a resistor network's
//! `1/(r0 + ... + r2999)` in the power of each resistor), printing each term in full is quadratic: 5.4 MB of
//! text for 300 resistors, gigabytes for 30,000 sources. Such terms are printed after `where` definitions of
//! their shared subexpressions (common-subexpression elimination over the terms), each printed once. Terms that
//! do not repeat much are printed as they are, so ordinary models print as before.

use super::Equations;
use crate::symbolic::{Expr, Symbol, cse};
use std::collections::{HashMap, HashSet};

/// The terms are printed over definitions when their trees have at least this many nodes in all ...
const MIN_TREE_NODES: usize = 10_000;
/// ... and this many times as many as their distinct nodes.
const MIN_REPETITION: usize = 8;

/// The energy terms over shared definitions.
pub(crate) struct SharedTerms {
    /// `(name, value)` of each definition, each using only those before it.
    pub definitions: Vec<(String, Expr)>,
    /// Each energy term's value over the definitions (`None` where the term has none).
    pub values: Vec<Option<Expr>>,
    /// The definitions' symbols and their printed names.
    pub names: HashMap<Symbol, String>,
}

/// The energy terms of `eqs` over named shared subexpressions, when printing them in full would repeat those
/// many times (see the module docs); `None` otherwise.
pub(crate) fn shared_energy(eqs: &Equations) -> Option<SharedTerms> {
    let present: Vec<Expr> = eqs.energy.iter().filter_map(|t| t.value.clone()).collect();
    if !repeats_much(&present) {
        return None;
    }
    let (definitions, rewritten) = cse(&present);
    let taken = taken_names(eqs);
    let mut fresh = (1..)
        .map(|k| format!("w{k}"))
        .filter(|n| !taken.contains(n));
    let names: HashMap<Symbol, String> = definitions
        .iter()
        .map(|(s, _)| (s.clone(), fresh.next().unwrap_or_default()))
        .collect();
    let definitions = definitions
        .into_iter()
        .map(|(s, e)| (names.get(&s).cloned().unwrap_or_default(), e))
        .collect();
    let mut rewritten = rewritten.into_iter();
    let values = eqs
        .energy
        .iter()
        .map(|t| t.value.as_ref().and_then(|_| rewritten.next()))
        .collect();
    Some(SharedTerms {
        definitions,
        values,
        names,
    })
}

/// Whether the trees of `values` hold many times their distinct nodes (and are large).
fn repeats_much(values: &[Expr]) -> bool {
    let total = values
        .iter()
        .map(Expr::node_count)
        .fold(0usize, usize::saturating_add);
    // Terms of a few nodes each print in linear size however much they share (a chain's `p_k^2/m`): no need to
    // count the distinct nodes of a million of them.
    if total < MIN_TREE_NODES || total < MIN_REPETITION.saturating_mul(values.len()) {
        return false;
    }
    total / MIN_REPETITION > Expr::distinct_nodes(values)
}

/// Every name a printed term may use: parameters, inputs, states, outputs, intermediates and bond variables.
fn taken_names(eqs: &Equations) -> HashSet<String> {
    eqs.params
        .iter()
        .map(|(n, _)| n.clone())
        .chain(eqs.inputs.iter().cloned())
        .chain(eqs.states.iter().map(|s| s.name.clone()))
        .chain(eqs.outputs.iter().map(|o| o.name.clone()))
        .chain(eqs.intermediates.iter().map(|i| i.name.clone()))
        .chain(eqs.var_names.iter().cloned())
        .collect()
}
