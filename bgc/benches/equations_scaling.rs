//! The equations stage (`lower` → `causality::analyse` → `equations::derive`, what `bgc equations` runs) on
//! families of models whose cost must grow with the model, not faster:
//! - a resistor ladder with chained algebraic loops (`rungs`), with one resistance for all and with a resistance per
//!   resistor,
//! - outputs defined through earlier outputs, `y_i = sin(y_{i-1}·y_{i-1}) + cos(y_{i-1})` (`levels`),
//! - a chain of modulated transformers with every inertia but one dependent (`n`),
//! - a gear train of numeric ratios whose efforts each hold the next (`n`),
//! - pairs of resistors in parallel on one junction, each pair an algebraic loop of its own (`n`),
//! - the benchmark chain: `Se` drives mass 1; each 1-junction has `I` (m = 1) and `R` (b = 0.5); a `C` to the
//!   wall at the first; a 0-junction and a `C` between neighbours; `2N` states.
//!
//! The `statespace/...` group times the state space of the ladder whose loops are one linear block (derivation,
//! the block's solve and the implicit-function linearisation at the origin, what `bgc statespace` runs): each
//! residual reads every tear, so its derivatives by them are taken in one reverse walk per residual.
//!
//! The `rust/...` groups time what `bgc rust` does after parsing (equations, Jacobians, code generation) on the
//! benchmark chain, the output chain, the gear train and separate algebraic loops: sparse Jacobians (a row that
//! reads many states in one reverse walk) and shared subexpressions keep them linear in the model.
//!
//! Run with `cargo bench -p bgc --bench equations_scaling`. The same generators, at small sizes, are checked against
//! hand-derived values in `tests/equations_scaling.rs`.

#[path = "support/families.rs"]
mod families;

use bgc::causality::analyse;
use bgc::equations::StateSelection;
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use families::{
    benchmark_chain, gear_train, gyrator_chain, ladder, ladder_distinct, loops_in_series,
    mtf_chain, mtf_chain_with_phases, output_chain, parallel_pairs,
};
use std::hint::black_box;

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

/// Derives and linearises at the origin (exact for a linear model whose loops are solved numerically); returns
/// `A[0][0]` so that nothing is optimised away.
fn state_space(text: &str) -> f64 {
    let mut sources = SourceMap::new();
    let root = sources.add("bench.bg".to_string(), text.to_string());
    let (models, _) = lower(&mut sources, root, &mut MemoryLoader::new());
    let Some(m) = models.first() else {
        return f64::NAN;
    };
    let (c, _) = analyse(m);
    let eqs = bgc::equations::derive(m, &c).0;
    let p = eqs.default_params();
    let (x0, u0) = (vec![0.0; eqs.states.len()], vec![0.0; eqs.inputs.len()]);
    bgc::equations::linearise(&eqs, StateSelection::Energy, &p, &x0, &u0, 0.0).map_or(
        f64::NAN,
        |ss| {
            ss.a.first()
                .and_then(|row| row.first())
                .copied()
                .unwrap_or(f64::NAN)
        },
    )
}

fn state_space_family(
    c: &mut Criterion,
    name: &str,
    sizes: &[usize],
    generate: fn(usize) -> String,
) {
    let mut group = c.benchmark_group(format!("statespace/{name}"));
    group.sample_size(10);
    for &n in sizes {
        let text = generate(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, t| {
            b.iter(|| black_box(state_space(black_box(t))))
        });
    }
    group.finish();
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
    family(c, "ladder", &[3, 6, 12, 50, 100], ladder);
    // A resistance per resistor: nested loops past a size are solved as one linear block, not in closed form.
    family(
        c,
        "ladder_distinct",
        &[6, 12, 24, 48, 96, 384],
        ladder_distinct,
    );
    state_space_family(c, "ladder_distinct", &[96, 192, 384], ladder_distinct);
    family(c, "output_chain", &[6, 12, 24], output_chain);
    // The velocities behind the chain's moduli are found in one walk of the definitions, not one per inertia.
    family(c, "mtf_chain", &[25, 100, 1000], mtf_chain);
    // Distinct moduli: the flows are flat products of distinct factors (the engine keeps products flat); their
    // time derivatives share the tails of those products, so the rates grow with the square of the chain as stored.
    family(
        c,
        "mtf_chain_with_phases",
        &[10, 20, 40, 80],
        mtf_chain_with_phases,
    );
    family(c, "gear_train", &[1000, 10_000], gear_train);
    // Every compliance in derivative causality: the rates are solved by a sparse elimination of the coupled block.
    family(c, "gyrator_chain", &[1000, 10_000], gyrator_chain);
    family(c, "parallel_pairs", &[1000, 10_000], parallel_pairs);
    family(c, "benchmark_chain", &[1000, 10_000], benchmark_chain);
    rust_family(c, "output_chain", &[6, 12, 24], output_chain);
    rust_family(c, "benchmark_chain", &[100, 1000, 10000], benchmark_chain);
    // The rate of the input mass reads every state: its Jacobian row is differentiated in one reverse walk. Each
    // output effort holds every later stage, so `∂h/∂x` has about n²/2 entries and the module grows with the square
    // of the train (121 MB at 1,000 stages, which takes seconds per run): the sizes stay where a run takes a second.
    rust_family(c, "gear_train", &[100, 300], gear_train);
    // Nested code (the mass matrix's Horner chain) is laid out with each part printed only as far as a line holds.
    rust_family(c, "mtf_chain", &[50, 100, 200], mtf_chain);
    // The Jacobians of the distinct moduli's rates: each product's derivative by the angle shares its tails.
    rust_family(
        c,
        "mtf_chain_with_phases",
        &[20, 40, 80],
        mtf_chain_with_phases,
    );
    // Separate diode loops, one block of one tear each: every block corrects the Jacobians with its own matrices,
    // and which tears a function reads is found from the symbols of all its expressions at once.
    rust_family(c, "separate_loops", &[250, 500, 1000], separate_loops);
}

/// `loops` separate diode loops of one capacitor each.
fn separate_loops(loops: usize) -> String {
    loops_in_series(loops, 1)
}

criterion_group!(benches, bench);
criterion_main!(benches);
