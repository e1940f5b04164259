//! Parsing throughput on a generated model of 100,000 elements and 100,000 bonds.
//!
//! Run with `cargo bench -p bgc --bench parse -- --quick`.

use bgc::span::FileId;
use bgc::syntax::{format, parse};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::fmt::Write;
use std::hint::black_box;

const ELEMENTS: usize = 100_000;

/// A ladder of `ELEMENTS / 4` cells, each a 1-junction with an inertia and a damper and a 0-junction with a spring:
/// `ELEMENTS` elements and as many bonds, with parameters, comments and a nonlinear law every hundred cells.
fn model() -> String {
    let cells = ELEMENTS / 4;
    let mut s = String::with_capacity(ELEMENTS * 60);
    s.push_str("/// A generated ladder.\nmodel ladder {\n    domain translational;\n");
    s.push_str("    param m = 0.5 [kg] \"cell mass\";\n    param k = 2.5e3 [N/m];\n    param d = 1.5 [N s/m];\n");
    s.push_str("    input F [N];\n    Se push = F;\n");
    for i in 0..cells {
        let _ = writeln!(s, "    // cell {i}");
        let _ = writeln!(s, "    1 v{i};");
        let _ = writeln!(s, "    I m{i} = m * (1 + {i} / {cells});");
        if i % 100 == 0 {
            let _ = writeln!(s, "    R d{i} {{ e = d * f + 0.1 * f ^ 3; }}");
        } else {
            let _ = writeln!(s, "    R d{i} = d;");
        }
        let _ = writeln!(s, "    0 n{i};");
        let _ = writeln!(s, "    C k{i} = 1 / k;");
        let _ = writeln!(s, "    bond v{i} -> m{i}, d{i};");
        let _ = writeln!(s, "    bond s{i}: v{i} -> n{i};");
        let _ = writeln!(s, "    bond n{i} -> k{i} stroke k{i};");
        if i + 1 < cells {
            let _ = writeln!(s, "    bond n{i} -> v{};", i + 1);
        }
    }
    s.push_str("    bond push -> v0;\n    output x [m] = q(k0) + q(k1);\n}\n");
    s
}

fn bench(c: &mut Criterion) {
    let src = model();
    let (tree, diags) = parse(FileId(0), &src);
    assert!(
        diags.is_empty(),
        "the generated model has errors: {:?}",
        diags.first()
    );
    let mut group = c.benchmark_group("parse");
    // Parsing alone (the tree is dropped outside the timing), then parsing and dropping the tree, which frees
    // several hundred thousand small allocations.
    group.throughput(Throughput::Bytes(src.len() as u64));
    group.bench_function("ladder_100k_elements_bytes", |b| {
        b.iter_with_large_drop(|| parse(FileId(0), black_box(&src)))
    });
    group.throughput(Throughput::Elements(ELEMENTS as u64));
    group.bench_function("ladder_100k_elements", |b| {
        b.iter_with_large_drop(|| parse(FileId(0), black_box(&src)))
    });
    group.bench_function("ladder_100k_elements_with_drop", |b| {
        b.iter(|| parse(FileId(0), black_box(&src)))
    });
    group.throughput(Throughput::Bytes(src.len() as u64));
    group.bench_function("format_100k_elements_bytes", |b| {
        b.iter(|| format(black_box(&tree)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
