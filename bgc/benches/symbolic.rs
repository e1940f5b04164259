//! Benchmarks of the symbolic engine on the shape of work the equations stage does: build the state equations of a
//! chain of masses and springs, take their Jacobian, extract the linear coefficients, solve a small loop and print;
//! and on the shapes that show whether operations cost linear in the number of distinct nodes:
//! - the shared chain `x_{k+1} = sin(x_k*x_k) + cos(x_k)` (each level uses the one below twice, so a tree walk is
//!   exponential in the number of levels and a walk of the DAG is linear);
//! - the deep chain `e_{k+1} = (e_k + a_k)*b_k`, 100,000 levels (nesting depth 200,000);
//! - the wide sum `Σ c_k*a_k*b_k` of 100,000 products.

use bgc::symbolic::{Expr, Symbol, cse, solve_linear, to_rust, to_rust_cse, to_text, to_text_cse};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::collections::HashMap;
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

/// `x_{k+1} = sin(x_k*x_k) + cos(x_k)` from `x_0 = x`, `levels` times.
fn shared_chain(levels: usize) -> Expr {
    let mut e = Expr::symbol(Symbol::state("x"));
    for _ in 0..levels {
        e = (&e * &e).sin() + e.cos();
    }
    e
}

/// `e_{k+1} = (e_k + a_k)*b_k` from `e_0 = x`: nesting depth `2*n`.
fn deep_chain(n: usize) -> Expr {
    let mut e = Expr::symbol(Symbol::state("x"));
    for k in 0..n {
        let a = Expr::symbol(Symbol::param(format!("a_{k}")));
        let b = Expr::symbol(Symbol::param(format!("b_{k}")));
        e = (e + a) * b;
    }
    e
}

/// `Σ c_k*a_k*b_k` for `k < n`, with `c_k = k + 1`.
fn wide_sum(n: usize) -> Expr {
    Expr::sum((0..n).map(|k| {
        let a = Expr::symbol(Symbol::state(format!("a_{k}")));
        let b = Expr::symbol(Symbol::param(format!("b_{k}")));
        (k as f64 + 1.0) * a * b
    }))
}

/// A value for every symbol: 0.5 for `x`, else a value derived from the name's length.
fn values(e: &Expr) -> HashMap<Symbol, f64> {
    e.free_symbols()
        .into_iter()
        .map(|s| {
            let v = if s.name() == "x" {
                0.5
            } else {
                1.0 + 1.0 / s.name().len() as f64
            };
            (s, v)
        })
        .collect()
}

fn bench_small(c: &mut Criterion) {
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

/// Levels of the shared chain for building, differentiating, evaluating and printing.
const SHARED_LEVELS: [usize; 3] = [12, 16, 24];
/// Levels of the deep chain.
const DEEP_LEVELS: [usize; 2] = [10_000, 100_000];
/// Terms of the wide sum.
const WIDE_TERMS: [usize; 1] = [100_000];

fn bench_shared(c: &mut Criterion) {
    let x = Symbol::state("x");
    let mut g = c.benchmark_group("symbolic/shared_chain");
    g.sample_size(10);
    for levels in SHARED_LEVELS {
        let e = shared_chain(levels);
        let env = values(&e);
        g.bench_with_input(BenchmarkId::new("build", levels), &levels, |b, &n| {
            b.iter(|| shared_chain(black_box(n)))
        });
        g.bench_with_input(BenchmarkId::new("diff", levels), &e, |b, e| {
            b.iter(|| e.diff(&x))
        });
        g.bench_with_input(BenchmarkId::new("eval", levels), &e, |b, e| {
            b.iter(|| e.eval(|s| env.get(s).copied()))
        });
        if levels <= 16 {
            g.bench_with_input(BenchmarkId::new("print_text", levels), &e, |b, e| {
                b.iter(|| to_text(e).len())
            });
        }
        let names = |s: &Symbol| s.name().to_string();
        let one = std::slice::from_ref(&e);
        g.bench_with_input(BenchmarkId::new("cse", levels), &e, |b, _| {
            b.iter(|| cse(one).0.len())
        });
        g.bench_with_input(BenchmarkId::new("print_text_cse", levels), &e, |b, _| {
            b.iter(|| to_text_cse(one, &names).len())
        });
        g.bench_with_input(BenchmarkId::new("print_rust_cse", levels), &e, |b, _| {
            b.iter(|| to_rust_cse(one, &names).len())
        });
    }
    g.finish();
}

fn bench_deep_and_wide(c: &mut Criterion) {
    let mut g = c.benchmark_group("symbolic/long");
    g.sample_size(10);
    let names = |s: &Symbol| s.name().to_string();
    let x = Symbol::state("x");
    for n in DEEP_LEVELS {
        let e = deep_chain(n);
        let env = values(&e);
        g.bench_with_input(BenchmarkId::new("deep_build", n), &n, |b, &n| {
            b.iter(|| deep_chain(black_box(n)))
        });
        g.bench_with_input(BenchmarkId::new("deep_diff", n), &e, |b, e| {
            b.iter(|| e.diff(&x))
        });
        g.bench_with_input(BenchmarkId::new("deep_eval", n), &e, |b, e| {
            b.iter(|| e.eval(|s| env.get(s).copied()))
        });
        g.bench_with_input(BenchmarkId::new("deep_print_text", n), &e, |b, e| {
            b.iter(|| to_text(e).len())
        });
        g.bench_with_input(BenchmarkId::new("deep_print_rust", n), &e, |b, e| {
            b.iter(|| to_rust(e, &names).len())
        });
    }
    for n in WIDE_TERMS {
        let e = wide_sum(n);
        let env = values(&e);
        let a0 = Symbol::state("a_0");
        g.bench_with_input(BenchmarkId::new("wide_build", n), &n, |b, &n| {
            b.iter(|| wide_sum(black_box(n)))
        });
        g.bench_with_input(BenchmarkId::new("wide_diff", n), &e, |b, e| {
            b.iter(|| e.diff(&a0))
        });

        g.bench_with_input(BenchmarkId::new("wide_eval", n), &e, |b, e| {
            b.iter(|| e.eval(|s| env.get(s).copied()))
        });
        g.bench_with_input(BenchmarkId::new("wide_print_text", n), &e, |b, e| {
            b.iter(|| to_text(e).len())
        });
        g.bench_with_input(BenchmarkId::new("wide_print_rust", n), &e, |b, e| {
            b.iter(|| to_rust(e, &names).len())
        });
    }
    // ẋ_i = x_{i-1} - 2 x_i + x_{i+1} for 10,000 states: 3 non-zeros a row.
    let n = 10_000;
    let xs: Vec<Symbol> = (0..n).map(|i| Symbol::state(format!("x_{i}"))).collect();
    let x = |i: usize| Expr::symbol(xs[i].clone());
    let rows: Vec<Expr> = (0..n)
        .map(|i| {
            let left = if i > 0 { x(i - 1) } else { Expr::zero() };
            let right = if i + 1 < n { x(i + 1) } else { Expr::zero() };
            left - 2.0 * x(i) + right
        })
        .collect();
    g.bench_with_input(
        BenchmarkId::new("tridiagonal_sparse_jacobian", n),
        &rows,
        |b, rows| b.iter(|| Expr::sparse_jacobian(rows, &xs).len()),
    );
    g.finish();
}

criterion_group!(benches, bench_small, bench_shared, bench_deep_and_wide);
criterion_main!(benches);
