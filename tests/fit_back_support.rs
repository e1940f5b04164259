//! The back-support bench identification (`bgc_workspace::back_support::identification`): the lab test's held
//! chirp command with the trunk held and bounded noise, the exact linear path against the ODE sensitivities, and
//! the identification at the paper's encoder bound and at a realistic one.

use crate::coverage::Coverage;
use bgc_models::back_support::{self as generated, Model, Params};
use bgc_runtime::fit::sensitivity::{self, Fitted};
use bgc_runtime::fit::{FitModel, FitSpec, FreeParam, Generated, Interp, Record, fit, linear};
use bgc_runtime::sim::{Method, SolverOptions};
use bgc_workspace::back_support::identification::{
    BenchConfig, ENCODER_BOUND, FITTED, TORQUE_SENSOR_BOUND, bench_clean, bench_record, identify,
    with_noise,
};

#[test]
fn bench_record_holds_the_chirp_and_bounded_noise() {
    let cfg = BenchConfig::paper();
    let a = bench_record(&cfg).expect("the bench simulates");
    assert_eq!(a.times.len(), cfg.samples + 1);
    assert_eq!(a.outputs, [0, 1]);
    // The trunk is held and the torque command is the chirp at each sample time (f0 t + ½ rate t²).
    let duration = cfg.sample_time * cfg.samples as f64;
    for (t, u) in a.times.iter().zip(&a.inputs).take(cfg.samples) {
        let phase = cfg.f0 * t + 0.5 * (cfg.f1 - cfg.f0) / duration * t * t;
        let want = cfg.amplitude * (2.0 * std::f64::consts::PI * phase).sin();
        assert!((u[0] - want).abs() < 1e-12 && u[1] == 0.0, "t = {t}: {u:?}");
    }
    // Another noise seed changes the measurements by at most twice each bound.
    let other = bench_record(&BenchConfig {
        seed: cfg.seed + 1,
        ..cfg.clone()
    })
    .expect("simulates");
    let mut largest = [0.0f64; 2];
    for (x, y) in a.measured.iter().zip(&other.measured) {
        for c in 0..2 {
            largest[c] = largest[c].max((x[c] - y[c]).abs());
        }
    }
    assert!(
        largest[0] <= 2.0 * ENCODER_BOUND && largest[1] <= 2.0 * TORQUE_SENSOR_BOUND,
        "{largest:?}"
    );
    // Uniform noise fills most of that range over a thousand samples.
    assert!(
        largest[0] > ENCODER_BOUND && largest[1] > TORQUE_SENSOR_BOUND,
        "{largest:?}"
    );
}

#[test]
fn the_exact_linear_path_agrees_with_the_ode_sensitivities() {
    // The first 0.1 s of the bench record (the ODE path at rtol 1e-11 takes seconds for it): outputs and
    // ∂y/∂ln θ of the four fitted parameters, at starting values 10–50 % off, from both paths.
    let full = bench_record(&BenchConfig::paper()).expect("the bench simulates");
    let n = 101;
    let record = Record::new(
        full.times[..n].to_vec(),
        full.inputs[..n].to_vec(),
        full.outputs.clone(),
        full.measured[..n].to_vec(),
    )
    .expect("a valid record");
    let truth = Params::default();
    let mut p: Vec<f64> = (0..generated::N_PARAMS)
        .map(|k| truth.get(k).expect("a parameter"))
        .collect();
    let free: Vec<usize> = FITTED
        .iter()
        .map(|name| {
            generated::PARAM_NAMES
                .iter()
                .position(|n| n == name)
                .expect("a parameter of the model")
        })
        .collect();
    for (&i, f) in free.iter().zip(BenchConfig::paper().start_factors) {
        p[i] *= f;
    }
    let scale: Vec<f64> = free.iter().map(|&i| p[i]).collect();
    let fitted = Fitted {
        params: &free,
        x0: &[],
        scale: &scale,
    };
    let mut model = Generated::exact(Model::default()).declared_linear();
    model.set_params(&p).expect("valid parameters");
    let x0 = [0.0; generated::N_STATES];
    let exact = linear::simulate(&model, &record, &x0, &fitted).expect("the exact path runs");
    let solver = SolverOptions {
        method: Method::Esdirk34,
        rtol: 1e-11,
        atol: 1e-13,
        max_steps: 1_000_000,
    };
    let ode = sensitivity::simulate(&model, &record, Interp::Zoh, &x0, &fitted, &solver)
        .expect("the ODE path runs");
    for o in 0..2 {
        let size = exact.outputs.iter().fold(0.0f64, |a, y| a.max(y[o].abs()));
        let gap = exact
            .outputs
            .iter()
            .zip(&ode.outputs)
            .fold(0.0f64, |a, (x, y)| a.max((x[o] - y[o]).abs()));
        assert!(gap <= 1e-7 * size, "output {o}: {gap:e} of {size:e}");
        for c in 0..FITTED.len() {
            let size = exact
                .jacobians
                .iter()
                .fold(0.0f64, |a, j| a.max(j[(o, c)].abs()));
            let gap = exact
                .jacobians
                .iter()
                .zip(&ode.jacobians)
                .fold(0.0f64, |a, (x, y)| a.max((x[(o, c)] - y[(o, c)]).abs()));
            assert!(
                gap <= 1e-5 * size,
                "∂y{o}/∂ln {}: {gap:e} of {size:e}",
                FITTED[c]
            );
        }
    }
}

#[test]
fn a_model_declared_linear_that_is_not_is_refused() {
    // The pendulum rig has a sine of its angle (gravity) and an explicit time dependence (the stepper).
    use bgc_models::pendulum_rig::{self as pend, Model as Pendulum};
    let times: Vec<f64> = (0..11).map(|k| 0.01 * k as f64).collect();
    let record =
        Record::new(times, vec![vec![]; 11], vec![0], vec![vec![0.0]; 11]).expect("a valid record");
    let model = Generated::new(Pendulum::default()).declared_linear();
    let fitted = Fitted {
        params: &[0],
        x0: &[],
        scale: &[1.0],
    };
    let err =
        linear::simulate(&model, &record, &[0.0; pend::N_STATES], &fitted).expect_err("refused");
    assert!(err.to_string().contains("declared linear"), "{err}");
}

#[test]
fn the_bench_identifies_j_g_k_g_k_s_and_flags_j_sint_with_a_realistic_encoder() {
    let cfg = BenchConfig::realistic();
    let record = bench_record(&cfg).expect("the bench simulates");
    let id = identify(&cfg, &record).expect("identified at the noise level");
    assert!(id.report.convergence.converged(), "{:?}", id.report);
    for p in &id.parameters[..3] {
        assert!(p.determined, "{p:?}");
        assert!(p.error_in_std_errors() < 3.0, "{p:?}");
    }
    // J_sint: the statistics name it and it is held at its start, never given an arbitrary value.
    let j_sint = &id.parameters[3];
    assert!(
        !j_sint.determined && j_sint.std_error.is_nan(),
        "{j_sint:?}"
    );
    let flagged = &id.report.undetermined;
    assert_eq!(flagged.len(), 1, "{flagged:?}");
    assert_eq!(flagged[0].combination[0].0, "J_sint");
    assert!(flagged[0].relative_std_error > 1.0);
}

#[test]
fn at_the_papers_encoder_bound_all_four_are_determined() {
    // An encoder good to 10⁻⁷ rad/s resolves the sensor ring: J_sint too is determined, to a few per cent.
    let cfg = BenchConfig::paper();
    let record = bench_record(&cfg).expect("the bench simulates");
    let id = identify(&cfg, &record).expect("identified at the noise level");
    assert!(
        id.report.residual_variance < 1.1,
        "{}",
        id.report.residual_variance
    );
    for p in &id.parameters {
        assert!(p.determined, "{p:?}");
        assert!(p.error_in_std_errors() < 3.0, "{p:?}");
    }
    assert!(id.parameters[3].std_error < 0.05 * id.parameters[3].estimate);
    assert!(id.report.undetermined.is_empty());
}

/// 100 seeded records of a shorter bench test (0.4 s) at the paper's noise bounds, J_g, k_g and k_s fitted
/// from 10 % off with J_sint known, checked by [`Coverage`]. The noise is uniform on ±b, so the weights are 3/b²
/// (its variance b²/3).
#[test]
fn back_support_estimates_cover_the_truth_and_their_errors_match_the_spread() {
    let cfg = BenchConfig {
        samples: 400,
        ..BenchConfig::paper()
    };
    let clean = bench_clean(&cfg).expect("the bench simulates");
    let names = ["J_g", "k_g", "k_s"];
    let index = |name: &str| {
        generated::PARAM_NAMES
            .iter()
            .position(|n| *n == name)
            .expect("a parameter of the model")
    };
    let truth = Params::default();
    let true_values: Vec<f64> = names
        .iter()
        .map(|n| truth.get(index(n)).expect("a parameter"))
        .collect();
    let mut start: Vec<f64> = (0..generated::N_PARAMS)
        .map(|k| truth.get(k).expect("a parameter"))
        .collect();
    for (n, f) in names.iter().zip([1.1, 0.9, 1.1]) {
        start[index(n)] *= f;
    }
    let mut spec = FitSpec::new(
        names
            .iter()
            .map(|n| FreeParam::new(index(n), n, true))
            .collect(),
        2,
    );
    spec.weights = vec![
        3.0 / cfg.encoder_bound.powi(2),
        3.0 / TORQUE_SENSOR_BOUND.powi(2),
    ];
    let mut study = Coverage::new(true_values);
    for seed in 0..100 {
        let record = with_noise(&clean, &cfg, 5000 + seed).expect("a valid record");
        let mut model = Generated::exact(Model::default()).declared_linear();
        let r = fit(
            &mut model,
            &record,
            &start,
            &[0.0; generated::N_STATES],
            &spec,
        )
        .expect("the fit runs");
        study.add(seed, &r);
    }
    study.check(&names);
}
