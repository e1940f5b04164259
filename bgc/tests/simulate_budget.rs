//! The step budget of a run: a method that cannot finish within it at its pace stops early and says why.

use crate::equations_kinematic::fixture;
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run};
use bgc::simulate::{SimError, System};

/// A forcing of 1 MHz over one second needs millions of steps of an implicit one-step method. With a budget of
/// 10,000 its pace is judged after each 100 (a hundredth of the budget) and the run stops at the first look,
/// naming what to try. The implicit methods used to keep their whole budget: the walking leg with its Coulomb
/// friction regularised over 1e-9 rad/s ran for minutes under the CLI's 10,000,000 steps (2.8 s now).
#[test]
fn an_implicit_run_too_slow_to_finish_stops_early() {
    let eqs = fixture("../corpus/oscillator");
    for method in [Method::TrBdf2, Method::Esdirk34] {
        let signals = vec![Signal::parse("sin(1e6*t)").unwrap_or_else(|e| panic!("{e}"))];
        let (system, _) =
            System::new(&eqs, eqs.default_params(), signals).unwrap_or_else(|e| panic!("{e}"));
        let opts = RunOptions {
            t_end: 1.0,
            dt_out: 0.1,
            method,
            rtol: 1e-6,
            atol: 1e-9,
            max_steps: 10_000,
            max_step: None,
        };
        match run(&system, &[0.0, 0.0], &opts) {
            Err(err @ SimError::TooSlow { steps, .. }) => {
                assert_eq!(steps, 100, "{method:?}");
                assert!(err.to_string().contains("smooth the law"), "{err}");
            }
            other => panic!("{method:?}: expected TooSlow, got {other:?}"),
        }
    }
}
