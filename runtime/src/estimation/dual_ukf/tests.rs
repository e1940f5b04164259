//! [`DualUkf::step_separate`] against the same recursion composed from two runtime UKFs, and its handling
//! of missing, non-finite and refused observations.

use super::{DualUkf, ParameterObservation};
use crate::estimation::fault::{EstimationError, RejectReason, UpdateOutcome};
use crate::estimation::sigma::SigmaPoints;
use crate::estimation::ukf::UnscentedKalmanFilter;
use crate::noise::Rng;
use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};

const DT: f64 = 0.01;
const FORGETTING: f64 = 0.98;
const TRUE_W: [f64; 2] = [4.0, 0.5];

/// Mass–spring–damper with unit mass, semi-implicit Euler; parameters `w = [k, c]`.
fn f(x: &Vector2<f64>, u: &Vector1<f64>, w: &Vector2<f64>) -> Vector2<f64> {
    let v = x[1] + DT * (u[0] - w[0] * x[0] - w[1] * x[1]);
    Vector2::new(x[0] + DT * v, v)
}

/// The position sensor.
fn h(x: &Vector2<f64>, _u: &Vector1<f64>, _w: &Vector2<f64>) -> Vector1<f64> {
    Vector1::new(x[0])
}

/// The parameter filter's output: the spring-and-damper force and a term nonlinear in the state.
fn output(x: &Vector2<f64>, _u: &Vector1<f64>, w: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(w[0] * x[0] + w[1] * x[1], w[0] * x[0] * x[0] + w[1])
}

fn input(k: usize) -> Vector1<f64> {
    let t = k as f64 * DT;
    Vector1::new((1.3 * t).sin() + 0.5 * (3.7 * t).sin())
}

fn state_filter() -> UnscentedKalmanFilter<2, 1, 1, 5> {
    UnscentedKalmanFilter::new(
        SigmaPoints::new(0.5, 2.0, 0.0).unwrap_or_else(|e| panic!("{e}")),
        Matrix2::new(1e-6, 0.0, 0.0, 1e-4),
        Matrix1::new(1e-4),
        Vector2::new(0.1, 0.0),
        Matrix2::identity() * 0.01,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

const W0: [f64; 2] = [5.2, 0.35];
const PW0: [f64; 2] = [1.0, 0.04];
const PE: [f64; 2] = [1e-4, 1e-4];

fn dual() -> DualUkf<2, 1, 1, 2, 5, 5> {
    DualUkf::new(
        state_filter(),
        SigmaPoints::new(0.5, 2.0, 0.0).unwrap_or_else(|e| panic!("{e}")),
        Vector2::from(W0),
        Matrix2::from_diagonal(&Vector2::from(PW0)),
        FORGETTING,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Noisy measurements of the true system: `(u, y, d)` per step.
fn data(steps: usize, noise: f64) -> Vec<(Vector1<f64>, Vector1<f64>, Vector2<f64>)> {
    let mut rng = Rng::new(3);
    let w = Vector2::from(TRUE_W);
    let mut x = Vector2::new(0.2, 0.0);
    (0..steps)
        .map(|k| {
            let u = input(k);
            x = f(&x, &u, &w);
            let y = h(&x, &u, &w) + Vector1::new(noise * rng.normal());
            let d = output(&x, &u, &w) + Vector2::new(noise * rng.normal(), noise * rng.normal());
            (u, y, d)
        })
        .collect()
}

fn observation(d: Vector2<f64>) -> ParameterObservation<2> {
    ParameterObservation {
        d,
        noise: Matrix2::from_diagonal(&Vector2::from(PE)),
    }
}

/// The paper's alternation written with two UKFs: the state UKF's step at the prior parameters, then a
/// parameter UKF with identity dynamics, process noise `(λ⁻¹ − 1) P_w` and measurement `Y(x̂, u, ·)`.
#[test]
fn separate_step_equals_two_composed_ukfs() {
    let mut dual = dual();
    let mut states = state_filter();
    let mut params = UnscentedKalmanFilter::<2, 1, 2, 5>::new(
        SigmaPoints::new(0.5, 2.0, 0.0).unwrap_or_else(|e| panic!("{e}")),
        Matrix2::zeros(),
        Matrix2::from_diagonal(&Vector2::from(PE)),
        Vector2::from(W0),
        Matrix2::from_diagonal(&Vector2::from(PW0)),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for (k, (u, y, d)) in data(300, 0.01).into_iter().enumerate() {
        let out = dual
            .step_separate(&u, &y, Some(&observation(d)), f, h, output)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        assert!(out.state.is_accepted() && out.parameters.is_some_and(|p| p.is_accepted()));

        let w = *params.state();
        states
            .predict(&u, |x, u| f(x, u, &w))
            .unwrap_or_else(|e| panic!("{e}"));
        states
            .update(&y, &u, |x, u| h(x, u, &w))
            .unwrap_or_else(|e| panic!("{e}"));
        let forgetting_noise = params.covariance() * (1.0 / FORGETTING - 1.0);
        params
            .set_noise(forgetting_noise, Matrix2::from_diagonal(&Vector2::from(PE)))
            .unwrap_or_else(|e| panic!("{e}"));
        params
            .predict(&u, |w, _| *w)
            .unwrap_or_else(|e| panic!("{e}"));
        let x_post = *states.state();
        params
            .update(&d, &u, |w, u| output(&x_post, u, w))
            .unwrap_or_else(|e| panic!("{e}"));

        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-6);
        for i in 0..2 {
            assert!(close(dual.state()[i], states.state()[i]), "x at step {k}");
            assert!(
                close(dual.parameters()[i], params.state()[i]),
                "w at step {k}"
            );
            for j in 0..2 {
                let (a, b) = (dual.state_covariance()[(i, j)], states.covariance()[(i, j)]);
                assert!(close(a, b), "P at step {k}: {a} vs {b}");
                let (a, b) = (
                    dual.parameter_covariance()[(i, j)],
                    params.covariance()[(i, j)],
                );
                assert!(close(a, b), "P_w at step {k}: {a} vs {b}");
            }
        }
        assert!((dual.innovation() - states.innovation()).norm() < 1e-12);
        assert!((out.parameter_innovation - params.innovation()).norm() < 1e-9);
    }
    // The parameters were learnt, not only carried along: from 30 % off to within 2 % of the truth.
    for (i, &truth) in TRUE_W.iter().enumerate() {
        let w = dual.parameters()[i];
        assert!((w - truth).abs() < 0.02 * truth, "w{i} = {w}, true {truth}");
    }
}

/// Without a parameter observation the parameters and their covariance are held exactly (no forgetting)
/// and the state filter is a plain UKF at those parameters.
#[test]
fn no_parameter_observation_holds_the_parameters() {
    let mut dual = dual();
    let mut states = state_filter();
    let w0 = *dual.parameters();
    let pw0 = *dual.parameter_covariance();
    for (u, y, _) in data(50, 0.01) {
        let out = dual
            .step_separate::<2, _, _, _>(&u, &y, None, f, h, output)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(out.parameters, None);
        assert_eq!(out.parameter_innovation, Vector2::zeros());
        states
            .predict(&u, |x, u| f(x, u, &w0))
            .unwrap_or_else(|e| panic!("{e}"));
        states
            .update(&y, &u, |x, u| h(x, u, &w0))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(dual.state(), states.state());
    }
    assert_eq!(*dual.parameters(), w0);
    assert_eq!(*dual.parameter_covariance(), pw0);
}

/// A non-finite `d` is rejected with its index and leaves the parameters as they were; a `P_e` that is not
/// a covariance, a non-finite input and a model output that is not finite are errors that change nothing.
#[test]
fn bad_parameter_observations_change_nothing() {
    let mut dual = dual();
    let steps = data(5, 0.01);
    for (u, y, d) in &steps[..3] {
        dual.step_separate(u, y, Some(&observation(*d)), f, h, output)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    let (u, y, d) = steps[3];
    let before = dual.clone();
    let nan = observation(Vector2::new(d[0], f64::NAN));
    let out = dual
        .step_separate(&u, &y, Some(&nan), f, h, output)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        out.parameters,
        Some(UpdateOutcome::Rejected {
            reason: RejectReason::NonFiniteMeasurement { index: 1 }
        })
    );
    assert_eq!(dual.parameters(), before.parameters());
    assert_eq!(dual.parameter_covariance(), before.parameter_covariance());
    assert!(out.state.is_accepted());

    let snapshot = dual.clone();
    let indefinite = ParameterObservation {
        d,
        noise: Matrix2::new(1.0, 0.0, 0.0, -1.0),
    };
    assert!(matches!(
        dual.step_separate(&u, &y, Some(&indefinite), f, h, output),
        Err(EstimationError::NotPositiveDefinite { name: "P_e", .. })
    ));
    assert!(matches!(
        dual.step_separate(
            &Vector1::new(f64::INFINITY),
            &y,
            Some(&observation(d)),
            f,
            h,
            output
        ),
        Err(EstimationError::NonFiniteInput { index: 0 })
    ));
    let broken = |_: &Vector2<f64>, _: &Vector1<f64>, _: &Vector2<f64>| Vector2::repeat(f64::NAN);
    assert!(matches!(
        dual.step_separate(&u, &y, Some(&observation(d)), f, h, broken),
        Err(EstimationError::NonFiniteModelOutput { .. })
    ));
    assert_eq!(dual.state(), snapshot.state());
    assert_eq!(dual.state_covariance(), snapshot.state_covariance());
    assert_eq!(dual.parameters(), snapshot.parameters());
    assert_eq!(dual.parameter_covariance(), snapshot.parameter_covariance());
}
