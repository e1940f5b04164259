//! The well-scaled CARE of a damped mass–spring chain (`n/2` unit masses, springs 1, dampers 0.1, the first
//! mass tied to a wall, the force on the last), `Q = I`, `R = 1`, at `n = 20, 50, 100, 200` states.
//! `care_chain_reference.py` (beside this file) times scipy and slycot on the same matrices.

use std::hint::black_box;
use std::time::Duration;

use bgc_runtime::linalg::care;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::DMatrix;

/// States `[q₁, v₁, q₂, v₂, …]`; mass `i` feels `−k(qᵢ − qᵢ₋₁) − k(qᵢ − qᵢ₊₁)` and the same with `c` on the
/// velocities, with `q₀ = 0` (wall) and no neighbour beyond the last mass.
fn chain(n: usize) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (k, c) = (1.0, 0.1);
    let masses = n / 2;
    let mut a = DMatrix::<f64>::zeros(n, n);
    for i in 0..masses {
        let (q, v) = (2 * i, 2 * i + 1);
        a[(q, v)] = 1.0;
        let neighbours = if i + 1 < masses { 2.0 } else { 1.0 };
        a[(v, q)] = -k * neighbours;
        a[(v, v)] = -c * neighbours;
        if i > 0 {
            a[(v, q - 2)] = k;
            a[(v, v - 2)] = c;
        }
        if i + 1 < masses {
            a[(v, q + 2)] = k;
            a[(v, v + 2)] = c;
        }
    }
    let mut b = DMatrix::<f64>::zeros(n, 1);
    b[(n - 1, 0)] = 1.0;
    (a, b, DMatrix::identity(n, n), DMatrix::identity(1, 1))
}

fn bench_care_chain(c: &mut Criterion) {
    let mut group = c.benchmark_group("care_chain");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    for n in [20, 50, 100, 200] {
        let (a, b, q, r) = chain(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |bench, _| {
            bench.iter(|| care(black_box(&a), black_box(&b), black_box(&q), black_box(&r)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_care_chain);
criterion_main!(benches);
