//! The time `rustc` takes to compile the generated module of a 999-state chain (500 masses joined by springs and
//! dampers: `codegen_support::chain(500)`), without the runtime's impls, in a debug (`-C opt-level=0`) and an
//! optimised (`-O`) build. The module is compiled on its own against the minimal `no_std` stand-ins of `nalgebra`
//! and `libm` that the no-std test uses, so the figure is the generated code's own compile time, not the
//! dependencies'. Generating the module (parse to Rust text) is timed separately.

#[path = "../tests/codegen_support/mod.rs"]
mod codegen_support;
#[path = "../tests/scratch.rs"]
mod scratch;

use bgc::codegen::{self, rust};
use bgc::lower::MemoryLoader;
use bgc::span::SourceMap;
use codegen_support::rustc::{compile_no_std_with, stand_ins};
use codegen_support::{chain, scratch};
use criterion::{Criterion, criterion_group, criterion_main};
use std::time::Duration;

fn generate(text: &str) -> String {
    let mut sources = SourceMap::new();
    let id = sources.add("chain.bg", text.to_string());
    let compiled = codegen::compile(&mut sources, id, &mut MemoryLoader::new())
        .unwrap_or_else(|d| panic!("the chain does not compile: {d:?}"));
    rust::generate_with(&compiled, "chain.bg", rust::Options { runtime: false })
}

fn bench(c: &mut Criterion) {
    let text = chain(500);
    let module = generate(&text);
    assert!(module.contains("pub const N_STATES: usize = 999;"));
    let dir = scratch("compile-bench");
    stand_ins(&dir);
    let mut group = c.benchmark_group("chain_999_states");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(30));
    group.bench_function("generate_rust", |b| b.iter(|| generate(&text)));
    for (name, args) in [
        ("rustc_debug", &["-C", "opt-level=0"][..]),
        ("rustc_release", &["-O"][..]),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                compile_no_std_with(&dir, "chain", &module, args)
                    .unwrap_or_else(|e| panic!("the generated chain does not compile: {e}"))
            })
        });
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
