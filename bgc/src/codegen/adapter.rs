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
use crate::symbolic::{Expr, Symbol};

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
        Sym::InputDot(_) | Sym::StateDot(_) => Err(AdaptError::Unsupported {
            symbol: eqs.sym_name(s),
        }),
    }
}

/// `e` as a symbolic-engine expression.
pub fn to_symbolic(eqs: &Equations, e: &Ex) -> Result<Expr, AdaptError> {
    Ok(match e {
        Ex::Num(v) => Expr::constant(*v),
        Ex::S(s) => Expr::symbol(symbol(eqs, *s)?),
        Ex::Add(ts) => Expr::sum(
            ts.iter()
                .map(|t| to_symbolic(eqs, t))
                .collect::<Result<Vec<_>, _>>()?,
        ),
        Ex::Mul(fs) => Expr::product(
            fs.iter()
                .map(|f| to_symbolic(eqs, f))
                .collect::<Result<Vec<_>, _>>()?,
        ),
        Ex::Pow(b, x) => to_symbolic(eqs, b)?.pow(&to_symbolic(eqs, x)?),
        Ex::Call(f, args) => {
            let args = args
                .iter()
                .map(|a| to_symbolic(eqs, a))
                .collect::<Result<Vec<_>, _>>()?;
            Expr::call(*f, &args).ok_or(AdaptError::Arity { func: f.name() })?
        }
    })
}
