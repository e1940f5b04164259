//! A small symbolic expression engine for the equations stage and the code generators.
//!
//! [`Expr`] is an immutable, canonical expression over `f64` constants, [`Symbol`]s (a name and a [`SymbolKind`]),
//! n-ary sums and products, powers and the functions of [`crate::ir::Func`]. Every constructor simplifies (see
//! `build.rs` for the rules and the NaN caveat), so two expressions that are equal up to commutativity,
//! associativity, like-term collection and constant folding are `==`, hash alike and print alike:
//! `a*b + c == c + b*a`. The form is canonical, not a normal form for all identities: `2*(x + y) - 2*x` does not
//! become `2*y` unless [`Expr::expand`] is asked for.
//!
//! # Simplification on construction (details in `symbolic/build.rs`)
//! Sums and products are flattened, sorted by a total deterministic order, like terms and like factors collected
//! (`2*x + 3*x = 5*x`, `x*x = x^2`), constants folded; `x + 0 = x`, `x*1 = x`, `x*0 = 0`, `x^0 = 1`, `x^1 = x`,
//! `(x^a)^n = x^(a*n)` and `(x*y)^n = x^n*y^n` for integer `n`; `a - b = a + (-1)*b`, `a/b = a*b^(-1)`,
//! `sqrt(x) = x^0.5`; a numeric coefficient times a single sum is distributed (`-(a - b) = b - a`), and a sum inside
//! a product has its sign taken out. Calls with constant arguments are folded.
//!
//! NaN caveat: the rules are those of generic computer algebra. The simplified form equals the original wherever
//! the original is finite, but may be finite where the original is NaN or infinite: `x*0 = 0`, `x - x = 0` and
//! `x/x = 1` although `inf*0`, `inf - inf` and `0/0` are NaN; `sqrt(x)^2 = x` although the left side is NaN for
//! `x < 0`. A NaN constant absorbs a whole sum or product. Signs of zeros are not kept (`-0` is stored as `0`).
//!
//! Derivatives ([`Expr::diff`]): `d|u| = sign(u) du`; `d sign(u) = 0` (exact away from `u = 0`);
//! `d min(a, b) = (1 - s)/2 da + (1 + s)/2 db` and `d max(a, b) = (1 + s)/2 da + (1 - s)/2 db` with
//! `s = sign(a - b)`, i.e. the derivative of the active argument and the mean of both where `a = b`.
//!
//! Evaluation and generated code share conventions: `sign(0) = 0`, `min`/`max` propagate NaN, `x^n` for integer
//! constants is binary powering, `x^0.5` is `sqrt`, the elementary functions are the `libm` crate's; sums and
//! products are computed in the order they print, so [`Expr::eval`] and the code printed by [`to_rust`] give the
//! same bits on every platform.
//!
//! # Representation
//! Expressions form a hash-consed DAG: every node is interned in one process-wide table (`intern.rs`), so equal
//! expressions are one node, `==` is a pointer comparison, and a subexpression used in many places is stored once.
//! The table holds weak references (it never keeps an expression alive) and is sharded by hash, so expressions need
//! no context threaded through calls, can be built from any thread, and `clone` is a reference-count increment.
//! The total order makes sorting, and therefore printing, deterministic.
//!
//! Operations walk the distinct nodes in post-order on an explicit stack (`dag.rs`) and keep one result per node:
//! evaluation, substitution, differentiation, free symbols, expansion and linear forms cost linear in the number of
//! distinct nodes, and no operation recurses to a depth that grows with the expression (comparison and freeing use
//! work lists too), so deep expressions cannot overflow the stack. Printers keep the printed form of shared nodes
//! and build text as a rope (`print/plan.rs`, `print/doc.rs`), so they print what a tree walk prints, in time
//! linear in the length of the text. Building a flattened sum or product one term at a time remains quadratic in
//! its length (each partial sum is a node of its own); [`Expr::sum`] and [`Expr::product`] take all terms at once.
//!
//! # Operations
//! - construction: [`Expr::constant`], [`Expr::symbol`], [`Expr::sum`], [`Expr::product`], [`Expr::pow`],
//!   [`Expr::call`], the operators `+ - * /` and unary `-` on `Expr`, `&Expr` and `f64`;
//! - [`Expr::substitute`], [`Expr::diff`], [`Expr::jacobian`], [`Expr::eval`], [`Expr::free_symbols`],
//!   [`Expr::expand`], [`Expr::linear_form`];
//! - sparsity: [`Expr::symbols_read`] (which symbols each expression reads) and [`Expr::sparse_jacobian`]
//!   (entries only where a variable occurs); [`Expr::distinct_nodes`], the stored size;
//!   [`Expr::symbols_under_calls`] (the symbols read inside `min`/`max` or other calls);
//! - [`cse`] names the subexpressions used more than once, [`to_text_cse`] and [`to_rust_cse`] print them as
//!   definitions (the default printers do not);
//! - [`solve_linear`] for small linear systems;
//! - printers [`to_text`] (also `Display`), [`to_latex`], [`to_rust`] (and [`to_rust_code`], its tree);
//! - [`from_ir`] from the IR's expressions.

mod build;
mod compiled;
mod cse;
mod dag;
mod diff;
mod error;
mod eval;
mod expr;
mod from_ir;
mod intern;
mod linear;
mod magnitude;
mod order;
mod print;
mod solve;

#[cfg(test)]
mod tests;

pub use compiled::Compiled;
pub use cse::{cse, to_rust_cse, to_text_cse};
pub use diff::{ProductTails, WIDE_ROW};
pub use error::SymbolicError;
pub use eval::{max, min, sign};
pub use expr::{Expr, ExprMap, ExprSet, Node, Symbol, SymbolKind};
pub use from_ir::from_ir;
pub use linear::{LinearForm, MAX_EXPANDED_POWER, MAX_EXPANDED_TERMS};
pub use print::latex::{
    latex_subscript, latex_symbol, latex_symbol_parts, to_latex, to_latex_with,
};
pub use print::rust::{
    RUST_HELPER_FNS, RUST_HELPER_PREFIX, RUST_HELPERS, RUST_MAX_FN, RUST_MIN_FN, RUST_POWI_FN,
    RUST_SIGN_FN, RustCode, RustOp, rust_helpers_used, to_rust, to_rust_code,
};
pub use print::text::{to_text, to_text_with};
pub use solve::{LinearSolution, MAX_SOLVE_SIZE, solve_linear};
