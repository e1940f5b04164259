//! Common subexpressions: naming the nodes an expression list uses more than once.
//!
//! Hash-consing already stores a shared subexpression once; [`cse`] makes that sharing visible to a reader (or to
//! generated code) by naming each non-leaf node used more than once, counting uses across all the expressions and
//! within each, as `t1`, `t2`, ... (intermediate symbols, with names no symbol of the expressions has). Definitions
//! come children first, so each uses only names defined before it, and substituting them back in reverse order
//! gives the original expressions. [`to_text_cse`] prints the result as `let`-style lines.
//!
//! The default printers do not do this: their output stays that of the expressions as written.

use super::dag::{Dag, Memo};
use super::expr::{Expr, Node, Symbol};
use super::print::rust::to_rust;
use super::print::text::to_text_with;
use std::collections::BTreeSet;

/// The definitions `(name, expression)` of the subexpressions used more than once, children first, and the
/// expressions rewritten over those names.
pub fn cse(exprs: &[Expr]) -> (Vec<(Symbol, Expr)>, Vec<Expr>) {
    let dag = Dag::new(exprs);
    let mut uses = vec![0u32; dag.len()];
    let mut bump = |e: &Expr| {
        if let Some(slot) = dag.index(e).and_then(|k| uses.get_mut(k)) {
            *slot = slot.saturating_add(1);
        }
    };
    exprs.iter().for_each(&mut bump);
    for e in &dag.order {
        e.node().for_each_child(&mut bump);
    }
    let taken: BTreeSet<String> = dag
        .order
        .iter()
        .filter_map(|e| e.as_symbol().map(|s| s.name().to_string()))
        .collect();
    let mut names = (1..)
        .map(|k| format!("t{k}"))
        .filter(|n| !taken.contains(n));
    let mut definitions = Vec::new();
    let mut rewritten: Memo<Expr> = Memo::new(&dag);
    for (i, e) in dag.order.iter().enumerate() {
        let body = e.map_children(&|c| rewritten.get(c).cloned().unwrap_or_else(|| c.clone()));
        let shared = uses.get(i).copied().unwrap_or(0) > 1;
        let is_leaf = matches!(e.node(), Node::Const(_) | Node::Sym(_));
        let name = if shared && !is_leaf {
            names.next()
        } else {
            None
        };
        let out = match name {
            Some(name) => {
                let symbol = Symbol::intermediate(name);
                definitions.push((symbol.clone(), body));
                Expr::symbol(symbol)
            }
            None => body,
        };
        rewritten.set(i, out);
    }
    let outputs = exprs
        .iter()
        .map(|e| rewritten.get(e).cloned().unwrap_or_else(|| e.clone()))
        .collect();
    (definitions, outputs)
}

/// The expressions as text with their common subexpressions named: one line `name = expression` per definition,
/// then one line per expression, each symbol printed as `names` says (the names of definitions as they are).
pub fn to_text_cse(exprs: &[Expr], names: &dyn Fn(&Symbol) -> String) -> String {
    cse_lines(exprs, names, to_text_with, |name, body| {
        format!("{name} = {body}")
    })
}

/// The expressions as Rust with their common subexpressions bound first: one `let name = expression;` line per
/// definition, then one line per expression, each symbol printed as `names` says (the names of definitions as
/// they are).
pub fn to_rust_cse(exprs: &[Expr], names: &dyn Fn(&Symbol) -> String) -> String {
    cse_lines(exprs, names, to_rust, |name, body| {
        format!("let {name} = {body};")
    })
}

/// A printer of one expression with the symbols named by a function (`to_text_with`, `to_rust`).
type Printer = fn(&Expr, &dyn Fn(&Symbol) -> String) -> String;

/// The lines of [`to_text_cse`] and [`to_rust_cse`]: each definition as `define` writes it, then each expression,
/// printed by `print` with the definitions' own names.
fn cse_lines(
    exprs: &[Expr],
    names: &dyn Fn(&Symbol) -> String,
    print: Printer,
    define: fn(&str, &str) -> String,
) -> String {
    let (definitions, outputs) = cse(exprs);
    let defined: BTreeSet<&Symbol> = definitions.iter().map(|(s, _)| s).collect();
    let name = |s: &Symbol| {
        if defined.contains(s) {
            s.name().to_string()
        } else {
            names(s)
        }
    };
    let mut out = String::new();
    for (s, body) in &definitions {
        out.push_str(&define(s.name(), &print(body, &name)));
        out.push('\n');
    }
    for e in &outputs {
        out.push_str(&print(e, &name));
        out.push('\n');
    }
    out
}
