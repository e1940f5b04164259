//! The sampled-data loop against exact discrete recursions.

use bgc_runtime::model::ContinuousModel;
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{Method, SampledLoopConfig, SimError, SolverOptions, simulate_sampled_loop};
use nalgebra::Vector1;

/// ẋ = −a x + b u, y = x.
struct FirstOrder {
    a: f64,
    b: f64,
}

impl ContinuousModel<1, 1, 1> for FirstOrder {
    fn rhs(&self, _t: f64, x: &Vector1<f64>, u: &Vector1<f64>, dx: &mut Vector1<f64>) {
        dx[0] = -self.a * x[0] + self.b * u[0];
    }
    fn outputs(&self, _t: f64, x: &Vector1<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
}

const T: f64 = 0.1;
const KI: f64 = 0.2;
const R: f64 = 1.0;

fn tight(method: Method) -> SolverOptions {
    SolverOptions {
        method,
        rtol: 1e-12,
        atol: 1e-14,
        ..SolverOptions::default()
    }
}

/// The exact zero-order-hold equivalent: x[k+1] = φ x[k] + γ u[k], φ = e^{−aT}, γ = b (1 − φ) / a.
fn zoh(p: &FirstOrder) -> (f64, f64) {
    let phi = (-p.a * T).exp();
    (phi, p.b * (1.0 - phi) / p.a)
}

#[test]
fn integral_loop_matches_exact_discrete_recursion() {
    let plant = FirstOrder { a: 2.0, b: 3.0 };
    let (phi, gamma) = zoh(&plant);
    for method in [Method::Bdf, Method::Esdirk34, Method::Tsit45] {
        let mut u_acc = 0.0;
        let mut controller = |_k: usize, _t: f64, y: &Vector1<f64>| {
            u_acc += KI * (R - y[0]);
            Vector1::new(u_acc)
        };
        let mut cfg = SampledLoopConfig::new(T, 60, Vector1::new(0.5));
        cfg.solver = tight(method);
        let traj = simulate_sampled_loop(&plant, &mut controller, &cfg).unwrap();
        assert_eq!(traj.times.len(), 61);
        assert_eq!(traj.inputs.len(), 60);

        let (mut x, mut u) = (0.5, 0.0);
        for k in 0..60 {
            assert!((traj.states[k][0] - x).abs() < 1e-9, "{method:?} k={k}");
            u += KI * (R - x);
            assert!((traj.inputs[k][0] - u).abs() < 1e-9, "{method:?} k={k}");
            x = phi * x + gamma * u;
            assert!((traj.times[k] - k as f64 * T).abs() < 1e-15);
        }
        assert!((traj.states[60][0] - x).abs() < 1e-9);
        // The integral action has nearly removed the error by then.
        assert!((x - R).abs() < 0.05, "{x}");
    }
}

#[test]
fn delayed_noisy_measurements_follow_the_documented_order() {
    let plant = FirstOrder { a: 1.0, b: 1.0 };
    let (phi, gamma) = zoh(&plant);
    let (sigma, delay, seed) = (0.01, 2, 42);
    let mut u_acc = 0.0;
    let mut controller = |_k: usize, _t: f64, y: &Vector1<f64>| {
        u_acc += KI * (R - y[0]);
        Vector1::new(u_acc)
    };
    let mut cfg = SampledLoopConfig::new(T, 40, Vector1::new(0.0));
    cfg.solver = tight(Method::Bdf);
    cfg.measurement_delay = delay;
    cfg.measurement_noise_std = Vector1::new(sigma);
    cfg.seed = seed;
    let traj = simulate_sampled_loop(&plant, &mut controller, &cfg).unwrap();

    // Exact recursion with the same noise stream: y_k = x_k + v_k, the controller sees y_{max(k−2, 0)}.
    let mut rng = Rng::new(seed);
    let (mut x, mut u) = (0.0, 0.0);
    let mut ys = Vec::new();
    for k in 0..40 {
        ys.push(x + rng.gaussian(0.0, sigma));
        assert!((traj.measurements[k][0] - ys[k]).abs() < 1e-9, "k={k}");
        u += KI * (R - ys[k.saturating_sub(delay)]);
        assert!((traj.inputs[k][0] - u).abs() < 1e-9, "k={k}");
        x = phi * x + gamma * u;
        assert!((traj.states[k + 1][0] - x).abs() < 1e-9, "k={k}");
    }
}

#[test]
fn process_noise_is_a_held_derivative_disturbance() {
    // A pure integrator ẋ = w_k: each interval adds exactly T w_k, with w_k drawn in order from the seed.
    let plant = FirstOrder { a: 0.0, b: 0.0 };
    let mut cfg = SampledLoopConfig::new(T, 20, Vector1::new(0.0));
    cfg.process_noise_std = Vector1::new(3.0);
    cfg.seed = 7;
    let mut hold = |_k: usize, _t: f64, _y: &Vector1<f64>| Vector1::new(0.0);
    let traj = simulate_sampled_loop(&plant, &mut hold, &cfg).unwrap();
    let mut rng = Rng::new(7);
    for k in 0..20 {
        let w = rng.gaussian(0.0, 3.0);
        let step = traj.states[k + 1][0] - traj.states[k][0];
        assert!((step - T * w).abs() < 1e-9, "k={k}: {step} vs {}", T * w);
    }
    // Same seed, same run; another seed, another run.
    let again = simulate_sampled_loop(&plant, &mut hold, &cfg).unwrap();
    assert_eq!(again, traj);
    cfg.seed = 8;
    let other = simulate_sampled_loop(&plant, &mut hold, &cfg).unwrap();
    assert_ne!(other.states, traj.states);
}

#[test]
fn nan_controller_output_is_an_error_with_its_time() {
    let plant = FirstOrder { a: 1.0, b: 1.0 };
    let mut bad =
        |k: usize, _t: f64, _y: &Vector1<f64>| Vector1::new(if k < 3 { 1.0 } else { f64::NAN });
    let cfg = SampledLoopConfig::new(T, 10, Vector1::new(0.0));
    let err = simulate_sampled_loop(&plant, &mut bad, &cfg).unwrap_err();
    match err {
        SimError::NonFiniteInput { time, index: 0 } => assert!((time - 0.3).abs() < 1e-12),
        other => panic!("unexpected {other}"),
    }
    let bad_dt = SampledLoopConfig::new(0.0, 10, Vector1::new(0.0));
    assert!(matches!(
        simulate_sampled_loop(&plant, &mut bad, &bad_dt),
        Err(SimError::BadSetting {
            name: "sample_time",
            ..
        })
    ));
}
