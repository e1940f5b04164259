//! A small symbolic expression engine for the equations stage and the code generators.
//!
//! [`Expr`] is an immutable, canonical expression over `f64` constants, [`Symbol`]s (a name and a [`SymbolKind`]),
//! n-ary sums and products, powers and the functions of [`crate::ir::Func`]. Every constructor simplifies (see
//! `build.rs` for the rules and the NaN caveat), so two expressions that are equal up to commutativity,
//! associativity, like-term collection and constant folding are `==`, hash alike and print alike:
//! `a*b + c == c + b*a`. The form is canonical, not a normal form for all identities: `2*(x + y) - 2*x` does not
//! become `2*y` unless [`Expr::expand`] is asked for.
//!
//! # Representation
//! Nodes are shared behind `Arc` with a cached structural hash, rather than interned in an arena. Expressions here
//! are small (element laws, state equations of a few dozen states), so hash-consing would save little memory, while
//! `Arc` nodes need no interner threaded through every call or kept alive beside the expressions, can be built from
//! any thread, and make `clone` a reference-count increment. The cached hash makes equality of different trees
//! cheap to refute; the total order makes sorting, and therefore printing, deterministic.
//!
//! # Operations
//! - construction: [`Expr::constant`], [`Expr::symbol`], [`Expr::sum`], [`Expr::product`], [`Expr::pow`],
//!   [`Expr::call`], the operators `+ - * /` and unary `-` on `Expr`, `&Expr` and `f64`;
//! - [`Expr::substitute`], [`Expr::diff`], [`Expr::jacobian`], [`Expr::eval`], [`Expr::free_symbols`],
//!   [`Expr::expand`], [`Expr::linear_form`];
//! - [`solve_linear`] for small linear systems;
//! - printers [`to_text`] (also `Display`), [`to_latex`], [`to_rust`];
//! - [`from_ir`] from the IR's expressions.

mod build;
mod diff;
mod error;
mod eval;
mod expr;
mod from_ir;
mod linear;
mod print;
mod solve;

#[cfg(test)]
mod tests;

pub use error::SymbolicError;
pub use eval::{max, min, sign};
pub use expr::{Expr, Node, Symbol, SymbolKind};
pub use from_ir::from_ir;
pub use linear::{LinearForm, MAX_EXPANDED_POWER, MAX_EXPANDED_TERMS};
pub use print::latex::{latex_symbol, to_latex, to_latex_with};
pub use print::rust::{RUST_HELPERS, RUST_MAX_FN, RUST_MIN_FN, RUST_SIGN_FN, to_rust};
pub use print::text::{to_text, to_text_with};
pub use solve::{LinearSolution, MAX_SOLVE_SIZE, solve_linear};
