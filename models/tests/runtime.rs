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

/// `∂f/∂x` of the oscillator in `(p_mass, q_spring)`, by hand from `ṗ = F − d p/m − k q`, `q̇ = p/m`.
fn oscillator_jac_x(m_: f64, k: f64, d: f64) -> [[f64; 2]; 2] {
    [[-d / m_, -k], [1.0 / m_, 0.0]]
}

fn assert_jac_x(model: &m::Model, want: [[f64; 2]; 2]) {
    use bgc_runtime::model::ContinuousModel;
    let mut jac = m::JacX::zeros();
    // A linear model's Jacobian is the same at any point.
    for (t, x, u) in [
        (0.0, m::State::zeros(), m::Inputs::zeros()),
        (7.0, m::State::new(3.0, -0.2), m::Inputs::new(40.0)),
    ] {
        model.jac_x(t, &x, &u, &mut jac);
        for (r, row) in want.iter().enumerate() {
            for (c, w) in row.iter().enumerate() {
                assert!(
                    (jac[(r, c)] - w).abs() <= 1e-12 * w.abs().max(1.0),
                    "∂f/∂x[{r},{c}] = {}, want {w}",
                    jac[(r, c)]
                );
            }
        }
    }
}

#[test]
fn a_linear_models_jacobian_follows_its_parameters() {
    use bgc_runtime::model::Parametric;
    let mut model = m::Model::default();
    assert_jac_x(&model, oscillator_jac_x(2.0, 800.0, 4.0));
    let k = m::PARAM_NAMES.iter().position(|n| *n == "k").expect("k");
    model.set_param(k, 500.0).expect("a physical stiffness");
    assert_jac_x(&model, oscillator_jac_x(2.0, 500.0, 4.0));
    // A refused value leaves the model, Jacobian included, as it was.
    assert!(model.set_param(k, -1.0).is_err());
    assert_jac_x(&model, oscillator_jac_x(2.0, 500.0, 4.0));
    let p = m::Params {
        m: 4.0,
        d: 1.0,
        ..*model.params()
    };
    model.set_params(p).expect("physical parameters");
    assert_jac_x(&model, oscillator_jac_x(4.0, 500.0, 1.0));
    assert_jac_x(
        &m::Model::new(p).expect("physical parameters"),
        oscillator_jac_x(4.0, 500.0, 1.0),
    );
}
