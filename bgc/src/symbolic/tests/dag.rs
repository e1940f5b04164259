//! Tests of the expression DAG: hash-consing, memoised operations on shared and on deep expressions, common
//! subexpressions and sparsity.

use super::super::{Expr, Node, Symbol, cse, to_latex, to_rust, to_rust_cse, to_text, to_text_cse};
use super::{Rng, p, s};
use std::cell::Cell;
use std::collections::BTreeMap;

/// `x_{k+1} = sin(x_k*x_k) + cos(x_k)` from `x_0 = x`: each level uses the one below twice.
fn shared_chain(levels: usize) -> Expr {
    let mut e = s("x");
    for _ in 0..levels {
        e = (&e * &e).sin() + e.cos();
    }
    e
}

/// `e_{k+1} = (e_k + a_k)*b_k` from `e_0 = x`: nesting depth `2*n`.
fn deep_chain(n: usize) -> Expr {
    let mut e = s("x");
    for k in 0..n {
        e = (e + p(&format!("a_{k}"))) * p(&format!("b_{k}"));
    }
    e
}

fn chain_value(name: &str) -> Option<f64> {
    // a_k = 1/(k + 2), b_k = 0.5 + 1/(k + 3), x = 0.25: values stay of order 1.
    let k = |rest: &str| rest.parse::<f64>().ok();
    match name.split_once('_') {
        Some(("a", r)) => k(r).map(|k| 1.0 / (k + 2.0)),
        Some(("b", r)) => k(r).map(|k| 0.5 / (1.0 + 1.0 / (k + 3.0))),
        _ if name == "x" => Some(0.25),
        _ => None,
    }
}

#[test]
fn equal_expressions_are_one_node() {
    let a = p("a") * s("x") + p("c");
    let b = p("c") + s("x") * p("a");
    assert_eq!(a, b);
    assert_eq!(a.address(), b.address());
    // Rebuilt through the constructors from its terms in another order: the same node.
    let Node::Add(terms) = a.node() else {
        panic!("{a} is not a sum");
    };
    let rebuilt = Expr::sum(terms.iter().rev().cloned());
    assert_eq!(rebuilt.address(), a.address());
    assert_ne!(a, p("c") + s("x") * p("b"));
}

#[test]
fn nodes_are_freed_and_rebuilt_alike() {
    let text = {
        let e = deep_chain(50);
        to_text(&e)
    };
    // The first chain is gone; building it again gives an equal expression that prints alike.
    assert_eq!(to_text(&deep_chain(50)), text);
}

#[test]
fn a_shared_chain_is_walked_once_per_distinct_node() {
    let e = shared_chain(24);
    // As a tree the chain has more than 2^24 nodes; as a DAG about 5 per level.
    assert!(e.node_count() > 1 << 24, "{}", e.node_count());
    assert!(Expr::distinct_nodes(std::slice::from_ref(&e)) <= 5 * 24 + 2);

    let lookups = Cell::new(0);
    let value = e
        .eval(|sym| {
            lookups.set(lookups.get() + 1);
            (sym.name() == "x").then_some(0.3)
        })
        .unwrap_or(f64::NAN);
    assert_eq!(lookups.get(), 1, "x is read once, not 2^24 times");
    let mut want = 0.3f64;
    for _ in 0..24 {
        want = libm::sin(want * want) + libm::cos(want);
    }
    assert_eq!(value.to_bits(), want.to_bits());

    let replaced = Cell::new(0);
    let y = Symbol::state("y");
    let moved = e.substitute_with(&|sym| {
        replaced.set(replaced.get() + 1);
        (sym.name() == "x").then(|| Expr::symbol(y.clone()))
    });
    assert_eq!(replaced.get(), 1);
    assert_eq!(
        Expr::distinct_nodes(std::slice::from_ref(&moved)),
        Expr::distinct_nodes(std::slice::from_ref(&e))
    );

    // d x_{k+1} = (2 x_k cos(x_k^2) - sin(x_k)) d x_k: the derivative is linear in size too.
    let d = e.diff(&Symbol::state("x"));
    assert!(
        Expr::distinct_nodes(std::slice::from_ref(&d)) <= 20 * 24,
        "{}",
        Expr::distinct_nodes(std::slice::from_ref(&d))
    );
    let (mut x, mut dx) = (0.3f64, 1.0f64);
    for _ in 0..24 {
        dx *= 2.0 * x * (x * x).cos() - x.sin();
        x = (x * x).sin() + x.cos();
    }
    let got = d
        .eval(|sym| (sym.name() == "x").then_some(0.3))
        .unwrap_or(f64::NAN);
    assert!(
        (got - dx).abs() <= 1e-9 * dx.abs().max(1.0),
        "{got} vs {dx}"
    );

    let (definitions, outputs) = cse(std::slice::from_ref(&e));
    assert_eq!(definitions.len(), 23, "x_1 ... x_23 are each used twice");
    assert_eq!(outputs.len(), 1);
    assert_eq!(to_text(&outputs[0]), "sin(t23^2) + cos(t23)");
}

#[test]
fn a_deep_chain_is_built_evaluated_printed_and_freed_without_deep_recursion() {
    let n = 100_000;
    let e = deep_chain(n);
    let value = e.eval(|sym| chain_value(sym.name())).unwrap_or(f64::NAN);
    let mut want = 0.25f64;
    for k in 0..n {
        let (a, b) = (
            chain_value(&format!("a_{k}")),
            chain_value(&format!("b_{k}")),
        );
        want = b.unwrap_or(f64::NAN) * (a.unwrap_or(f64::NAN) + want);
    }
    assert_eq!(value.to_bits(), want.to_bits());
    assert_eq!(e.free_symbols().len(), 2 * n + 1);
    assert!(e.depends_on(&Symbol::state("x")));
    assert!(!e.depends_on(&Symbol::state("y")));

    // b_k*(a_k + ...(b_0*(a_0 + x))...)
    let mut text = String::new();
    for k in (0..n).rev() {
        text.push_str(&format!("b_{k}*(a_{k} + "));
    }
    text.push('x');
    text.push_str(&")".repeat(n));
    assert_eq!(to_text(&e), text);
    let rust = to_rust(&e, &|sym: &Symbol| sym.name().to_string());
    assert_eq!(rust, text.replace('*', " * "));
    assert!(to_latex(&e).starts_with(&format!(
        "b_{{{}}} \\left(a_{{{}}} + b_{{{}}}",
        n - 1,
        n - 1,
        n - 2
    )));

    // x -> 2*y everywhere, then back.
    let y = Symbol::state("y");
    let there = e.substitute(&BTreeMap::from([(
        Symbol::state("x"),
        2.0 * Expr::symbol(y.clone()),
    )]));
    let back = there.substitute(&BTreeMap::from([(y, 0.5 * s("x"))]));
    assert_eq!(back, e);
}

#[test]
fn a_deep_chain_is_differentiated_without_deep_recursion() {
    // e_{k+1} = (e_k + x)*b_k: d_{k+1} = b_k*(d_k + 1), d_0 = 1.
    let n = 100_000;
    let mut e = s("x");
    for k in 0..n {
        e = (e + s("x")) * p(&format!("b_{k}"));
    }
    let d = e.diff(&Symbol::state("x"));
    let mut want = 1.0f64;
    for k in 0..n {
        want = chain_value(&format!("b_{k}")).unwrap_or(f64::NAN) * (want + 1.0);
    }
    let got = d.eval(|sym| chain_value(sym.name())).unwrap_or(f64::NAN);
    assert!((got - want).abs() <= 1e-9 * want.abs(), "{got} vs {want}");
}

#[test]
fn linear_forms_of_deep_expressions() {
    // The coefficient is a product of n factors, built one factor a level: keep n moderate.
    let n = 1_000;
    let e = deep_chain(n);
    let x = Symbol::state("x");
    let form = e.linear_form(std::slice::from_ref(&x));
    let Ok(form) = form else {
        panic!("not linear: {form:?}");
    };
    // e = (Π b_k) x + rest.
    let coefficient = form.coefficients[0]
        .eval(|sym| chain_value(sym.name()))
        .unwrap_or(f64::NAN);
    let want: f64 = (0..n)
        .map(|k| chain_value(&format!("b_{k}")).unwrap_or(f64::NAN))
        .product();
    assert!(
        (coefficient - want).abs() <= 1e-12 * want.abs(),
        "{coefficient} vs {want}"
    );
    assert!(!form.rest.depends_on(&x));
}

#[test]
fn common_subexpressions_are_named_once_and_substitute_back() {
    let x = s("x");
    let k = p("k");
    let shared = (&k * &x).sin();
    let exprs = vec![&shared * &shared + 1.0, &shared + &x, x.cos()];
    let (definitions, outputs) = cse(&exprs);
    assert_eq!(definitions.len(), 1);
    assert_eq!(to_text(&definitions[0].1), "sin(k*x)");
    let t1 = Expr::symbol(definitions[0].0.clone());
    assert_eq!(outputs, vec![&t1 * &t1 + 1.0, &t1 + &x, x.cos()]);
    assert_eq!(
        to_text_cse(&exprs, &|sym: &Symbol| sym.name().to_string()),
        "t1 = sin(k*x)\nt1^2 + 1\nx + t1\ncos(x)\n"
    );
    assert_eq!(
        to_rust_cse(&exprs, &|sym: &Symbol| format!("p.{}", sym.name())),
        "let t1 = libm::sin(p.k * p.x);\nbgc_powi(t1, 2) + 1.0\np.x + t1\nlibm::cos(p.x)\n"
    );
    // A name taken by a symbol of the expressions is skipped.
    let taken = vec![&shared * Expr::symbol(Symbol::intermediate("t1")) + &shared];
    let (definitions, _) = cse(&taken);
    assert_eq!(definitions[0].0.name(), "t2");
}

#[test]
fn cse_of_random_shared_expressions_substitutes_back_exactly() {
    let mut rng = Rng(7);
    for _ in 0..200 {
        let exprs = random_shared(&mut rng);
        let (definitions, outputs) = cse(&exprs);
        let mut back = outputs.clone();
        for (name, body) in definitions.iter().rev() {
            let map = BTreeMap::from([(name.clone(), body.clone())]);
            back = back.iter().map(|e| e.substitute(&map)).collect();
        }
        assert_eq!(back, exprs);
        for (name, body) in &definitions {
            // Children first: a definition reads only names defined before it.
            let later: Vec<&Symbol> = definitions
                .iter()
                .skip_while(|(n, _)| n != name)
                .map(|(n, _)| n)
                .collect();
            assert!(later.iter().all(|n| !body.depends_on(n)), "{name} = {body}");
        }
    }
}

/// A few expressions built from shared random pieces.
fn random_shared(rng: &mut Rng) -> Vec<Expr> {
    let mut pool = vec![s("x"), s("y"), p("k")];
    for _ in 0..12 {
        let pick = |rng: &mut Rng, pool: &[Expr]| {
            let i = (rng.next_u64() % pool.len() as u64) as usize;
            pool[i].clone()
        };
        let (a, b) = (pick(rng, &pool), pick(rng, &pool));
        let e = match rng.next_u64() % 6 {
            0 => &a + &b,
            1 => &a * &b,
            2 => a.sin() + 1.5,
            3 => &a - 2.0 * &b,
            4 => a.powi(2) / (b.powi(2) + 1.0),
            _ => Expr::atan2(&a, &(b.exp())),
        };
        pool.push(e);
    }
    pool.split_off(pool.len() - 3)
}

#[test]
fn symbols_under_min_and_max_calls() {
    use crate::ir::Func;
    let inner = Expr::call(Func::Max, &[s("x"), p("k")]).expect("two arguments");
    let e = s("y") * inner.sin() + s("z");
    let (func, read) = e
        .symbols_under_calls(&[Func::Min, Func::Max])
        .expect("a max reads symbols");
    assert_eq!(func, Func::Max);
    assert_eq!(
        read.iter().map(Symbol::name).collect::<Vec<_>>(),
        ["k", "x"]
    );
    assert_eq!(
        (s("y") * s("x").sin()).symbols_under_calls(&[Func::Min, Func::Max]),
        None
    );
}

#[test]
fn symbols_read_and_sparse_jacobian() {
    let (x, y, z) = (Symbol::state("x"), Symbol::state("y"), Symbol::state("z"));
    let rows = vec![s("x") * s("y"), s("z").sin(), p("k") + 0.0 * s("x")];
    let reads = Expr::symbols_read(&rows);
    assert_eq!(
        reads[0].iter().map(Symbol::name).collect::<Vec<_>>(),
        ["x", "y"]
    );
    assert_eq!(reads[1].iter().map(Symbol::name).collect::<Vec<_>>(), ["z"]);
    assert_eq!(reads[2].iter().map(Symbol::name).collect::<Vec<_>>(), ["k"]);
    let vars = [x, y, z];
    let sparse = Expr::sparse_jacobian(&rows, &vars);
    let want = vec![(0, 0, s("y")), (0, 1, s("x")), (1, 2, s("z").cos())];
    assert_eq!(sparse, want);
    // The same entries as the dense Jacobian, whose other entries are 0.
    let dense = Expr::jacobian(&rows, &vars);
    for (i, row) in dense.iter().enumerate() {
        for (j, entry) in row.iter().enumerate() {
            match sparse.iter().find(|(r, c, _)| (*r, *c) == (i, j)) {
                Some((_, _, e)) => assert_eq!(e, entry),
                None => assert!(entry.is_zero(), "({i}, {j}) = {entry}"),
            }
        }
    }
}

#[test]
fn a_sparse_jacobian_of_a_long_chain_has_its_non_zeros_only() {
    // ẋ_i = x_{i-1} - 2 x_i + x_{i+1}: three entries a row.
    let n = 2_000;
    let xs: Vec<Symbol> = (0..n).map(|i| Symbol::state(format!("x_{i}"))).collect();
    let x = |i: usize| Expr::symbol(xs[i].clone());
    let rows: Vec<Expr> = (0..n)
        .map(|i| {
            let left = if i > 0 { x(i - 1) } else { Expr::zero() };
            let right = if i + 1 < n { x(i + 1) } else { Expr::zero() };
            left - 2.0 * x(i) + right
        })
        .collect();
    let sparse = Expr::sparse_jacobian(&rows, &xs);
    assert_eq!(sparse.len(), 3 * n - 2);
    assert!(sparse.iter().all(|(i, j, e)| {
        let want = if i == j { -2.0 } else { 1.0 };
        i.abs_diff(*j) <= 1 && e.as_const() == Some(want)
    }));
}

/// Substituting into many expressions at once gives each what substituting into it alone gives, and visits the
/// shared part once: 60 levels of the shared chain, each level and its square an expression of its own.
#[test]
fn substituting_into_many_at_once_is_substituting_into_each() {
    let levels: Vec<Expr> = (0..60).map(shared_chain).collect();
    let exprs: Vec<Expr> = levels
        .iter()
        .flat_map(|e| [e.clone(), e * e + p("k")])
        .collect();
    let visits = Cell::new(0usize);
    let f = |sym: &Symbol| {
        visits.set(visits.get() + 1);
        (sym.name() == "x").then(|| s("y") + p("k"))
    };
    let together = Expr::substitute_all(&exprs, &f);
    // `x` and `k`, each looked up once for all 120 expressions.
    assert_eq!(visits.get(), 2);
    for (e, t) in exprs.iter().zip(&together) {
        assert_eq!(*t, e.substitute_with(&f));
    }
    let reads_y = Expr::each_depends_on(&together, &|sym: &Symbol| sym.name() == "y");
    assert!(reads_y.iter().all(|&r| r));
    let reads_k = Expr::each_depends_on(&exprs, &|sym: &Symbol| sym.name() == "k");
    let expected: Vec<bool> = exprs
        .iter()
        .map(|e| e.depends_on(&Symbol::param("k")))
        .collect();
    assert_eq!(reads_k, expected);
    assert_eq!(reads_k.iter().filter(|&&r| r).count(), 60);
}

#[test]
fn a_symbol_keeps_its_kind_name_and_index_and_sorts_by_them_in_that_order() {
    use super::super::SymbolKind::*;
    let kinds = [
        Param,
        Input,
        Time,
        State,
        Intermediate,
        Output,
        Tear,
        StateRate,
        InputRate,
    ];
    let mut made = Vec::new();
    for kind in kinds {
        for index in [0, 1, 7, 1 << 40] {
            let symbol = Symbol::indexed(kind, index);
            assert_eq!(
                (symbol.kind(), symbol.name(), symbol.index()),
                (kind, "", Some(index))
            );
            made.push(symbol);
        }
        for name in ["a", "b"] {
            let symbol = Symbol::new(name, kind);
            assert_eq!(
                (symbol.kind(), symbol.name(), symbol.index()),
                (kind, name, None)
            );
            made.push(symbol);
        }
    }
    // Sorted by kind, then name (the indexed symbols have the empty name), then index.
    let key = |s: &Symbol| (s.kind(), s.name().to_owned(), s.index());
    let mut by_key = made.clone();
    by_key.sort_by_key(key);
    made.sort();
    assert!(made.iter().map(key).eq(by_key.iter().map(key)));
    assert_ne!(Symbol::indexed(State, 3), Symbol::indexed(Param, 3));
    assert_ne!(Symbol::indexed(State, 3), Symbol::indexed(State, 4));
    assert_eq!(Symbol::indexed(State, 3), Symbol::indexed(State, 3));
    assert_ne!(Symbol::state("x"), Symbol::indexed(State, 0));
}
