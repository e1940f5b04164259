//! `bgc simulate`'s integration (what the command runs after deriving: the compiled system and diffsol) on the
//! benchmark chain of `N` masses (`2N` states), `u = sin(3t)`, 0.01 s on BDF. From 200 states on the implicit
//! methods factorise a sparse Jacobian, so the time grows with the number of non-zeros.
//!
//! `simulate/mtf_chain` derives, compiles and runs the chain of `N` modulated transformers (two states, one mass-matrix
//! row whose inertia sums products of all the moduli): the compiled programs compute each shared node once, so
//! their length and the time grow with `N`, not with the expressions as trees (`N²`).
//!
//! `simulate/gear_train` runs the gear train of `N` stages with an output at every stage for 101 rows: each
//! output's effort holds the next one's, and all outputs are one program, so a row costs the train, not its
//! square.
//!
//! `simulate/loops_in_series` runs `N` separate diode loops of ten capacitors each (`10N` states, a nonlinear
//! algebraic loop per diode): the Jacobian takes each loop's implicit derivatives, so it stays block-diagonal and
//! the sparse LU's cost grows with `N` (with finite differences and a dense LU it grew as `N³`).
//!
//! `simulate/ladder` runs the resistor ladder of `N` rungs (one state, one block of linear loops of about `N`
//! tears): its `∂r/∂z` reads parameters only and is factored once per run, so a solve costs the block's residuals.
//!
//! Run with `cargo bench -p bgc --bench simulate_scaling`.

#[path = "support/families.rs"]
mod families;

use bgc::causality::analyse;
use bgc::lower::{MemoryLoader, lower};
use bgc::simulate::System;
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run};
use bgc::span::SourceMap;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use families::{benchmark_chain, gear_train, ladder, loops_in_series, mtf_chain};
use std::hint::black_box;

/// The compiled system of a model with one input, driven by `sin(3t)`.
fn system_of(text: String) -> Option<System> {
    let mut sources = SourceMap::new();
    let root = sources.add("bench.bg".to_string(), text);
    let (models, _) = lower(&mut sources, root, &mut MemoryLoader::new());
    let model = models.first()?;
    let (causality, _) = analyse(model);
    let (eqs, _) = bgc::equations::derive(model, &causality);
    let drive = Signal::parse("sin(3*t)").ok()?;
    let (system, _) = System::new(&eqs, eqs.default_params(), vec![drive]).ok()?;
    Some(system)
}

/// Benchmarks the run of `model(n)` for each size `n`, compiled once outside the timing.
fn run_group(
    c: &mut Criterion,
    name: &str,
    sizes: &[usize],
    model: fn(usize) -> String,
    opts: &RunOptions,
) {
    let mut group = c.benchmark_group(name);
    group.sample_size(10);
    for &n in sizes {
        let Some(system) = system_of(model(n)) else {
            continue;
        };
        let x0 = vec![0.0; system.state_count()];
        group.bench_with_input(BenchmarkId::from_parameter(n), &system, |b, s| {
            b.iter(|| run(black_box(s), &x0, opts).map(|t| t.times.len()))
        });
    }
    group.finish();
}

fn bench(c: &mut Criterion) {
    let opts = RunOptions {
        t_end: 0.01,
        dt_out: 0.01,
        method: Method::Bdf,
        rtol: 1e-6,
        atol: 1e-9,
        max_steps: 100_000,
        max_step: None,
    };
    run_group(
        c,
        "simulate/benchmark_chain",
        &[100, 1000, 10_000],
        benchmark_chain,
        &opts,
    );
    let mut group = c.benchmark_group("simulate/mtf_chain");
    group.sample_size(10);
    for n in [250, 1000] {
        let text = mtf_chain(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, t| {
            b.iter(|| {
                let s = system_of(black_box(t.clone()))?;
                run(&s, &vec![0.0; s.state_count()], &opts)
                    .ok()
                    .map(|t| t.times.len())
            })
        });
    }
    group.finish();
    let ten_caps = |n| loops_in_series(n, 10);
    run_group(c, "simulate/loops_in_series", &[50, 200], ten_caps, &opts);
    run_group(c, "simulate/ladder", &[100], ladder, &opts);
    let rows = RunOptions {
        dt_out: 1e-4,
        ..opts
    };
    run_group(c, "simulate/gear_train", &[1000, 4000], gear_train, &rows);
}

criterion_group!(benches, bench);
criterion_main!(benches);
