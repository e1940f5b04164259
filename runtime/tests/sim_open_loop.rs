//! Open-loop simulation against closed forms and physical invariants.

use bgc_runtime::model::ContinuousModel;
use bgc_runtime::sim::{Method, SimError, SolverOptions, simulate_open_loop};
use nalgebra::{SVector, Vector1, Vector2};

/// m ẍ + c ẋ + k x = u; state (x, v), output x.
struct MassSpringDamper {
    m: f64,
    c: f64,
    k: f64,
}

impl ContinuousModel<2, 1, 1> for MassSpringDamper {
    fn rhs(&self, _t: f64, x: &Vector2<f64>, u: &Vector1<f64>, dx: &mut Vector2<f64>) {
        dx[0] = x[1];
        dx[1] = (u[0] - self.c * x[1] - self.k * x[0]) / self.m;
    }
    fn outputs(&self, _t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
}

/// Unit-step response of the underdamped mass-spring-damper from rest:
/// x(t) = (1/k) [1 − e^{−ζω t} (cos ω_d t + ζω/ω_d sin ω_d t)].
fn msd_step(p: &MassSpringDamper, t: f64) -> f64 {
    let w = (p.k / p.m).sqrt();
    let zeta = p.c / (2.0 * (p.k * p.m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    (1.0 - (-zeta * w * t).exp() * ((wd * t).cos() + zeta * w / wd * (wd * t).sin())) / p.k
}

#[test]
fn mass_spring_damper_step_matches_closed_form_for_every_method() {
    let plant = MassSpringDamper {
        m: 1.0,
        c: 0.4,
        k: 4.0,
    };
    let times: Vec<f64> = (0..=100).map(|i| 0.1 * i as f64).collect();
    for method in [
        Method::Bdf,
        Method::Esdirk34,
        Method::TrBdf2,
        Method::Tsit45,
    ] {
        let opts = SolverOptions {
            method,
            rtol: 1e-10,
            atol: 1e-12,
            ..SolverOptions::default()
        };
        let traj = simulate_open_loop(
            &plant,
            0.0,
            &Vector2::zeros(),
            |_t| Vector1::new(1.0),
            &times,
            &opts,
        )
        .unwrap();
        assert_eq!(traj.len(), times.len());
        for (t, y) in traj.times.iter().zip(&traj.outputs) {
            let err = (y[0] - msd_step(&plant, *t)).abs();
            assert!(err < 1e-6, "{method:?}: t={t}, error {err:e}");
        }
    }
}

/// ẍ = −ω² x, the undamped oscillator; energy E = ½ v² + ½ ω² x².
struct Oscillator {
    omega: f64,
}

impl ContinuousModel<2, 1, 1> for Oscillator {
    fn rhs(&self, _t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, dx: &mut Vector2<f64>) {
        dx[0] = x[1];
        dx[1] = -self.omega * self.omega * x[0];
    }
    fn outputs(&self, _t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
}

#[test]
fn undamped_oscillator_conserves_energy() {
    let osc = Oscillator { omega: 2.0 };
    let period = std::f64::consts::PI; // 2π / ω
    let times: Vec<f64> = (1..=200).map(|i| 0.05 * period * i as f64).collect(); // ten periods
    let x0 = Vector2::new(1.0, 0.0);
    let energy = |x: &Vector2<f64>| 0.5 * x[1] * x[1] + 0.5 * 4.0 * x[0] * x[0];
    for method in [Method::Bdf, Method::Tsit45] {
        let opts = SolverOptions {
            method,
            rtol: 1e-12,
            atol: 1e-14,
            ..SolverOptions::default()
        };
        let traj =
            simulate_open_loop(&osc, 0.0, &x0, |_t| Vector1::zeros(), &times, &opts).unwrap();
        let e0 = energy(&x0);
        for (t, x) in traj.times.iter().zip(&traj.states) {
            let drift = (energy(x) - e0).abs() / e0;
            assert!(
                drift < 1e-8,
                "{method:?}: t={t}, relative energy drift {drift:e}"
            );
        }
        // After ten periods the oscillator is back at its start.
        let last = traj.states.last().unwrap();
        assert!((last - x0).norm() < 1e-7, "{method:?}: {last:?}");
    }
}

/// ẋ = x², which blows up at t = 1 from x(0) = 1.
struct Blowup;

impl ContinuousModel<1, 1, 1> for Blowup {
    fn rhs(&self, _t: f64, x: &Vector1<f64>, _u: &Vector1<f64>, dx: &mut Vector1<f64>) {
        dx[0] = x[0] * x[0];
    }
    fn outputs(&self, _t: f64, x: &Vector1<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
}

/// A model that leaves its domain at t = 0.5 (returns NaN from then on).
struct LeavesDomain;

impl ContinuousModel<1, 1, 1> for LeavesDomain {
    fn rhs(&self, t: f64, _x: &Vector1<f64>, _u: &Vector1<f64>, dx: &mut Vector1<f64>) {
        dx[0] = if t < 0.5 { -1.0 } else { f64::NAN };
    }
    fn outputs(&self, _t: f64, x: &Vector1<f64>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[0];
    }
}

fn error_time(e: &SimError) -> f64 {
    match e {
        SimError::Solver { time, .. }
        | SimError::NonFiniteState { time, .. }
        | SimError::NonFiniteDerivative { time, .. }
        | SimError::NonFiniteOutput { time, .. }
        | SimError::NonFiniteInput { time, .. }
        | SimError::TooManySteps { time, .. } => *time,
        SimError::BadSetting { .. }
        | SimError::Discretisation { .. }
        | SimError::PlantShape { .. } => f64::NAN,
    }
}

#[test]
fn diverging_model_is_an_error_at_the_blow_up_time() {
    for method in [
        Method::Bdf,
        Method::Esdirk34,
        Method::TrBdf2,
        Method::Tsit45,
    ] {
        let opts = SolverOptions {
            method,
            ..SolverOptions::default()
        };
        let result = simulate_open_loop(
            &Blowup,
            0.0,
            &Vector1::new(1.0),
            |_t| Vector1::zeros(),
            &[0.5, 2.0],
            &opts,
        );
        let err = result.expect_err("x' = x^2 cannot be integrated past t = 1");
        let t = error_time(&err);
        assert!((0.9..=1.0 + 1e-6).contains(&t), "{method:?}: {err}");
    }
}

#[test]
fn nan_model_is_an_error_not_a_panic() {
    for method in [Method::Bdf, Method::Tsit45] {
        let opts = SolverOptions {
            method,
            ..SolverOptions::default()
        };
        let result = simulate_open_loop(
            &LeavesDomain,
            0.0,
            &Vector1::new(1.0),
            |_t| Vector1::zeros(),
            &[1.0],
            &opts,
        );
        let err = result.expect_err("the model returns NaN after t = 0.5");
        let t = error_time(&err);
        assert!((0.5..=1.0).contains(&t), "{method:?}: {err}");
    }
}

#[test]
fn bad_settings_are_refused() {
    let plant = MassSpringDamper {
        m: 1.0,
        c: 0.4,
        k: 4.0,
    };
    let run = |times: &[f64], x0: SVector<f64, 2>, opts: SolverOptions| {
        simulate_open_loop(&plant, 0.0, &x0, |_t| Vector1::zeros(), times, &opts)
    };
    let ok = SolverOptions::default();
    assert!(matches!(
        run(&[1.0, 0.5], Vector2::zeros(), ok),
        Err(SimError::BadSetting { name: "times", .. })
    ));
    assert!(matches!(
        run(&[-1.0], Vector2::zeros(), ok),
        Err(SimError::BadSetting { .. })
    ));
    assert!(matches!(
        run(&[1.0], Vector2::new(f64::NAN, 0.0), ok),
        Err(SimError::BadSetting { name: "x0", .. })
    ));
    let bad_tol = SolverOptions { rtol: -1.0, ..ok };
    assert!(matches!(
        run(&[1.0], Vector2::zeros(), bad_tol),
        Err(SimError::BadSetting { name: "rtol", .. })
    ));
    // A time equal to t0 reports the initial state itself.
    let traj = run(&[0.0, 1.0], Vector2::new(0.3, 0.0), ok).unwrap();
    assert_eq!(traj.states[0], Vector2::new(0.3, 0.0));
}

/// The heat equation on a line of `N` cells with cold ends, `ẋᵢ = xᵢ₋₁ − 2 xᵢ + xᵢ₊₁`: a model whose `N × N`
/// Jacobian (1.3 MB at `N = 400`) does not fit a test thread's stack twice.
struct HeatLine<const N: usize>;

impl<const N: usize> ContinuousModel<N, 1, 1> for HeatLine<N> {
    fn rhs(&self, _t: f64, x: &SVector<f64, N>, _u: &Vector1<f64>, dx: &mut SVector<f64, N>) {
        for i in 0..N {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < N { x[i + 1] } else { 0.0 };
            dx[i] = left - 2.0 * x[i] + right;
        }
    }
    fn outputs(&self, _t: f64, x: &SVector<f64, N>, _u: &Vector1<f64>, y: &mut Vector1<f64>) {
        y[0] = x[N / 2];
    }
    fn jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, N>,
        _u: &Vector1<f64>,
        jac: &mut nalgebra::SMatrix<f64, N, N>,
    ) {
        jac.fill(0.0);
        for i in 0..N {
            jac[(i, i)] = -2.0;
            if i > 0 {
                jac[(i, i - 1)] = 1.0;
            }
            if i + 1 < N {
                jac[(i, i + 1)] = 1.0;
            }
        }
    }
}

#[test]
fn a_model_of_400_states_runs_on_an_implicit_method_in_a_test_thread_and_decays_as_its_slowest_mode()
 {
    const N: usize = 400;
    // The slowest mode xᵢ = sin(iπ/(N+1)) decays as exp(λ t), λ = −2 + 2 cos(π/(N+1)) (the eigenpair of the
    // tridiagonal matrix).
    let angle = std::f64::consts::PI / (N as f64 + 1.0);
    let lambda = -2.0 + 2.0 * angle.cos();
    let x0 = SVector::<f64, N>::from_fn(|i, _| ((i + 1) as f64 * angle).sin());
    let times = [0.5, 1.0, 2.0];
    let opts = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-9,
        atol: 1e-12,
        ..SolverOptions::default()
    };
    let traj = simulate_open_loop(
        &HeatLine::<N>,
        0.0,
        &x0,
        |_t| Vector1::zeros(),
        &times,
        &opts,
    )
    .expect("the heat line runs");
    for (t, x) in traj.times.iter().zip(&traj.states) {
        let expected = x0 * (lambda * t).exp();
        let err = (x - expected).amax();
        assert!(err < 1e-6, "t = {t}: largest error {err:e}");
    }
}
