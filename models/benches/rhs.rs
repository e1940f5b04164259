//! The generated back-support rhs against a hand-written nalgebra implementation of the paper's Eq. (3)
//! (`ẋ = A x + B u` with `A`, `B` formed once; see `tests/support/eq3.rs`). The generated rhs works in the energy
//! states plus the four angles (10 states) and computes the bond-graph equations directly.

use bgc_models::back_support as m;
use bgc_runtime::model::ContinuousModel;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::SVector;
use std::hint::black_box;

#[path = "../tests/support/eq3.rs"]
mod eq3;

fn rhs(c: &mut Criterion) {
    let p = m::Params::default();
    let x = m::State::from_fn(|i, _| 1e-3 * (i as f64 + 1.0));
    let u = m::Inputs::new(0.5, 0.1);
    let mut dx = m::State::zeros();
    let mut group = c.benchmark_group("back_support_rhs");
    group.bench_function("generated", |b| {
        b.iter(|| {
            m::rhs_into(black_box(&p), 0.0, black_box(&x), black_box(&u), &mut dx);
            black_box(&dx);
        })
    });
    // What the runtime calls: `Model` holds the parameter terms (`1/J_m`, `J_m/(J_m + J_g)`, ...), so its rhs
    // divides by no parameter; the free `rhs_into` above computes the terms at each call.
    let model = m::Model::default();
    group.bench_function("model_rhs", |b| {
        b.iter(|| {
            black_box(&model).rhs(0.0, black_box(&x), black_box(&u), &mut dx);
            black_box(&dx);
        })
    });
    let hand = eq3::Eq3::new(&eq3::Eq3Params::of(&p));
    let x7 = SVector::<f64, 7>::from_fn(|i, _| 1e-3 * (i as f64 + 1.0));
    let mut dx7 = SVector::<f64, 7>::zeros();
    group.bench_function("hand_written_eq3", |b| {
        b.iter(|| {
            black_box(&hand).rhs(black_box(&x7), black_box(&u), &mut dx7);
            black_box(&dx7);
        })
    });
    let mut jac = m::JacX::zeros();
    group.bench_function("generated_jac_x", |b| {
        b.iter(|| {
            m::jac_x_into(black_box(&p), 0.0, black_box(&x), black_box(&u), &mut jac);
            black_box(&jac);
        })
    });
    // What the runtime calls (Kalman filters, linearisation, implicit solvers): a linear model's Jacobian is
    // the same at every point, so `Model` holds it.
    group.bench_function("model_jac_x", |b| {
        b.iter(|| {
            black_box(&model).jac_x(0.0, black_box(&x), black_box(&u), &mut jac);
            black_box(&jac);
        })
    });
    group.finish();
}

criterion_group!(benches, rhs);
criterion_main!(benches);
