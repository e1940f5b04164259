//! The elements whose values or laws use time `t`: exogenous signals written into the model.
//!
//! `ẋ = f(x, u, p, t)` holds them, so simulation is exact; a state space `ẋ = A x + B u` has no column for a signal
//! of time, and the linear state space refuses such a model naming these elements
//! ([`super::LinearError::TimeDependent`]) rather than dropping their terms.

use crate::ir::{Expr, Model, Relation};

/// The names of the elements whose relation uses `t` (directly or through an output), in node order.
pub(crate) fn time_elements(model: &Model) -> Vec<String> {
    model
        .graph
        .node_weights()
        .filter(|w| {
            let exprs: Vec<&Expr> = match &w.relation {
                Relation::Junction => Vec::new(),
                Relation::Source(e) | Relation::Linear(e) | Relation::Modulus(e) => vec![e],
                Relation::Laws(laws) => laws.iter().map(|l| &l.rhs).collect(),
                Relation::MassMatrix { entries, .. } => entries.iter().collect(),
            };
            exprs.into_iter().any(|e| uses_time(model, e, 0))
        })
        .map(|w| w.name.clone())
        .collect()
}

/// True when `e` uses `t`. `depth` bounds the walk through outputs (which lowering keeps acyclic).
fn uses_time(model: &Model, e: &Expr, depth: usize) -> bool {
    if depth > model.outputs.len() + 1 {
        return false;
    }
    match e {
        Expr::Time => true,
        Expr::Output(o) => model
            .outputs
            .get(*o)
            .is_some_and(|out| uses_time(model, &out.value, depth + 1)),
        Expr::Neg(a) => uses_time(model, a, depth),
        Expr::Binary(_, a, b) => uses_time(model, a, depth) || uses_time(model, b, depth),
        Expr::Call(_, args) => args.iter().any(|a| uses_time(model, a, depth)),
        _ => false,
    }
}
