//! The one place where the equations stage's expressions ([`Ex`]) become the symbolic engine's ([`Expr`]).
//!
//! The equations stage still carries its own expression type; code generation prints through
//! [`crate::symbolic::to_rust`], so every expression crosses over here. The conversion is structural (sums,
//! products, powers and calls rebuilt with the engine's simplifying constructors), so the value is unchanged up to
//! the engine's canonical reordering. Leaves become named [`Symbol`]s: parameters, inputs, states, intermediates
//! (bond variables of the readable form), the tear variables of nonlinear algebraic loops (intermediates named
//! `loop_<variable>`, which the generated functions bind from the loops' solution, see [`super::loops`]) and time.
//! Derivatives of inputs or states have no meaning in generated code and are refused. When the two expression types are unified this module goes away.

use crate::equations::Equations;
use crate::equations::sym::{Ex, Sym};
use crate::symbolic::{Expr, Symbol, SymbolKind};

/// An expression that cannot be generated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AdaptError {
    #[error("`{symbol}` (a derivative) has no value in generated code")]
    Unsupported { symbol: String },
    #[error("`{func}` is called with the wrong number of arguments")]
    Arity { func: &'static str },
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
pub fn to_symbolic(eqs: &Equations, e: &Ex) -> Result<Expr, AdaptError> {
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

/// `e` with the earlier outputs `outputs[j]` in place of [`Sym::Output`]`(j)` where they are given.
fn convert(eqs: &Equations, e: &Ex, outputs: &[Option<Expr>]) -> Result<Expr, AdaptError> {
    Ok(match e {
        // The zeros of dense matrices skip the interning table.
        Ex::Num(v) if *v == 0.0 => Expr::zero(),
        Ex::Num(v) => Expr::constant(*v),
        Ex::S(s) => match s_output(outputs, *s) {
            Some(shared) => shared.clone(),
            None => Expr::symbol(symbol(eqs, *s)?),
        },
        Ex::Add(ts) => Expr::sum(
            ts.iter()
                .map(|t| convert(eqs, t, outputs))
                .collect::<Result<Vec<_>, _>>()?,
        ),
        Ex::Mul(fs) => Expr::product(
            fs.iter()
                .map(|f| convert(eqs, f, outputs))
                .collect::<Result<Vec<_>, _>>()?,
        ),
        Ex::Pow(b, x) => convert(eqs, b, outputs)?.pow(&convert(eqs, x, outputs)?),
        Ex::Call(f, args) => {
            let args = args
                .iter()
                .map(|a| convert(eqs, a, outputs))
                .collect::<Result<Vec<_>, _>>()?;
            Expr::call(*f, &args).ok_or(AdaptError::Arity { func: f.name() })?
        }
    })
}
