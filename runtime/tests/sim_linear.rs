//! The sampled-data loop of a linear plant (exact zero-order hold) against hand recursions and against the
//! ODE path; the streaming variants and the bounds on the run's length; the Jacobian handed to diffsol.

use std::cell::RefCell;
use std::ops::ControlFlow;

use bgc_runtime::model::ContinuousModel;
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{
    LinearPlant, Method, SampledLoopConfig, SimError, SolverOptions, simulate_sampled_linear_loop,
    simulate_sampled_linear_loop_streaming, simulate_sampled_loop, simulate_sampled_loop_streaming,
};
use nalgebra::{Matrix1, SMatrix, SVector, Vector1, Vector2};

const T: f64 = 0.1;

fn first_order(a: f64, b: f64) -> LinearPlant<1, 1, 1> {
    LinearPlant::new(
        Matrix1::new(-a),
        Matrix1::new(b),
        Matrix1::new(1.0),
        Matrix1::new(0.0),
    )
}

/// ẋ = −a x + b u under zero-order hold: x[k+1] = φ x[k] + γ u[k], φ = e^{−aT}, γ = b (1 − φ) / a (by hand);
/// the controller integrates the error of the measurement delivered two samples late.
#[test]
fn linear_loop_is_the_exact_recursion_with_delay_and_noise() {
    let (a, b, ki, r) = (1.0, 1.0, 0.2, 1.0);
    let (phi, gamma) = ((-a * T).exp(), b * (1.0 - (-a * T).exp()) / a);
    let (sigma, delay, seed) = (0.01, 2, 42);
    let mut u_acc = 0.0;
    let mut controller = |_k: usize, _t: f64, y: &Vector1<f64>| {
        u_acc += ki * (r - y[0]);
        Vector1::new(u_acc)
    };
    let mut cfg = SampledLoopConfig::new(T, 40, Vector1::new(0.0));
    cfg.measurement_delay = delay;
    cfg.measurement_noise_std = Vector1::new(sigma);
    cfg.seed = seed;
    let traj = simulate_sampled_linear_loop(&first_order(a, b), &mut controller, &cfg).unwrap();
    assert_eq!((traj.times.len(), traj.inputs.len()), (41, 40));
    let mut rng = Rng::new(seed);
    let (mut x, mut u) = (0.0, 0.0);
    let mut ys = Vec::new();
    for k in 0..40 {
        ys.push(x + rng.gaussian(0.0, sigma));
        assert!((traj.measurements[k][0] - ys[k]).abs() < 1e-14, "k={k}");
        u += ki * (r - ys[k.saturating_sub(delay)]);
        assert!((traj.inputs[k][0] - u).abs() < 1e-14, "k={k}");
        x = phi * x + gamma * u;
        assert!((traj.states[k + 1][0] - x).abs() < 1e-14, "k={k}");
    }
}

/// A pure integrator ẋ = w_k gains exactly T w_k per interval.
#[test]
fn linear_loop_holds_the_process_disturbance() {
    let mut cfg = SampledLoopConfig::new(T, 20, Vector1::new(0.0));
    cfg.process_noise_std = Vector1::new(3.0);
    cfg.seed = 7;
    let mut hold = |_k: usize, _t: f64, _y: &Vector1<f64>| Vector1::new(0.0);
    let traj = simulate_sampled_linear_loop(&first_order(0.0, 0.0), &mut hold, &cfg).unwrap();
    let mut rng = Rng::new(7);
    for k in 0..20 {
        let w = rng.gaussian(0.0, 3.0);
        let step = traj.states[k + 1][0] - traj.states[k][0];
        assert!((step - T * w).abs() < 1e-14, "k={k}");
    }
}

/// Two masses between springs (lightly damped, complex modes), the force on the second, both positions
/// measured with noise, process noise on both velocities and an output feedback `u = −K y`: the exact step
/// and BDF at tight tolerances agree to the solver's accuracy over 200 samples.
#[test]
fn linear_loop_matches_the_ode_path() {
    #[rustfmt::skip]
    let a = SMatrix::<f64, 4, 4>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0,
        -2.0, -0.2, 1.0, 0.1,
        0.0, 0.0, 0.0, 1.0,
        1.0, 0.1, -1.0, -0.1,
    ]);
    let plant = LinearPlant::new(
        a,
        SMatrix::<f64, 4, 1>::from_column_slice(&[0.0, 0.0, 0.0, 1.0]),
        SMatrix::<f64, 2, 4>::from_row_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        SMatrix::zeros(),
    );
    let mut cfg = SampledLoopConfig::new(0.05, 200, SVector::<f64, 4>::new(1.0, 0.0, -0.5, 0.0));
    cfg.measurement_noise_std = Vector2::new(0.01, 0.02);
    cfg.process_noise_std = SVector::<f64, 4>::new(0.0, 0.5, 0.0, 0.5);
    cfg.measurement_delay = 1;
    cfg.seed = 3;
    cfg.solver = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-12,
        atol: 1e-14,
        ..SolverOptions::default()
    };
    let feedback = |_k: usize, _t: f64, y: &Vector2<f64>| Vector1::new(-0.8 * y[0] - 1.5 * y[1]);
    let exact = simulate_sampled_linear_loop(&plant, &mut { feedback }, &cfg).unwrap();
    let ode = simulate_sampled_loop(&plant, &mut { feedback }, &cfg).unwrap();
    assert_eq!(exact.times, ode.times);
    let scale = exact.states.iter().map(|x| x.amax()).fold(0.0, f64::max);
    assert!(scale > 0.1, "the run must move: {scale}");
    for (k, (xe, xo)) in exact.states.iter().zip(&ode.states).enumerate() {
        assert!((xe - xo).amax() < 1e-9 * scale, "k={k}: {xe} vs {xo}");
    }
    for (ue, uo) in exact.inputs.iter().zip(&ode.inputs) {
        assert!((ue - uo).amax() < 1e-9 * scale);
    }
}

#[test]
fn runs_too_long_to_record_are_refused_and_streams_stop_at_the_sink() {
    let plant = first_order(1.0, 1.0);
    let mut hold = |_k: usize, _t: f64, y: &Vector1<f64>| -y;
    for samples in [1_000_000_000, usize::MAX] {
        let cfg = SampledLoopConfig::new(1e-3, samples, Vector1::new(1.0));
        assert!(matches!(
            simulate_sampled_loop(&plant, &mut hold, &cfg),
            Err(SimError::BadSetting {
                name: "samples",
                ..
            })
        ));
        assert!(matches!(
            simulate_sampled_linear_loop(&plant, &mut hold, &cfg),
            Err(SimError::BadSetting {
                name: "samples",
                ..
            })
        ));
    }
    // 10⁹ samples stream in constant memory; the sink ends the run after ten.
    let cfg = SampledLoopConfig::new(1e-3, 1_000_000_000, Vector1::new(1.0));
    let mut seen = Vec::new();
    let mut sink = |s: &bgc_runtime::sim::Sample<1, 1, 1>| {
        seen.push((s.k, s.state[0], s.input));
        if s.k == 9 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    assert_eq!(
        simulate_sampled_linear_loop_streaming(&plant, &mut hold, &cfg, &mut sink),
        Ok(10)
    );
    assert_eq!(seen.len(), 10);
    // u = −x, so x[k+1] = (2φ − 1) x[k] with φ = e^{−T}.
    let rate = 2.0 * (-1e-3_f64).exp() - 1.0;
    for (k, &(i, x, u)) in seen.iter().enumerate() {
        assert_eq!(i, k);
        assert!((x - rate.powi(k as i32)).abs() < 1e-14);
        assert_eq!(u, Some(Vector1::new(-x)));
    }
    let mut count = 0;
    let n = simulate_sampled_loop_streaming(&plant, &mut hold, &cfg, |_s| {
        count += 1;
        if count == 3 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    assert_eq!(n, Ok(3));
    // With usize::MAX samples the last instants cannot be told apart in floating point.
    let endless = SampledLoopConfig::new(1e-3, usize::MAX, Vector1::new(1.0));
    assert!(matches!(
        simulate_sampled_loop_streaming(
            &plant,
            &mut hold,
            &endless,
            |_s| ControlFlow::Continue(())
        ),
        Err(SimError::BadSetting {
            name: "samples",
            ..
        })
    ));
    // A complete short stream ends with the last sample, which has no input.
    let short = SampledLoopConfig::new(1e-3, 2, Vector1::new(1.0));
    let mut last = None;
    let done = simulate_sampled_linear_loop_streaming(&plant, &mut hold, &short, |s| {
        last = Some((s.k, s.input));
        ControlFlow::Continue(())
    });
    assert_eq!((done, last), (Ok(3), Some((2, None))));
}

#[test]
fn non_finite_plant_matrices_are_refused() {
    let mut plant = first_order(1.0, 1.0);
    plant.a[(0, 0)] = f64::NAN;
    let cfg = SampledLoopConfig::new(T, 5, Vector1::new(1.0));
    let mut hold = |_k: usize, _t: f64, _y: &Vector1<f64>| Vector1::new(0.0);
    assert!(matches!(
        simulate_sampled_linear_loop(&plant, &mut hold, &cfg),
        Err(SimError::BadSetting {
            name: "linear plant matrix",
            ..
        })
    ));
}

/// A nonlinear pendulum that logs the point of every `jac_x` call.
struct LoggingPendulum {
    calls: RefCell<Vec<(f64, Vector2<f64>)>>,
}

impl ContinuousModel<2, 1, 1> for LoggingPendulum {
    fn rhs(&self, _t: f64, x: &Vector2<f64>, u: &Vector1<f64>, dx: &mut Vector2<f64>) {
        *dx = Vector2::new(x[1], -10.0 * x[0].sin() - 0.5 * x[1] + u[0]);
    }
    fn outputs(&self, _t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
    fn jac_x(&self, t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, jac: &mut SMatrix<f64, 2, 2>) {
        self.calls.borrow_mut().push((t, *x));
        *jac = SMatrix::<f64, 2, 2>::new(0.0, 1.0, -10.0 * x[0].cos(), -0.5);
    }
}

/// diffsol assembles its Jacobian column by column at one point; the model's Jacobian must be evaluated once
/// per point, not once per column.
#[test]
fn the_model_jacobian_is_evaluated_once_per_point() {
    let model = LoggingPendulum {
        calls: RefCell::new(Vec::new()),
    };
    let cfg = SampledLoopConfig::new(0.05, 40, Vector2::new(1.0, 0.0));
    let mut hold = |_k: usize, _t: f64, y: &Vector1<f64>| Vector1::new(-y[0]);
    simulate_sampled_loop(&model, &mut hold, &cfg).unwrap();
    let calls = model.calls.borrow();
    assert!(!calls.is_empty(), "BDF uses the Jacobian");
    for pair in calls.windows(2) {
        assert!(
            pair[0] != pair[1],
            "jac_x evaluated twice in a row at {:?}",
            pair[0]
        );
    }
}
