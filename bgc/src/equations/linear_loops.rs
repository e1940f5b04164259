//! Linear models whose algebraic loops are solved numerically.
//!
//! The resolver solves a loop that is affine in its tear in closed form, unless nested loops would make that closed
//! form grow geometrically (a ladder of resistors with parameters of their own): such a loop is kept as a block of
//! linear equations in its tears ([`super::TearBlock`]), solved numerically. The model has then no symbolic state
//! space, but it is still linear: its rates, outputs and loop residuals are linear in the states, inputs and tears,
//! so the implicit-function linearisation at any point, the origin included, is its exact state space.

use super::Equations;
use super::linear::{LinearError, StateSelection, selected, time_elements_text};
use super::symbols::{self, Sym, SymExt};
use crate::symbolic::Expr;
use std::collections::BTreeSet;

/// Whether `eqs` has algebraic loops solved numerically and is nonetheless linear: every selected rate, every output
/// and every loop residual is linear (without a constant part) in the states, inputs and tears, with coefficients
/// free of them and of time, and every mass matrix is constant. Then [`super::linearise`] at any point gives the
/// exact `A, B, C, D`.
pub fn linear_through_loops(eqs: &Equations, selection: StateSelection) -> bool {
    if eqs.tear_blocks.is_empty() {
        return false;
    }
    let constant_mass = eqs
        .mass
        .iter()
        .flat_map(|b| b.matrix.iter().flatten())
        .all(|m| !m.any_sym(&unknown));
    if !constant_mass {
        return false;
    }
    let Ok((f, h)) = selected(eqs, selection) else {
        return false;
    };
    let residuals = eqs.tear_blocks.iter().flat_map(|b| b.residuals.iter());
    f.iter().chain(&h).chain(residuals).all(linear_in_unknowns)
}

/// The symbols whose values a linear model multiplies by constant coefficients, and time (which it must not read).
fn unknown(s: Sym) -> bool {
    matches!(
        s,
        Sym::State(_)
            | Sym::Input(_)
            | Sym::Tear(_)
            | Sym::Time
            | Sym::StateDot(_)
            | Sym::InputDot(_)
    )
}

/// `e = Σ c_k v_k` over the unknowns `v_k` it reads, each `c_k` free of unknowns, and nothing else.
fn linear_in_unknowns(e: &Expr) -> bool {
    let mut read = BTreeSet::new();
    e.for_each_sym(&mut |s| {
        if unknown(s) {
            read.insert(s);
        }
    });
    if read
        .iter()
        .any(|s| matches!(s, Sym::Time | Sym::StateDot(_) | Sym::InputDot(_)))
    {
        return false;
    }
    let read: Vec<Sym> = read.into_iter().collect();
    let constant_slopes =
        symbols::gradient(e, &read).is_ok_and(|slopes| slopes.iter().all(|d| !d.any_sym(&unknown)));
    constant_slopes && symbols::subst(e, &mut |s| unknown(s).then(Expr::zero)).is_zero()
}

/// The error for a model whose numerically solved loops read a signal of time (`Se mains = V0*sin(w*t);` on a
/// loop): like a rate that reads one, it has no state space `ẋ = A x + B u` ([`LinearError::TimeDependent`]).
/// `None` when no loop residual reads `t`.
pub fn time_in_loops(eqs: &Equations) -> Option<LinearError> {
    let block = eqs
        .tear_blocks
        .iter()
        .find(|b| b.residuals.iter().any(|r| r.contains(Sym::Time)))?;
    Some(LinearError::TimeDependent {
        what: super::tear::loop_named(&block.names),
        elements: time_elements_text(eqs),
    })
}
