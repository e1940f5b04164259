//! Step costs of the estimators: Kalman filter (7 states, 2 measurements), UKF (6 states, 3 measurements)
//! and dual UKF (6 states, 3 parameters).

use bgc_runtime::estimation::dual_ukf::DualUkf;
use bgc_runtime::estimation::{
    KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter,
};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{SMatrix, SVector};
use std::hint::black_box;

#[path = "support/clock.rs"]
mod clock;

/// Three damped pendulums (a 3-joint leg without coupling), masses `w`, semi-implicit Euler at 100 Hz.
fn leg(x: &SVector<f64, 6>, u: &SVector<f64, 3>, w: &SVector<f64, 3>) -> SVector<f64, 6> {
    let dt = 0.01;
    let mut next = *x;
    for j in 0..3 {
        let acc = (u[j] - w[j] * 9.81 * 0.4 * x[j].sin() - 0.5 * x[3 + j]) / (w[j] * 0.16);
        next[3 + j] = x[3 + j] + dt * acc;
        next[j] = x[j] + dt * next[3 + j];
    }
    next
}

fn joints(x: &SVector<f64, 6>) -> SVector<f64, 3> {
    x.fixed_rows::<3>(0).into_owned()
}

/// One predict and update of a 7-state filter with 2 sensors and 1 input.
///
/// Flops (a multiply-add counted as two; the derivation is in `bgc_runtime::estimation::kalman`'s docs): the
/// arithmetic a step cannot do without, `3 n³ + 4 n² m + 5 n m² + 3 n² + 7 n m + 2 p (n + m)` with `n = 7`,
/// `m = 2`, `p = 1`, is 1,029 + 392 + 140 + 147 + 98 + 18 = 1,824, about 1,850 with the factor and solves of
/// the 2 × 2 `S`; the step executes about 2,000 (whole columns of `P Aᵀ`, blocks of four rows down to the
/// diagonal of the symmetric products, the certificates that replace the definiteness test of `P`). At 4 flops
/// per cycle (two multiplies and two adds per cycle, scalar) the bound of 1,850 flops is 462 cycles, and 1.5
/// times it 694 cycles; `clock_3000_cycles` in the same bench converts cycles to nanoseconds on the machine
/// that runs it (`support/clock.rs`). The hardware's peak is higher: twice that with two-wide vectors (SSE2,
/// the default target), four times with AVX2 and FMA, which the step uses where the processor has them.
fn kalman_step(c: &mut Criterion) {
    let mut a = SMatrix::<f64, 7, 7>::identity();
    for i in 0..6 {
        a[(i, i + 1)] = 0.001;
    }
    a[(6, 0)] = -0.002;
    let model = LinearDiscreteModel {
        a,
        b: SMatrix::<f64, 7, 1>::from_fn(|i, _| 0.001 * (i + 1) as f64),
        c: SMatrix::<f64, 2, 7>::from_fn(|i, j| if j == 3 * i { 1.0 } else { 0.0 }),
        d: SMatrix::<f64, 2, 1>::zeros(),
    };
    let mut kf = KalmanFilter::new(
        model,
        SMatrix::<f64, 7, 7>::identity() * 1e-4,
        SMatrix::<f64, 2, 2>::identity() * 1e-2,
        SVector::<f64, 7>::zeros(),
        SMatrix::<f64, 7, 7>::identity(),
    )
    .expect("valid filter");
    let u = SVector::<f64, 1>::new(0.3);
    let y = SVector::<f64, 2>::new(0.01, -0.02);
    c.bench_function("kf_step_7x2", |b| {
        b.iter(|| {
            kf.predict(black_box(&u)).expect("predict");
            black_box(kf.update(black_box(&y), &u).expect("update"));
        })
    });
}

fn ukf_step(c: &mut Criterion) {
    let w = SVector::<f64, 3>::new(8.0, 3.5, 1.2);
    let mut ukf = UnscentedKalmanFilter::<6, 3, 3, 13>::new(
        SigmaPoints::new(0.5, 2.0, 0.0).expect("weights"),
        SMatrix::<f64, 6, 6>::identity() * 1e-5,
        SMatrix::<f64, 3, 3>::identity() * 1e-3,
        SVector::<f64, 6>::repeat(0.1),
        SMatrix::<f64, 6, 6>::identity() * 0.01,
    )
    .expect("valid filter");
    let u = SVector::<f64, 3>::new(1.0, 0.5, 0.2);
    let y = SVector::<f64, 3>::new(0.1, 0.1, 0.1);
    c.bench_function("ukf_step_6x3", |b| {
        b.iter(|| {
            ukf.predict(black_box(&u), |x, u| leg(x, u, &w))
                .expect("predict");
            black_box(
                ukf.update(black_box(&y), &u, |x, _| joints(x))
                    .expect("update"),
            );
        })
    });
}

fn dual_ukf_step(c: &mut Criterion) {
    let state = UnscentedKalmanFilter::<6, 3, 3, 13>::new(
        SigmaPoints::new(0.5, 2.0, 0.0).expect("weights"),
        SMatrix::<f64, 6, 6>::identity() * 1e-5,
        SMatrix::<f64, 3, 3>::identity() * 1e-3,
        SVector::<f64, 6>::repeat(0.1),
        SMatrix::<f64, 6, 6>::identity() * 0.01,
    )
    .expect("valid filter");
    let mut dual = DualUkf::new(
        state,
        SigmaPoints::<3, 7>::new(0.5, 2.0, 0.0).expect("weights"),
        SVector::<f64, 3>::new(8.0, 3.5, 1.2),
        SMatrix::<f64, 3, 3>::identity() * 0.01,
        0.995,
    )
    .expect("valid dual filter");
    let u = SVector::<f64, 3>::new(1.0, 0.5, 0.2);
    let y = SVector::<f64, 3>::new(0.1, 0.1, 0.1);
    c.bench_function("dual_ukf_step_6x3_p3", |b| {
        b.iter(|| {
            black_box(
                dual.step_with(black_box(&u), black_box(&y), leg, |x, _u, _w| joints(x))
                    .expect("step"),
            );
        })
    });
}

criterion_group!(benches, clock::clock, kalman_step, ukf_step, dual_ukf_step);
criterion_main!(benches);
