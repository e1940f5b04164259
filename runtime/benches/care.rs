//! CARE on the ill-scaled 8-state back-support design (plant of Eq. 3 with two integrators, Eq. 12; weights of
//! Eq. 15: Q up to 5·10¹⁵, R = 10¹²).

use std::hint::black_box;

use bgc_runtime::linalg::care;
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::DMatrix;

fn back_support_8() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (jm, jg, rg, kg) = (3.06e-4, 0.40e-4, 160.0, 2.64e4);
    let (jsi, jse, ks) = (1e-4, 1.19e-3, 3.38e4);
    let (bg, dg, keh) = (0.65, 6.0, 1125.0);
    let j = jm + jg;
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(8, 8, &[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        -kg / (j * rg * rg), -(bg + dg) / (j * rg * rg), kg / (j * rg), dg / (j * rg), 0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0,
        kg / (jsi * rg), dg / (jsi * rg), -(kg + ks) / jsi, -dg / jsi, ks / jsi, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, ks / jse, 0.0, -(keh + ks) / jse, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, -keh, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
    ]);
    let b = DMatrix::from_row_slice(8, 1, &[0.0, 1.0 / j, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let q = DMatrix::from_diagonal(&nalgebra::dvector![
        1e5, 1e5, 1e7, 1e7, 1e7, 1e7, 5e13, 5e15
    ]);
    let r = DMatrix::from_element(1, 1, 1e12);
    (a, b, q, r)
}

fn bench_care(c: &mut Criterion) {
    let (a, b, q, r) = back_support_8();
    c.bench_function("care_back_support_8x8", |bench| {
        bench.iter(|| care(black_box(&a), black_box(&b), black_box(&q), black_box(&r)))
    });
}

criterion_group!(benches, bench_care);
criterion_main!(benches);
