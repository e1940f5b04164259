//! Conversion of the equations' expressions to the shared expression engine [`crate::symbolic`], whose printers
//! (text, LaTeX, Rust) the code generators use.
//!
//! Symbols keep their printed names; kinds map as: parameter → `Param`, input → `Input`, state → `State`,
//! intermediate bond variable → `Intermediate`, time → `Time`. The transient symbols (state and input derivatives,
//! loop tears) do not occur in the explicit rates and outputs; if met they become `Intermediate` symbols with
//! their printed names (`dp_rotor_dt`), so the conversion is total.

use super::Equations;
use super::sym::{Ex, Sym};
use crate::symbolic::{Expr, Symbol, SymbolKind};

/// The symbol of `s` in the shared engine.
pub fn symbol(eqs: &Equations, s: Sym) -> Symbol {
    let kind = match s {
        Sym::Param(_) => SymbolKind::Param,
        Sym::Input(_) => SymbolKind::Input,
        Sym::State(_) => SymbolKind::State,
        Sym::Time => SymbolKind::Time,
        Sym::Output(_) => SymbolKind::Output,
        Sym::Var(_) | Sym::StateDot(_) | Sym::InputDot(_) | Sym::Tear(_) => {
            SymbolKind::Intermediate
        }
    };
    Symbol::new(eqs.sym_name(s), kind)
}

/// `e` as an expression of the shared engine; `None` only for a function call with the wrong number of arguments
/// (which the equations stage never builds).
pub fn to_symbolic(eqs: &Equations, e: &Ex) -> Option<Expr> {
    Some(match e {
        Ex::Num(v) => Expr::constant(*v),
        Ex::S(s) => Expr::symbol(symbol(eqs, *s)),
        Ex::Add(ts) => Expr::sum(
            ts.iter()
                .map(|t| to_symbolic(eqs, t))
                .collect::<Option<Vec<_>>>()?,
        ),
        Ex::Mul(fs) => Expr::product(
            fs.iter()
                .map(|f| to_symbolic(eqs, f))
                .collect::<Option<Vec<_>>>()?,
        ),
        Ex::Pow(b, x) => to_symbolic(eqs, b)?.pow(&to_symbolic(eqs, x)?),
        Ex::Call(f, args) => {
            let args = args
                .iter()
                .map(|a| to_symbolic(eqs, a))
                .collect::<Option<Vec<_>>>()?;
            Expr::call(*f, &args)?
        }
    })
}
