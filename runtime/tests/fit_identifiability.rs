//! What a fit reports about convergence and identifiability, on a first-order lag whose answers are known by hand:
//! `τ ẋ = −x + K u`, `y = x + c`, with a unit step input.

use bgc_runtime::fit::{Convergence, FitModel, FitSpec, FreeParam, Record, fit};
use nalgebra::DMatrix;

/// Parameters `[τ, K, c]`.
struct Lag {
    p: [f64; 3],
}

impl FitModel for Lag {
    fn state_count(&self) -> usize {
        1
    }
    fn input_count(&self) -> usize {
        1
    }
    fn output_count(&self) -> usize {
        1
    }
    fn param_count(&self) -> usize {
        3
    }
    fn set_params(&mut self, p: &[f64]) -> Result<(), String> {
        if p[0] <= 0.0 {
            return Err(format!("τ = {} is not positive", p[0]));
        }
        self.p.copy_from_slice(p);
        Ok(())
    }
    fn rhs(&self, _t: f64, x: &[f64], u: &[f64], dx: &mut [f64]) -> Result<(), String> {
        dx[0] = (-x[0] + self.p[1] * u[0]) / self.p[0];
        Ok(())
    }
    fn outputs(&self, _t: f64, x: &[f64], _u: &[f64], y: &mut [f64]) -> Result<(), String> {
        y[0] = x[0] + self.p[2];
        Ok(())
    }
    fn rate_jacobians(
        &self,
        _t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let [tau, k, _] = self.p;
        let all = [(x[0] - k * u[0]) / (tau * tau), u[0] / tau, 0.0];
        let fp = DMatrix::from_fn(1, free.len(), |_, j| all[free[j]]);
        Ok((DMatrix::from_element(1, 1, -1.0 / tau), fp))
    }
    fn output_jacobians(
        &self,
        _t: f64,
        _x: &[f64],
        _u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let fp = DMatrix::from_fn(1, free.len(), |_, j| if free[j] == 2 { 1.0 } else { 0.0 });
        Ok((DMatrix::from_element(1, 1, 1.0), fp))
    }
}

const TRUTH: [f64; 3] = [0.5, 2.0, 1e-3];

/// 51 samples over 2.5 s of the step response with a fixed ±σ pattern of noise (σ = 0.1).
fn record() -> Record {
    let times: Vec<f64> = (0..51).map(|k| 0.05 * k as f64).collect();
    let measured = times
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let noise = if k % 2 == 0 { 0.1 } else { -0.1 };
            vec![TRUTH[1] * (1.0 - (-t / TRUTH[0]).exp()) + TRUTH[2] + noise]
        })
        .collect();
    Record::new(times, vec![vec![1.0]; 51], vec![0], measured).expect("a valid record")
}

#[test]
fn a_single_parameter_with_a_large_standard_error_is_flagged() {
    // The offset c = 10⁻³ under noise σ = 0.1 over 51 samples: its standard error, about σ/√51 = 0.014, is
    // fourteen times its value. A fit of c alone must say so (it is the only quantity, so none is held).
    let mut spec = FitSpec::new(vec![FreeParam::new(2, "c", false)], 1);
    spec.solver.rtol = 1e-10;
    spec.solver.atol = 1e-12;
    let mut model = Lag { p: TRUTH };
    let report = fit(&mut model, &record(), &TRUTH, &[0.0], &spec).expect("fits");
    assert_eq!(report.convergence, Convergence::Converged);
    let c = &report.estimates[0];
    assert!(!c.determined, "{report:?}");
    assert!(c.std_error > 3.0 * c.value.abs(), "{c:?}");
    assert_eq!(report.undetermined.len(), 1);
    assert_eq!(report.undetermined[0].held, None);
    assert_eq!(report.undetermined[0].combination[0].0, "c");
}

#[test]
fn the_determined_parameters_stay_determined_beside_an_undetermined_one() {
    // τ and K are determined to a few per cent; c is held at its start.
    let free = vec![
        FreeParam::new(0, "tau", true),
        FreeParam::new(1, "K", true),
        FreeParam::new(2, "c", false),
    ];
    let mut spec = FitSpec::new(free, 1);
    spec.solver.rtol = 1e-10;
    spec.solver.atol = 1e-12;
    let start = [0.6, 1.8, TRUTH[2]];
    let report = fit(&mut Lag { p: start }, &record(), &start, &[0.0], &spec).expect("fits");
    assert_eq!(report.convergence, Convergence::Converged);
    let determined: Vec<bool> = report.estimates.iter().map(|e| e.determined).collect();
    assert_eq!(determined, [true, true, false], "{report:?}");
    assert_eq!(report.undetermined[0].held.as_deref(), Some("c"));
    for e in &report.estimates[..2] {
        assert!(e.std_error < 0.1 * e.value, "{e:?}");
    }
}

#[test]
fn a_time_constant_running_off_to_infinity_is_not_converged() {
    // A record of zeros for a unit step: the closer τ is to infinity the smaller the response, so the cost has no
    // minimum; the fit must not call where it stops a minimum.
    let mut r = record();
    r.measured.iter_mut().for_each(|m| m[0] = 0.0);
    let mut spec = FitSpec::new(vec![FreeParam::new(0, "tau", true)], 1);
    spec.lm.max_iterations = 60;
    let start = TRUTH;
    let report = fit(&mut Lag { p: start }, &r, &start, &[0.0], &spec).expect("runs");
    assert_ne!(report.convergence, Convergence::Converged, "{report:?}");
    assert!(report.estimates[0].value > 100.0 * TRUTH[0]);
}

#[test]
fn records_and_specs_that_do_not_fit_the_model_are_refused_with_the_reason() {
    let spec = FitSpec::new(vec![FreeParam::new(1, "K", false)], 1);
    let refused = |model_p: [f64; 3], r: &Record, x0: &[f64], spec: &FitSpec| {
        let got = fit(&mut Lag { p: model_p }, r, &model_p, x0, spec);
        match got {
            Err(bgc_runtime::fit::FitError::Spec(why)) => why,
            other => panic!("expected a refusal, got {other:?}"),
        }
    };
    // A ragged row of inputs: refused by Record::new, and by fit for a record whose public fields were edited
    // (the fit checked the first row only and panicked copying the short row into the model's input).
    let ragged = Record::new(
        vec![0.0, 1.0],
        vec![vec![1.0], vec![]],
        vec![0],
        vec![vec![1.0]; 2],
    );
    assert!(ragged.is_err(), "{ragged:?}");
    let mut r = record();
    r.inputs[7].clear();
    assert!(refused(TRUTH, &r, &[0.0], &spec).contains("inputs"));
    // A parameter named twice gave two estimates of it, one with a NaN standard error.
    let twice = FitSpec::new(
        vec![FreeParam::new(1, "K", false), FreeParam::new(1, "K", false)],
        1,
    );
    assert!(refused(TRUTH, &record(), &[0.0], &twice).contains("twice"));
    // A NaN fixed parameter or initial state reached the ODE solver, which failed with "step size too small".
    assert!(refused([0.5, 2.0, f64::NAN], &record(), &[0.0], &spec).contains("parameter 2"));
    assert!(refused(TRUTH, &record(), &[f64::NAN], &spec).contains("initial state 0"));
    // A NaN tolerance switched its test off silently.
    let mut nan_opts = spec.clone();
    nan_opts.lm.max_log_step = f64::NAN;
    assert!(refused(TRUTH, &record(), &[0.0], &nan_opts).contains("max_log_step"));
}

/// `Record::input_at` panicked on a buffer of the wrong length (`copy_from_slice`) and gave NaN inputs for a NaN
/// time; it now writes nothing and says so. Within the record, a linear input is interpolated: 1 + 2·0.25 at
/// t = 0.25 between (0, 1) and (1, 3), and the held one is the sample's.
#[test]
fn inputs_at_a_time_refuse_a_wrong_buffer_and_a_nan_time() {
    use bgc_runtime::fit::Interp;
    let record = Record::new(
        vec![0.0, 1.0],
        vec![vec![1.0, 10.0], vec![3.0, 10.0]],
        vec![0],
        vec![vec![0.0], vec![0.0]],
    )
    .expect("a valid record");
    let mut u = [0.0; 2];
    assert!(record.input_at(Interp::Linear, 0.25, &mut u));
    assert_eq!(u, [1.5, 10.0]);
    assert!(record.input_at(Interp::Zoh, 0.25, &mut u));
    assert_eq!(u, [1.0, 10.0]);
    let mut short = [7.0; 1];
    assert!(!record.input_at(Interp::Linear, 0.25, &mut short));
    assert_eq!(short, [7.0]);
    let mut long = [7.0; 3];
    assert!(!record.input_at(Interp::Zoh, 0.25, &mut long));
    assert!(!record.input_at(Interp::Linear, f64::NAN, &mut u));
    assert_eq!(u, [1.0, 10.0]);
    // Samples near the largest f64: the values in between, not the overflow of their difference (NaN before).
    let huge = Record::new(
        vec![0.0, 1.0],
        vec![vec![1e308], vec![-1e308]],
        vec![0],
        vec![vec![0.0], vec![0.0]],
    )
    .expect("a valid record");
    let mut v = [0.0; 1];
    assert!(huge.input_at(Interp::Linear, 0.25, &mut v));
    assert_eq!(v, [5e307]);
}
