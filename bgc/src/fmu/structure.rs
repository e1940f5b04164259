//! The dependencies of `ModelStructure`: which states and inputs each state derivative and output may depend on,
//! from the structure of the generated Jacobians (the symbolic `∂f/∂x`, `∂f/∂u`, `∂h/∂x`, `∂h/∂u` that are not
//! identically zero).
//!
//! A listed dependency may be numerically zero at some point; an unlisted one never is. The rows of an I-field's
//! velocities are `M(q)⁻¹ F`: each depends on what any force of its block depends on and on the coordinates `M`
//! depends on. A model with nonlinear algebraic loops gets no lists (the standard then reads "depends on every
//! state and input"): its rates depend on the states also through the tears' solution.

use crate::codegen::emit;
use crate::equations::{Equations, SparseMatrix};
use std::collections::BTreeSet;

/// Per state derivative and per output, the columns it depends on: `k < n_states` the state `k`, else the input
/// `k - n_states`. `None`: not known structurally (the standard's default, every state and input).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Dependencies {
    pub derivatives: Option<Vec<BTreeSet<usize>>>,
    pub outputs: Option<Vec<BTreeSet<usize>>>,
}

pub fn dependencies(eqs: &Equations) -> Dependencies {
    let Ok(plan) = emit::plan(eqs) else {
        return Dependencies::default();
    };
    if plan.loops.is_some() {
        return Dependencies::default();
    }
    let nx = plan.states.len();
    let pattern = |dx: &SparseMatrix, du: &SparseMatrix| -> Vec<BTreeSet<usize>> {
        dx.entries
            .iter()
            .zip(&du.entries)
            .map(|(rx, ru)| {
                let states = rx.iter().filter(|(_, e)| !e.is_zero()).map(|(k, _)| *k);
                let inputs = ru.iter().filter(|(_, e)| !e.is_zero()).map(|(k, _)| nx + k);
                states.chain(inputs).collect()
            })
            .collect()
    };
    let mut derivatives = pattern(&plan.dfdx, &plan.dfdu);
    let outputs = pattern(&plan.dhdx, &plan.dhdu);
    if derivatives.len() != nx {
        return Dependencies::default();
    }
    for block in &plan.mass {
        let mut union: BTreeSet<usize> = block.derivatives.iter().map(|(k, _)| *k).collect();
        for &r in &block.rows {
            if let Some(row) = derivatives.get(r) {
                union.extend(row.iter().copied());
            }
        }
        for &r in &block.rows {
            if let Some(row) = derivatives.get_mut(r) {
                row.clone_from(&union);
            }
        }
    }
    Dependencies {
        derivatives: Some(derivatives),
        outputs: Some(outputs),
    }
}
