//! The back-support loop of Sec. 5.2 in miniature: the six-state drive and series-elastic sensor of Eq. 3
//! (motor torque in; motor velocity and sensor torque measured), a discrete LQR on the estimate of a
//! fixed-gain Kalman filter, 1.5 s at 1 kHz with process and measurement noise. `ode` integrates the plant by
//! BDF solves (one per sample, as for any model), `zoh` steps it by its exact zero-order-hold discretisation.

use std::hint::black_box;

use bgc_runtime::design::{dlqe, dlqr};
use bgc_runtime::linalg::expm;
use bgc_runtime::model::ContinuousModel;
use bgc_runtime::sim::{
    LinearPlant, SampledLoopConfig, simulate_sampled_linear_loop, simulate_sampled_loop,
};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, SMatrix, SVector};

const NX: usize = 6;
const T: f64 = 1e-3;

/// The plant of Eq. 3 with the paper's parameters (states θ_m, θ̇_m, θ_si, θ̇_si, θ_se, θ̇_se).
fn plant() -> LinearPlant<NX, 1, 2> {
    let (jm, jg, rg, kg) = (3.06e-4, 0.40e-4, 160.0, 2.64e4);
    let (jsi, jse, ks) = (1e-4, 1.19e-3, 3.38e4);
    let (bg, dg, keh) = (0.65, 6.0, 1125.0);
    let j = jm + jg;
    #[rustfmt::skip]
    let a = SMatrix::<f64, NX, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0,
        -kg / (j * rg * rg), -(bg + dg) / (j * rg * rg), kg / (j * rg), dg / (j * rg), 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
        kg / (jsi * rg), dg / (jsi * rg), -(kg + ks) / jsi, -dg / jsi, ks / jsi, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        0.0, 0.0, ks / jse, 0.0, -(keh + ks) / jse, 0.0,
    ]);
    let b = SMatrix::<f64, NX, 1>::from_column_slice(&[0.0, 1.0 / j, 0.0, 0.0, 0.0, 0.0]);
    #[rustfmt::skip]
    let c = SMatrix::<f64, 2, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, ks, 0.0, -ks, 0.0,
    ]);
    LinearPlant::new(a, b, c, SMatrix::zeros())
}

/// The ODE path sees the plant only through the model trait, as it sees a generated model.
struct AsModel(LinearPlant<NX, 1, 2>);

impl ContinuousModel<NX, 1, 2> for AsModel {
    fn rhs(&self, t: f64, x: &SVector<f64, NX>, u: &SVector<f64, 1>, dx: &mut SVector<f64, NX>) {
        self.0.rhs(t, x, u, dx)
    }
    fn outputs(&self, t: f64, x: &SVector<f64, NX>, u: &SVector<f64, 1>, y: &mut SVector<f64, 2>) {
        self.0.outputs(t, x, u, y)
    }
    fn jac_x(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, 1>,
        j: &mut SMatrix<f64, NX, NX>,
    ) {
        self.0.jac_x(t, x, u, j)
    }
}

/// `x̂ ← A_d x̂ + B_d u`, `x̂ ← x̂ + M (y − C x̂)`, `u = −K x̂`.
#[derive(Clone)]
struct Observer {
    ad: SMatrix<f64, NX, NX>,
    bd: SMatrix<f64, NX, 1>,
    c: SMatrix<f64, 2, NX>,
    m: SMatrix<f64, NX, 2>,
    k: SMatrix<f64, 1, NX>,
    x_hat: SVector<f64, NX>,
    u: SVector<f64, 1>,
}

impl Observer {
    fn design(p: &LinearPlant<NX, 1, 2>) -> Observer {
        let mut big = DMatrix::<f64>::zeros(NX + 1, NX + 1);
        big.view_mut((0, 0), (NX, NX)).copy_from(&(*p.a * T));
        big.view_mut((0, NX), (NX, 1)).copy_from(&(*p.b * T));
        let e = expm(&big).expect("the plant discretises");
        let ad = DMatrix::from_fn(NX, NX, |i, j| e[(i, j)]);
        let bd = DMatrix::from_fn(NX, 1, |i, _| e[(i, NX)]);
        let c = DMatrix::from_fn(2, NX, |i, j| p.c[(i, j)]);
        let q = DMatrix::from_diagonal(&nalgebra::dvector![1e3, 1.0, 1e3, 1.0, 1e3, 1.0]);
        let lqr = dlqr(&ad, &bd, &q, &DMatrix::from_element(1, 1, 1.0)).expect("LQR");
        let rn = DMatrix::from_diagonal(&nalgebra::dvector![1e-4, 1e-2]);
        let kf = dlqe(&ad, &bd, &c, &DMatrix::from_element(1, 1, 1e-2), &rn).expect("Kalman");
        Observer {
            ad: SMatrix::from_fn(|i, j| ad[(i, j)]),
            bd: SMatrix::from_fn(|i, _| bd[(i, 0)]),
            c: *p.c,
            m: SMatrix::from_fn(|i, j| kf.filter_gain[(i, j)]),
            k: SMatrix::from_fn(|_, j| lqr.k[(0, j)]),
            x_hat: SVector::zeros(),
            u: SVector::zeros(),
        }
    }

    fn update(&mut self, y: &SVector<f64, 2>) -> SVector<f64, 1> {
        self.x_hat = self.ad * self.x_hat + self.bd * self.u;
        self.x_hat += self.m * (y - self.c * self.x_hat);
        self.u = -(self.k * self.x_hat);
        self.u
    }
}

fn config() -> SampledLoopConfig<NX, 1, 2> {
    let mut cfg = SampledLoopConfig::new(T, 1500, SVector::zeros());
    cfg.x0[1] = 1.0;
    cfg.measurement_noise_std = SVector::<f64, 2>::new(1e-2, 1e-1);
    cfg.process_noise_std[1] = 10.0;
    cfg.seed = 2020;
    cfg
}

fn bench_sampled_loop(c: &mut Criterion) {
    let p = plant();
    let cfg = config();
    let model = AsModel(p.clone());
    let designed = Observer::design(&p);
    let mut group = c.benchmark_group("back_support_loop_1500");
    group.sample_size(20);
    group.bench_function("ode", |bench| {
        bench.iter(|| {
            let mut obs = designed.clone();
            let mut ctl = |_k: usize, _t: f64, y: &SVector<f64, 2>| obs.update(y);
            simulate_sampled_loop(black_box(&model), &mut ctl, black_box(&cfg))
        })
    });
    group.bench_function("zoh", |bench| {
        bench.iter(|| {
            let mut obs = designed.clone();
            let mut ctl = |_k: usize, _t: f64, y: &SVector<f64, 2>| obs.update(y);
            simulate_sampled_linear_loop(black_box(&p), &mut ctl, black_box(&cfg))
        })
    });
    group.finish();
}

criterion_group!(benches, bench_sampled_loop);
criterion_main!(benches);
