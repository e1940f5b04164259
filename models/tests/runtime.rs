//! A generated model plugs into the runtime: the simulator (which uses the generated symbolic Jacobian in its
//! implicit solver) reproduces the closed-form step response of the oscillator of the corpus.

use bgc_models::corpus::oscillator as m;
use bgc_runtime::sim::{SolverOptions, simulate_open_loop};

/// Mass-spring-damper `m ẍ + d ẋ + k x = F` from rest under a step `F0`:
/// `x(t) = F0/k [1 − e^{−ζ ω_n t} (cos ω_d t + ζ/√(1−ζ²) sin ω_d t)]`, `ω_n = √(k/m)`, `ζ = d/(2√(k m))`,
/// `ω_d = ω_n √(1−ζ²)`.
fn step_response(p: &m::Params, f0: f64, t: f64) -> f64 {
    let wn = (p.k / p.m).sqrt();
    let zeta = p.d / (2.0 * (p.k * p.m).sqrt());
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    f0 / p.k
        * (1.0
            - (-zeta * wn * t).exp()
                * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin()))
}

#[test]
fn oscillator_step_response_matches_the_closed_form() {
    let model = m::Model::default();
    let p = *model.params();
    assert_eq!(m::STATE_NAMES, ["p_mass", "q_spring"]);
    let f0 = 3.0;
    let times: Vec<f64> = (0..=40).map(|k| 0.025 * k as f64).collect();
    let run = simulate_open_loop(
        &model,
        0.0,
        &m::State::zeros(),
        |_| m::Inputs::new(f0),
        &times,
        &SolverOptions::default(),
    )
    .expect("simulation");
    for (t, x) in run.times.iter().zip(&run.states) {
        let want = step_response(&p, f0, *t);
        // The spring's displacement is the mass's position.
        assert!(
            (x[1] - want).abs() <= 1e-6 * f0 / p.k,
            "t = {t}: simulated {}, closed form {want}",
            x[1]
        );
    }
}
