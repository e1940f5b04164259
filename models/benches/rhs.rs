//! The generated back-support rhs against a hand-written nalgebra implementation of the paper's Eq. (3)
//! (`ẋ = A x + B u` with `A`, `B` formed once; see `tests/support/eq3.rs`). The generated rhs works in the energy
//! states plus the four angles (10 states) and computes the bond-graph equations directly. `memory_floor` does the
//! loads and stores of `Model::rhs` without its arithmetic.

use bgc_models::back_support as m;
use bgc_runtime::model::ContinuousModel;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::SVector;
use std::hint::black_box;

#[path = "../../runtime/benches/support/clock.rs"]
mod clock;
#[path = "../tests/support/eq3.rs"]
mod eq3;

/// The memory traffic of `Model::rhs` without its arithmetic: the 21 values the back-support rhs reads (6 states,
/// 2 inputs, 8 parameters and 5 parameter terms) loaded one at a time and its 10 rates stored one at a time, as
/// the generated code does, with 11 additions in between; volatile accesses keep the compiler from merging or
/// dropping any of them. The rhs does 25 flops (14 multiplications, 11 additions and subtractions), 6.25 cycles
/// at 4 flops per cycle; these 31 loads and stores take 14–15 cycles on their own on the machines measured
/// (docs/runtime.md). `clock_3000_cycles` converts cycles to nanoseconds on the machine that runs the bench.
fn memory_floor(consts: &[f64; 13], x: &m::State, u: &m::Inputs, dx: &mut m::State) {
    // SAFETY: every pointer comes from a reference to an element of a live array.
    let read = |v: &f64| unsafe { std::ptr::read_volatile(v) };
    let [x0, x1, x2, x3, x4, x5] = std::array::from_fn(|i| read(&x[i]));
    let [u0, u1] = std::array::from_fn(|i| read(&u[i]));
    let c: [f64; 13] = std::array::from_fn(|i| read(&consts[i]));
    let rates = [
        x0 + c[0],
        x1 + c[1],
        x2 + c[2],
        x3 + c[3],
        x4 + c[4],
        x5 + c[5],
        u0 + c[6],
        u1 + c[7],
        c[8] + c[9],
        c[10] + c[11] + c[12],
    ];
    for (d, r) in dx.iter_mut().zip(rates) {
        // SAFETY: as above.
        unsafe { std::ptr::write_volatile(d, r) };
    }
}

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
    // The loads and stores of `model_rhs` alone: the floor of any rhs that reads and writes its values one at a
    // time.
    let consts: [f64; 13] = std::array::from_fn(|i| 1.0 + i as f64);
    group.bench_function("memory_floor", |b| {
        b.iter(|| {
            memory_floor(black_box(&consts), black_box(&x), black_box(&u), &mut dx);
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

/// How many rhs evaluations a UKF step of the back-support model makes: its 2n + 1 = 21 sigma points (n = 10).
const SIGMA_POINTS: usize = 21;

/// The rhs at the 21 sigma points of a UKF step, one after the other, as the filter propagates them: the
/// evaluations are independent, so the core overlaps them and the time per evaluation is a throughput, the
/// quantity a flop bound (flops at 4 per cycle) bounds. The time printed is for all 21; divide by 21.
fn rhs_at_sigma_points(c: &mut Criterion) {
    let model = m::Model::default();
    let u = m::Inputs::new(0.5, 0.1);
    let points: [m::State; SIGMA_POINTS] =
        std::array::from_fn(|k| m::State::from_fn(|i, _| 1e-3 * (i + k + 1) as f64));
    let mut rates = [m::State::zeros(); SIGMA_POINTS];
    let mut group = c.benchmark_group("back_support_rhs_sigma_points");
    group.throughput(criterion::Throughput::Elements(SIGMA_POINTS as u64));
    group.bench_function("model_rhs_x21", |b| {
        b.iter(|| {
            let model = black_box(&model);
            for (x, dx) in black_box(&points).iter().zip(rates.iter_mut()) {
                model.rhs(0.0, x, black_box(&u), dx);
            }
            black_box(&rates);
        })
    });
    group.finish();
}

criterion_group!(benches, clock::clock, rhs, rhs_at_sigma_points);
criterion_main!(benches);
