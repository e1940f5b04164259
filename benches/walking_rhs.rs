//! The generated walking-leg rhs (`bgc_models::walking_leg`: the mass matrix `M(q)` and the forces written out,
//! `M ḟ = F` solved by the generated Gaussian elimination) against the hand-written nalgebra implementation of the
//! same equations (`LegModel::derivative`: `M`, `C q̇`, `G` and friction, solved by nalgebra's Cholesky).

use bgc_models::walking_leg as m;
use bgc_runtime::model::ContinuousModel;
use bgc_workspace::walking::anthropometry::{LegFriction, LegSegments};
use bgc_workspace::walking::plant::LegModel;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Vector3, Vector6};
use std::hint::black_box;

fn rhs(c: &mut Criterion) {
    let p = m::Params::default();
    let x = m::State::from_column_slice(&[0.1, 0.4, -0.2, 0.5, -1.0, 2.0]);
    let u = m::Inputs::from_column_slice(&[5.0, 10.0, 0.0, 2.0, 3.0, 0.0, 0.0]);
    let mut dx = m::State::zeros();
    let mut group = c.benchmark_group("walking_leg_rhs");
    group.bench_function("generated", |b| {
        b.iter(|| {
            m::rhs_into(black_box(&p), 0.0, black_box(&x), black_box(&u), &mut dx);
            black_box(&dx);
        })
    });
    // What the runtime calls: `Model` holds the parameter terms (the derived inertia and gravity constants,
    // `1/eps`, ...); the free `rhs_into` above computes them at each call.
    let model = m::Model::default();
    group.bench_function("model_rhs", |b| {
        b.iter(|| {
            black_box(&model).rhs(0.0, black_box(&x), black_box(&u), &mut dx);
            black_box(&dx);
        })
    });
    let hand = LegModel::new(LegSegments::paper_subject(), LegFriction::table8_right());
    let xh = Vector6::new(0.1, 0.4, -0.2, 0.5, -1.0, 2.0);
    let tau = Vector3::new(0.0, 7.0, 13.0);
    group.bench_function("hand_written", |b| {
        b.iter(|| black_box(black_box(&hand).derivative(black_box(&xh), black_box(&tau))))
    });
    let mut jac = m::JacX::zeros();
    group.bench_function("generated_jac_x", |b| {
        b.iter(|| {
            m::jac_x_into(black_box(&p), 0.0, black_box(&x), black_box(&u), &mut jac);
            black_box(&jac);
        })
    });
    group.finish();
}

criterion_group!(benches, rhs);
criterion_main!(benches);
