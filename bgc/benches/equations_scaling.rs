//! The equations stage (`lower` → `causality::analyse` → `equations::derive`, what `bgc equations` runs) on
//! families of models whose cost must grow with the model, not faster:
//! - a resistor ladder with chained algebraic loops (`rungs`),
//! - outputs defined through earlier outputs, `y_i = sin(y_{i-1}·y_{i-1}) + cos(y_{i-1})` (`levels`),
//! - a chain of modulated transformers with every inertia but one dependent (`n`),
//! - the benchmark chain: `Se` drives mass 1; each 1-junction has `I` (m = 1) and `R` (b = 0.5); a `C` to the
//!   wall at the first; a 0-junction and a `C` between neighbours; `2N` states.
//!
//! The `rust/...` groups time what `bgc rust` does after parsing (equations, Jacobians, code generation) on the
//! benchmark chain and the output chain: sparse Jacobians and shared subexpressions keep both linear in the model.
//!
//! Run with `cargo bench -p bgc --bench equations_scaling`. The same generators, at small sizes, are checked against
//! hand-derived values in `tests/equations_scaling.rs`.

#[path = "support/chain.rs"]
mod chain;

use bgc::causality::analyse;
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use chain::benchmark_chain;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn ladder(rungs: usize) -> String {
    let mut s = String::from(
        "model ladder {\n    domain electrical;\n    input u [V];\n    param r = 1 [Ohm];\n    param c = 1e-3 [F];\n    Se src = u;\n    C cap = c;\n",
    );
    let mut chain = String::from("src");
    for k in 1..=rungs {
        s += &format!("    1 s{k};\n    R rs{k} = r;\n    0 n{k};\n    R rp{k} = {k}*r;\n");
        s += &format!("    bond s{k} -> rs{k};\n    bond n{k} -> rp{k};\n");
        chain += &format!(" -> s{k} -> n{k}");
    }
    s += &format!("    bond {chain} -> cap;\n    output i1 [A] = f(rs1);\n}}\n");
    s
}

fn output_chain(levels: usize) -> String {
    let mut s = String::from(
        "model outchain {\n    domain translational;\n    param m = 1 [kg];\n    param k = 1 [N/m];\n    param q0 = 1 [m];\n    1 j;\n    I mass = m;\n    C spring = 1/k;\n    bond j -> mass;\n    bond j -> spring;\n    output y1 [1] = sin(q(spring)*q(spring)/(q0*q0)) + cos(q(spring)/q0);\n",
    );
    for i in 2..=levels {
        let p = i - 1;
        s += &format!("    output y{i} [1] = sin(y{p}*y{p}) + cos(y{p});\n");
    }
    s + "}\n"
}

fn mtf_chain(n: usize) -> String {
    let mut s = String::from(
        "model mtfchain {\n    domain rotational;\n    param J = 1 [kg m^2];\n    param b = 0.1 [N m s/rad];\n    input tau [N m];\n    var theta [rad] = int(f(j0));\n    Se drive = tau;\n    1 j0;\n    I i0 = J;\n    R r0 = b;\n    bond drive -> j0;\n    bond j0 -> i0;\n    bond j0 -> r0;\n",
    );
    for k in 1..=n {
        let p = k - 1;
        s += &format!(
            "    1 j{k};\n    I i{k} = J;\n    MTF g{k} = 1 + 0.1*cos(theta);\n    bond j{p} -> g{k} -> j{k};\n    bond j{k} -> i{k};\n"
        );
    }
    s + "}\n"
}

/// Lowers, assigns causality and derives; returns the number of states so that nothing is optimised away.
fn derive(text: &str) -> usize {
    let mut sources = SourceMap::new();
    let root = sources.add("bench.bg".to_string(), text.to_string());
    let (models, _) = lower(&mut sources, root, &mut MemoryLoader::new());
    models
        .iter()
        .map(|m| {
            let (c, _) = analyse(m);
            bgc::equations::derive(m, &c).0.states.len()
        })
        .sum()
}

/// Compiles and generates the Rust module (without the runtime); returns its length.
fn generate_rust(text: &str) -> usize {
    let mut sources = SourceMap::new();
    let root = sources.add("bench.bg".to_string(), text.to_string());
    match bgc::codegen::compile(&mut sources, root, &mut MemoryLoader::new()) {
        Ok(compiled) => bgc::codegen::rust::generate_with(
            &compiled,
            "bench.bg",
            bgc::codegen::rust::Options { runtime: false },
        )
        .len(),
        Err(_) => 0,
    }
}

fn rust_family(c: &mut Criterion, name: &str, sizes: &[usize], generate: fn(usize) -> String) {
    let mut group = c.benchmark_group(format!("rust/{name}"));
    group.sample_size(10);
    for &n in sizes {
        let text = generate(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, t| {
            b.iter(|| generate_rust(black_box(t)))
        });
    }
    group.finish();
}

fn family(c: &mut Criterion, name: &str, sizes: &[usize], generate: fn(usize) -> String) {
    let mut group = c.benchmark_group(format!("equations/{name}"));
    group.sample_size(10);
    for &n in sizes {
        let text = generate(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, t| {
            b.iter(|| derive(black_box(t)))
        });
    }
    group.finish();
}

fn bench(c: &mut Criterion) {
    family(c, "ladder", &[3, 6, 12], ladder);
    family(c, "output_chain", &[6, 12, 24], output_chain);
    // Each value of the MTF chain holds the next junction's: the expressions, and so the cost, grow as N².
    family(c, "mtf_chain", &[25, 50, 100], mtf_chain);
    family(c, "benchmark_chain", &[1000, 10_000], benchmark_chain);
    rust_family(c, "output_chain", &[6, 12, 24], output_chain);
    rust_family(c, "benchmark_chain", &[100, 1000, 10000], benchmark_chain);
}

criterion_group!(benches, bench);
criterion_main!(benches);
