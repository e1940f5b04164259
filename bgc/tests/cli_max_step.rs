//! `bgc simulate --max-step`: a bound on the solver's step for a forcing that acts in short windows.
//!
//! The diode peak detector `bgc/tests/corpus/diode_rc.bg` driven by `u = 10 sin(50 t)`: the diode conducts only
//! near each peak of the sine, and once the capacitor is charged those windows are a small part of each period.
//! Without a bound the solver's steps grow across them (its error estimate sees the model only where a step
//! evaluates it), and at the default tolerances the charge at t = 5 s is 2.1 % low; with `--max-step 0.01` it is
//! within 1.2e-4 at every time below.
//!
//! Reference: the charge `q` of `dq/dt = i`, `i = I_s (exp((u − R_s i − q/C)/V_t) − 1)` (the loop solved by
//! `brentq` at every evaluation), by scipy 1.17.1's Radau:
//!
//! ```text
//! R, Is, Vt, C = 100.0, 1e-6, 0.05, 1e-3
//! def current(q, t):
//!     u = 10*math.sin(50*t)
//!     r = lambda i: i - Is*(math.exp(min((u - R*i - q/C)/Vt, 700.0)) - 1)
//!     return brentq(r, -Is, max((u - q/C)/R, 0.0) + Is, xtol=1e-300, rtol=1e-15, maxiter=500)
//! solve_ivp(lambda t, y: [current(y[0], t)], (0, 20), [0.0], method="Radau", rtol=1e-11, atol=1e-16,
//!           max_step=1e-3, t_eval=[1, 5, 10, 15, 20])
//! ```
//!
//! (with `rtol=1e-10, atol=1e-15, max_step=2e-3` the values agree to 2e-10).

use crate::cli_support::{bgc, corpus, simulate};

const REFERENCE: [(f64, f64); 5] = [
    (1.0, 0.008_005_086_376_128_125),
    (5.0, 0.009_497_798_021_675_446),
    (10.0, 0.009_649_233_387_749_853),
    (15.0, 0.009_699_741_746_883_586),
    (20.0, 0.009_726_193_150_243_909),
];

#[test]
fn a_bounded_step_sees_the_diode_conduct_at_every_peak() {
    let path = corpus("diode_rc.bg");
    let csv = simulate(&[
        &path,
        "--t-end",
        "20",
        "--input",
        "u=10*sin(50*t)",
        "--max-step",
        "0.01",
    ]);
    let (t, q) = (csv.col("t"), csv.col("q_cap"));
    for (at, want) in REFERENCE {
        let k = t.iter().position(|v| (v - at).abs() < 1e-9);
        let got = k.and_then(|k| q.get(k)).copied().unwrap_or(f64::NAN);
        assert!(
            (got - want).abs() <= 5e-4 * want,
            "t = {at}: q = {got}, reference {want}"
        );
    }
}

#[test]
fn a_step_bound_that_is_not_a_positive_time_is_refused_by_name() {
    let path = corpus("diode_rc.bg");
    for bad in ["0", "-0.01", "nan", "inf", "1e-300"] {
        let (code, _, err) = bgc(&[
            "simulate",
            &path,
            "--t-end",
            "1",
            "--input",
            "u=1",
            "--max-step",
            bad,
        ]);
        assert_eq!(code, 1, "--max-step {bad}: {err}");
        assert!(err.contains("--max-step"), "--max-step {bad}: {err}");
    }
}
