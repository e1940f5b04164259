//! Benchmarks of the symbolic engine on the shape of work the equations stage does: build the state equations of a
//! chain of masses and springs, take their Jacobian, extract the linear coefficients, solve a small loop and print.

use bgc::symbolic::{Expr, Symbol, solve_linear, to_rust};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// ṗᵢ = k(q_{i-1} - qᵢ)... for a chain of `n` masses: the right-hand sides and the state symbols.
fn chain(n: usize) -> (Vec<Expr>, Vec<Symbol>) {
    let q: Vec<Symbol> = (0..n).map(|i| Symbol::state(format!("q_{i}"))).collect();
    let p: Vec<Symbol> = (0..n).map(|i| Symbol::state(format!("p_{i}"))).collect();
    let mut rhs = Vec::new();
    for i in 0..n {
        let m = Expr::symbol(Symbol::param(format!("m_{i}")));
        let k = Expr::symbol(Symbol::param(format!("k_{i}")));
        let b = Expr::symbol(Symbol::param(format!("b_{i}")));
        let qi = Expr::symbol(q[i].clone());
        let pi = Expr::symbol(p[i].clone());
        let left = if i == 0 {
            Expr::zero()
        } else {
            Expr::symbol(q[i - 1].clone())
        };
        rhs.push(&pi / &m);
        rhs.push(&k * (&left - &qi) - &b * &pi / &m + (&qi * 0.1).sin());
    }
    (rhs, q.into_iter().chain(p).collect())
}

fn bench(c: &mut Criterion) {
    let (rhs, states) = chain(6);
    c.bench_function("symbolic/build_chain_6", |b| b.iter(|| chain(black_box(6))));
    c.bench_function("symbolic/jacobian_chain_6", |b| {
        b.iter(|| Expr::jacobian(black_box(&rhs), &states))
    });
    c.bench_function("symbolic/linear_form_chain_6", |b| {
        b.iter(|| {
            rhs.iter()
                .filter(|e| e.diff(&states[0]).linear_form(&states).is_ok())
                .count()
        })
    });
    let names = |s: &Symbol| s.name().to_string();
    c.bench_function("symbolic/print_rust_chain_6", |b| {
        b.iter(|| rhs.iter().map(|e| to_rust(e, &names).len()).sum::<usize>())
    });
    let a: Vec<Vec<Expr>> = (0..4)
        .map(|i| {
            (0..4)
                .map(|j| Expr::symbol(Symbol::param(format!("a_{i}{j}"))))
                .collect()
        })
        .collect();
    let rhs4: Vec<Expr> = (0..4)
        .map(|i| Expr::symbol(Symbol::input(format!("u_{i}"))))
        .collect();
    c.bench_function("symbolic/solve_4x4", |b| {
        b.iter(|| solve_linear(black_box(&a), &rhs4).is_ok())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
