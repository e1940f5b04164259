//! The one place where the equations' symbols get the names code generation prints.
//!
//! The equations stage builds its expressions in the shared engine with numbered symbols
//! ([`crate::equations::symbols`]); code generation prints through [`crate::symbolic::to_rust`], which prints a
//! symbol's name, so every expression is renamed here (one memoised substitution, linear in its distinct nodes).
//! Leaves become named [`Symbol`]s: parameters, inputs, states, intermediates (bond variables of the readable form),
//! the tear variables of nonlinear algebraic loops (intermediates named `loop_<variable>`, which the generated
//! functions bind from the loops' solution, see [`super::loops`]) and time. Derivatives of inputs or states have no
//! meaning in generated code and are refused.

use crate::equations::Equations;
use crate::equations::symbols::{Sym, SymExt};
use crate::symbolic::{Expr, Symbol, SymbolKind};

/// An expression that cannot be generated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AdaptError {
    #[error("`{symbol}` (a derivative) has no value in generated code")]
    Unsupported { symbol: String },
}

/// The symbol a leaf of the equations stands for, named as the equations name it.
pub fn symbol(eqs: &Equations, s: Sym) -> Result<Symbol, AdaptError> {
    match s {
        Sym::Param(_) => Ok(Symbol::param(eqs.sym_name(s))),
        Sym::Input(_) => Ok(Symbol::input(eqs.sym_name(s))),
        Sym::State(_) => Ok(Symbol::state(eqs.sym_name(s))),
        // A tear (`loop_<variable>`) is a local of the generated functions, bound from the loops' solution.
        Sym::Var(_) | Sym::Tear(_) => Ok(Symbol::intermediate(eqs.sym_name(s))),
        Sym::Time => Ok(Symbol::time()),
        // An earlier output in a readable output (explicit outputs are converted by `explicit_outputs`).
        Sym::Output(_) => Ok(Symbol::new(eqs.sym_name(s), SymbolKind::Output)),
        Sym::InputDot(_) | Sym::StateDot(_) => Err(AdaptError::Unsupported {
            symbol: eqs.sym_name(s),
        }),
    }
}

/// `e` as a symbolic-engine expression.
pub fn to_symbolic(eqs: &Equations, e: &Expr) -> Result<Expr, AdaptError> {
    convert(eqs, e, &[])
}

/// The explicit outputs `h(x, u, p, t)`, in order: a reference to an earlier output ([`Sym::Output`]) becomes that
/// output's expression, one shared node of the engine however often it is used. `None` for an output that was not
/// derived (and for the outputs defined through it).
pub fn explicit_outputs(eqs: &Equations) -> Result<Vec<Option<Expr>>, AdaptError> {
    let mut done: Vec<Option<Expr>> = Vec::with_capacity(eqs.outputs.len());
    for o in &eqs.outputs {
        let refs_ok = o.explicit.as_ref().is_some_and(|e| {
            !e.any_sym(&|s| matches!(s, Sym::Output(j) if done.get(j).is_none_or(Option::is_none)))
        });
        let value = match (&o.explicit, refs_ok) {
            (Some(e), true) => Some(convert(eqs, e, &done)?),
            _ => None,
        };
        done.push(value);
    }
    Ok(done)
}

/// The given expression of output `s`, if `s` is one.
fn s_output(outputs: &[Option<Expr>], s: Sym) -> Option<&Expr> {
    match s {
        Sym::Output(j) => outputs.get(j).and_then(Option::as_ref),
        _ => None,
    }
}

/// `e` with the earlier outputs `outputs[j]` in place of [`Sym::Output`]`(j)` where they are given, and every other
/// symbol of the equations by its named symbol: one substitution, each distinct node rebuilt once.
fn convert(eqs: &Equations, e: &Expr, outputs: &[Option<Expr>]) -> Result<Expr, AdaptError> {
    // The first refused symbol; the substitution keeps it and the error is returned after.
    let refused = std::cell::RefCell::new(None);
    let out = e.substitute_with(&|s: &Symbol| {
        let stage = Sym::of(s)?;
        if let Some(shared) = s_output(outputs, stage) {
            return Some(shared.clone());
        }
        match symbol(eqs, stage) {
            Ok(named) => Some(Expr::symbol(named)),
            Err(err) => {
                refused.borrow_mut().get_or_insert(err);
                None
            }
        }
    });
    match refused.into_inner() {
        Some(err) => Err(err),
        None => Ok(out),
    }
}

/// A matrix of the equations' expressions with every entry named ([`to_symbolic`]).
pub fn named_matrix(
    eqs: &Equations,
    m: crate::equations::SparseMatrix,
) -> Result<crate::equations::SparseMatrix, AdaptError> {
    let entries = m
        .entries
        .into_iter()
        .map(|row| {
            row.into_iter()
                .map(|(j, e)| Ok((j, to_symbolic(eqs, &e)?)))
                .collect::<Result<Vec<_>, AdaptError>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(crate::equations::SparseMatrix { entries, ..m })
}

/// The parameter chain with its symbols and links named as the generated code names them.
pub fn named_chain(
    eqs: &Equations,
    chain: crate::equations::ParamChain,
) -> Result<crate::equations::ParamChain, AdaptError> {
    let symbols = chain
        .symbols
        .iter()
        .map(|s| match Sym::of(s) {
            Some(t) => symbol(eqs, t),
            None => Ok(s.clone()),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let links = chain
        .links
        .iter()
        .map(|row| row.iter().map(|e| to_symbolic(eqs, e)).collect())
        .collect::<Result<Vec<_>, _>>()?;
    Ok(crate::equations::ParamChain {
        symbols,
        links,
        ..chain
    })
}
