//! `bgc_runtime::fit` on the generated pendulum rig (nonlinear: gravity `−m g l sin θ`): 100 seeded noisy records
//! simulated at known parameters. The estimates must lie within 3 standard errors of the truth in at least 95 of
//! them (a 3σ interval misses 0.27 % of the time), and the mean reported standard error must agree with the
//! spread of the estimates over the records to within 30 %.

use crate::coverage::Coverage;
use bgc_models::pendulum_rig::{self as pend, Model, Params};
use bgc_runtime::fit::{FitSpec, FreeParam, Generated, Record, fit};
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{SolverOptions, simulate_open_loop};
use nalgebra::SVector;

const SIGMA_THETA: f64 = 2e-3;
const SIGMA_OMEGA: f64 = 2e-2;

/// The noise-free outputs `theta_pend`, `omega_pend` at `times` from rest, by the runtime's own simulator.
fn truth(times: &[f64]) -> Vec<[f64; 2]> {
    let model = Model::default();
    let opts = SolverOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..SolverOptions::default()
    };
    let run = simulate_open_loop(
        &model,
        0.0,
        &SVector::zeros(),
        |_| SVector::zeros(),
        times,
        &opts,
    )
    .expect("the rig simulates");
    run.outputs.iter().map(|y| [y[0], y[1]]).collect()
}

fn index(name: &str) -> usize {
    pend::PARAM_NAMES
        .iter()
        .position(|n| *n == name)
        .expect("a parameter of the rig")
}

/// A noisy record from `clean` with noise seed `seed`.
fn record(times: &[f64], clean: &[[f64; 2]], seed: u64) -> Record {
    let mut rng = Rng::new(seed);
    let measured = clean
        .iter()
        .map(|y| {
            vec![
                y[0] + SIGMA_THETA * rng.normal(),
                y[1] + SIGMA_OMEGA * rng.normal(),
            ]
        })
        .collect();
    Record::new(
        times.to_vec(),
        vec![vec![]; times.len()],
        vec![0, 1],
        measured,
    )
    .expect("a valid record")
}

fn spec() -> FitSpec {
    let mut spec = FitSpec::new(
        vec![
            FreeParam::new(index("J_p"), "J_p", true),
            FreeParam::new(index("d_s"), "d_s", true),
        ],
        2,
    );
    spec.weights = vec![SIGMA_THETA.powi(-2), SIGMA_OMEGA.powi(-2)];
    spec
}

#[test]
fn pendulum_estimates_cover_the_truth_and_their_errors_match_the_spread() {
    let times: Vec<f64> = (0..=100).map(|k| k as f64 * 0.01).collect();
    let clean = truth(&times);
    let defaults = Params::default();
    let true_values = [defaults.J_p, defaults.d_s];
    // Start 30 % off the truth.
    let mut start: Vec<f64> = (0..pend::N_PARAMS)
        .map(|k| defaults.get(k).unwrap())
        .collect();
    start[index("J_p")] *= 1.3;
    start[index("d_s")] *= 0.7;
    let spec = spec();
    let mut study = Coverage::new(true_values.to_vec());
    for seed in 0..100 {
        let rec = record(&times, &clean, 1000 + seed);
        let mut model = Generated::exact(Model::default());
        let r = fit(&mut model, &rec, &start, &[0.0; 4], &spec).expect("the fit runs");
        study.add(seed, &r);
    }
    study.check(&["J_p", "d_s"]);
}
