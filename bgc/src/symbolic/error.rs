//! Errors of the symbolic engine.

use super::expr::SymbolKind;
use thiserror::Error;

#[derive(Clone, Debug, PartialEq, Eq, Error)]
pub enum SymbolicError {
    #[error("no value given for the {kind:?} symbol `{name}`")]
    UnboundSymbol { name: String, kind: SymbolKind },
    #[error("`{func}` takes {expected} argument(s), {found} given")]
    Arity {
        func: &'static str,
        expected: usize,
        found: usize,
    },
    #[error(
        "the expression is not linear in `{symbol}`: the term `{term}` is not a constant times a variable"
    )]
    NotLinear { symbol: String, term: String },
    #[error("the symbolic solver handles systems of at most {max} equations, {n} given")]
    SystemTooLarge { n: usize, max: usize },
    #[error("row {row} of the matrix has {found} entries, the system needs {expected}")]
    ShapeMismatch {
        row: usize,
        found: usize,
        expected: usize,
    },
    #[error("the system is singular: column {column} has no structurally non-zero pivot")]
    Singular { column: usize },
    #[error("no symbolic value for the IR leaf {leaf}")]
    UnmappedLeaf { leaf: String },
}
