//! The dual UKF identifies the parameters of a noise-free mass–spring–damper.

use bgc_runtime::estimation::dual_ukf::{DualUkf, ParameterObservationNoise};
use bgc_runtime::estimation::{EstimationError, SigmaPoints, UnscentedKalmanFilter};
use bgc_runtime::model::{DiscreteModel, ParamError, Parametric};
use nalgebra::{Matrix2, Vector1, Vector2};

const DT: f64 = 0.01;

/// Semi-implicit Euler: `x2' = x2 + Δt (−k x1 − c x2 + u)`, `x1' = x1 + Δt x2'`, `y = [x1, x2]` (joint
/// encoder and its velocity), parameters `[k, c]`.
#[derive(Clone)]
struct Msd {
    k: f64,
    c: f64,
}

impl DiscreteModel<2, 1, 2> for Msd {
    fn step(&self, x: &Vector2<f64>, u: &Vector1<f64>, next: &mut Vector2<f64>) {
        *next = msd_step(x, u, self.k, self.c);
    }
    fn outputs(&self, x: &Vector2<f64>, _u: &Vector1<f64>, y: &mut Vector2<f64>) {
        *y = *x;
    }
}

impl Parametric for Msd {
    fn param_names(&self) -> &'static [&'static str] {
        &["k", "c"]
    }
    fn param(&self, index: usize) -> Option<f64> {
        [self.k, self.c].get(index).copied()
    }
    fn set_param(&mut self, index: usize, value: f64) -> Result<(), ParamError> {
        let name = *self
            .param_names()
            .get(index)
            .ok_or(ParamError::NoSuchParam { index })?;
        if value.is_nan() || value <= 0.0 {
            return Err(ParamError::NonPhysical {
                name,
                value,
                reason: "must be positive",
            });
        }
        match index {
            0 => self.k = value,
            _ => self.c = value,
        }
        Ok(())
    }
}

fn msd_step(x: &Vector2<f64>, u: &Vector1<f64>, k: f64, c: f64) -> Vector2<f64> {
    let v = x[1] + DT * (-k * x[0] - c * x[1] + u[0]);
    Vector2::new(x[0] + DT * v, v)
}

/// A persistently exciting input.
fn input(step: usize) -> Vector1<f64> {
    let t = step as f64 * DT;
    Vector1::new((1.3 * t).sin() + 0.5 * (3.7 * t).sin() + 0.3 * (0.4 * t).cos())
}

fn dual_filter(w0: Vector2<f64>) -> DualUkf<2, 1, 2, 2, 5, 5> {
    let state = UnscentedKalmanFilter::<2, 1, 2, 5>::new(
        SigmaPoints::new(1.0, 2.0, 0.0).unwrap(),
        Matrix2::identity() * 1e-10,
        Matrix2::identity() * 1e-8,
        Vector2::new(0.0, 0.0),
        Matrix2::identity() * 1e-4,
    )
    .unwrap();
    DualUkf::new(
        state,
        SigmaPoints::new(1.0, 2.0, 0.0).unwrap(),
        w0,
        Matrix2::new(1.0, 0.0, 0.0, 0.25),
        0.995,
    )
    .unwrap()
}

#[test]
fn dual_ukf_converges_to_the_true_parameters_with_closures() {
    for noise in [
        ParameterObservationNoise::StateInnovation,
        ParameterObservationNoise::MeasurementNoise,
    ] {
        converges_with(noise);
    }
}

fn converges_with(noise: ParameterObservationNoise) {
    let (k_true, c_true) = (4.0, 0.5);
    let mut dual = dual_filter(Vector2::new(2.0, 1.0)).with_parameter_observation_noise(noise);
    let mut x = Vector2::new(0.0, 0.0);
    for step in 0..3000 {
        let u = input(step);
        x = msd_step(&x, &u, k_true, c_true);
        let y = x;
        let out = dual
            .step_with(&u, &y, |x, u, w| msd_step(x, u, w[0], w[1]), |x, _u, _w| *x)
            .unwrap();
        assert!(out.state.is_accepted() && out.parameters.is_accepted());
    }
    let w = dual.parameters();
    // Noise-free data: the estimates must reach the truth to far better than any noise level would allow
    // (they end within about 3e-9).
    assert!((w[0] - k_true).abs() < 1e-6, "{noise:?}: k = {}", w[0]);
    assert!((w[1] - c_true).abs() < 1e-6, "{noise:?}: c = {}", w[1]);
    assert!((dual.state() - x).amax() < 1e-6);
    // The forgetting factor keeps the parameter covariance from collapsing to zero.
    assert!(dual.parameter_covariance()[(0, 0)] > 0.0);
}

#[test]
fn dual_ukf_on_a_parametric_model_leaves_the_estimate_in_the_model() {
    let truth = Msd { k: 4.0, c: 0.5 };
    let mut model = Msd { k: 2.0, c: 1.0 };
    let mut dual = dual_filter(Vector2::new(model.k, model.c));
    let mut x = Vector2::new(0.0, 0.0);
    for step in 0..3000 {
        let u = input(step);
        let mut next = Vector2::zeros();
        truth.step(&x, &u, &mut next);
        x = next;
        dual.step_parametric(&mut model, [0, 1], &u, &x).unwrap();
    }
    assert!((model.k - 4.0).abs() < 1e-6, "k = {}", model.k);
    assert!((model.c - 0.5).abs() < 1e-6, "c = {}", model.c);
    assert_eq!(model.k, dual.parameters()[0]);
}

/// A parameter sigma point the model refuses (a negative stiffness) fails the step with the model's reason
/// and leaves filter and model unchanged.
#[test]
fn refused_parameter_is_an_error_and_changes_nothing() {
    let mut model = Msd { k: 0.5, c: 1.0 };
    // P_w(0,0) = 1 around k = 0.5: sigma points at 0.5 ± √2 include a negative stiffness.
    let mut dual = dual_filter(Vector2::new(0.5, 1.0));
    let before = (
        *dual.state(),
        *dual.parameters(),
        *dual.parameter_covariance(),
    );
    let err = dual
        .step_parametric(
            &mut model,
            [0, 1],
            &Vector1::new(1.0),
            &Vector2::new(0.1, 0.0),
        )
        .unwrap_err();
    assert!(
        matches!(
            err,
            EstimationError::ParamRefused(ParamError::NonPhysical { name: "k", .. })
        ),
        "{err:?}"
    );
    assert_eq!(
        before,
        (
            *dual.state(),
            *dual.parameters(),
            *dual.parameter_covariance()
        )
    );
    assert_eq!((model.k, model.c), (0.5, 1.0));
}

#[test]
fn nan_measurement_is_rejected_by_both_filters_without_forgetting() {
    let mut dual = dual_filter(Vector2::new(2.0, 1.0));
    let pw = *dual.parameter_covariance();
    let out = dual
        .step_with(
            &Vector1::new(1.0),
            &Vector2::new(0.0, f64::NAN),
            |x, u, w| msd_step(x, u, w[0], w[1]),
            |x, _u, _w| *x,
        )
        .unwrap();
    assert!(!out.state.is_accepted() && !out.parameters.is_accepted());
    assert_eq!(*dual.parameter_covariance(), pw);
    // The state was predicted: velocity 0 + Δt · u = 0.01.
    assert!((dual.state()[1] - 0.01).abs() < 1e-12);
}
