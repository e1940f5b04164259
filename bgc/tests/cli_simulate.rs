//! `bgc simulate`, run as a user would: solutions against analytic ones, energy balances, errors.

mod cli_support;

use cli_support::{Csv, bgc, corpus, repo, simulate};

#[test]
fn undamped_oscillator_conserves_energy_over_ten_periods() {
    // m = 2, k = 800: omega = 20 rad/s, period pi/10; ten periods end at pi. q(0) = 0.01 gives E = k q^2/2 = 0.04.
    let csv = simulate(&[
        &corpus("oscillator.bg"),
        "--param",
        "d=0",
        "--x0",
        "q_spring=0.01",
        "--t-end",
        "3.141592653589793",
        "--dt-out",
        "0.01",
        "--solver",
        "tsit45",
        "--rtol",
        "1e-12",
        "--atol",
        "1e-14",
    ]);
    let e = csv.col("energy");
    let e0 = 0.04;
    assert!((e[0] - e0).abs() < 1e-15);
    let worst = e.iter().map(|x| (x - e0).abs() / e0).fold(0.0, f64::max);
    assert!(worst < 1e-8, "relative energy drift {worst}");
    assert!(csv.col("dissipated").iter().all(|x| *x == 0.0));
    assert!(csv.col("supplied").iter().all(|x| *x == 0.0));
    // The solution itself: q = 0.01 cos(20 t), back at 0.01 after ten periods.
    let (t, q) = (csv.col("t"), csv.col("q_spring"));
    for (t, q) in t.iter().zip(&q) {
        assert!((q - 0.01 * (20.0 * t).cos()).abs() < 1e-9, "t = {t}: {q}");
    }
    assert_eq!(*t.last().expect("rows"), std::f64::consts::PI);
}

#[test]
fn mass_spring_damper_step_response_is_the_analytic_one() {
    // x'' m + d x' + k x = F step(0.1), F = 10: with wn = sqrt(k/m) = 20, z = d/(2 sqrt(k m)) = 0.05,
    // wd = wn sqrt(1 - z^2), tau = t - 0.1:
    //   x = F/k (1 - exp(-z wn tau) (cos(wd tau) + z/sqrt(1 - z^2) sin(wd tau))),
    //   p = m x' = m F/k wn/sqrt(1 - z^2) exp(-z wn tau) sin(wd tau).
    // Cross-checked against scipy:
    //   t = np.linspace(0, 1.9, 20); _, y = scipy.signal.step(scipy.signal.lti([10], [2, 4, 800]), T=t)
    //   max |x - y| = 4e-17
    let csv = simulate(&[
        &corpus("oscillator.bg"),
        "--input",
        "F=10*step(0.1)",
        "--t-end",
        "2",
        "--dt-out",
        "0.005",
        "--rtol",
        "1e-10",
        "--atol",
        "1e-13",
    ]);
    let (m, k, d, f) = (2.0f64, 800.0f64, 4.0f64, 10.0f64);
    let wn = (k / m).sqrt();
    let z = d / (2.0 * (k * m).sqrt());
    let wd = wn * (1.0 - z * z).sqrt();
    let t = csv.col("t");
    let (q, p) = (csv.col("q_spring"), csv.col("p_mass"));
    assert_eq!(t.len(), 401);
    for i in 0..t.len() {
        let tau = t[i] - 0.1;
        let (x, mv) = if tau < 0.0 {
            (0.0, 0.0)
        } else {
            let decay = (-z * wn * tau).exp();
            (
                f / k
                    * (1.0
                        - decay * ((wd * tau).cos() + z / (1.0 - z * z).sqrt() * (wd * tau).sin())),
                m * f / k * wn / (1.0 - z * z).sqrt() * decay * (wd * tau).sin(),
            )
        };
        assert!(
            (q[i] - x).abs() < 1e-9,
            "t = {}: q = {}, want {x}",
            t[i],
            q[i]
        );
        assert!(
            (p[i] - mv).abs() < 1e-8,
            "t = {}: p = {}, want {mv}",
            t[i],
            p[i]
        );
    }
    // Energy balance with a damper and a source: E + dissipated - supplied = 0 throughout.
    let (e, dis, sup) = (
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    for i in 0..t.len() {
        assert!((e[i] + dis[i] - sup[i]).abs() < 1e-9, "t = {}", t[i]);
    }
    // At the end the supplied energy is F x (the force is constant after the step).
    let last = t.len() - 1;
    assert!((sup[last] - f * q[last]).abs() < 1e-9);
}

#[test]
fn back_support_keeps_its_energy_balance() {
    // The trunk is held still (omega_h = 0, the default): the trunk-motion source then does no work, so leaving
    // its power out of `supplied` (it needs d(omega_h)/dt, a warning says so) is exact.
    let (code, out, err) = bgc(&[
        "simulate",
        &repo("models/back_support.bg"),
        "--input",
        "tau_m=0.5*step(0.1) + 0.2*sin(20*t)",
        "--t-end",
        "2",
        "--dt-out",
        "0.01",
        "--rtol",
        "1e-9",
        "--atol",
        "1e-12",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("the supplied power of `trunk_motion` has no expression"),
        "{err}"
    );
    let csv = Csv::parse(&out);
    assert_eq!(
        csv.header[..11],
        [
            "t",
            "p_rotor",
            "q_gear_spring",
            "p_sensor_in",
            "q_sensor_spring",
            "p_sensor_out",
            "q_coupling_spring",
            "theta_m",
            "theta_sint",
            "theta_sext",
            "theta_h"
        ]
    );
    assert_eq!(
        csv.header[11..],
        [
            "omega_m",
            "tau_s",
            "tau_h",
            "energy",
            "dissipated",
            "supplied"
        ]
    );
    let (e, dis, sup) = (
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    let scale = sup.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 1.0, "the motor does work: {scale} J");
    assert!(dis.last().copied().unwrap_or(0.0) > 0.1);
    let worst = (0..e.len())
        .map(|i| (e[i] + dis[i] - sup[i]).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-6 * scale,
        "balance off by {worst} J of {scale} J"
    );
    // The outputs agree with the states: omega_m = p_rotor / J_m, tau_s = k_s q_sensor_spring.
    let (p, w) = (csv.col("p_rotor"), csv.col("omega_m"));
    let (qs, ts) = (csv.col("q_sensor_spring"), csv.col("tau_s"));
    for i in 0..p.len() {
        assert!((w[i] - p[i] / 3.06e-4).abs() <= 1e-9 * w[i].abs().max(1.0));
        assert!((ts[i] - 3.38e4 * qs[i]).abs() <= 1e-9 * ts[i].abs().max(1.0));
    }
}

#[test]
fn simulate_errors_are_reported() {
    let osc = corpus("oscillator.bg");
    let cases: [(&[&str], &str); 6] = [
        (&["--param", "mass=3"], "unknown parameter `mass`"),
        (
            &["--input", "F=sin(2*t"],
            "input `F` = `sin(2*t`: expected `)` or `,` at column 8",
        ),
        (&["--input", "F=foo(t)"], "unknown name `foo`"),
        (&["--input", "G=1"], "unknown input `G`; the model has F"),
        (
            &["--x0", "q=1"],
            "unknown state `q`; the model has p_mass, q_spring",
        ),
        (&["--input", "F=1/(t-0.5)"], "the solver failed at t = 0.4"),
    ];
    for (extra, message) in cases {
        let mut args = vec!["simulate", osc.as_str(), "--t-end", "1"];
        args.extend_from_slice(extra);
        let (code, out, err) = bgc(&args);
        assert_eq!(code, 1, "{extra:?}: {err}");
        assert!(out.is_empty(), "{extra:?}");
        assert!(err.contains(message), "{extra:?}: {err}");
    }
    let (code, _, err) = bgc(&["simulate", &osc, "--t-end", "-1"]);
    assert_eq!(code, 1);
    assert!(err.contains("must be finite and positive"), "{err}");
    let (code, _, err) = bgc(&["simulate", &osc, "--t-end", "1", "--dt-out", "1e-9"]);
    assert_eq!(code, 1);
    assert!(err.contains("choose a larger --dt-out"), "{err}");
}

#[test]
fn every_solver_follows_the_step_response() {
    // The analytic response of `mass_spring_damper_step_response_is_the_analytic_one`, at rtol 1e-8: each
    // method stays within 5e-7 m of it (the response peaks at 0.024 m) and keeps the energy balance to 1e-6 J.
    let (m, k, d, f) = (2.0f64, 800.0f64, 4.0f64, 10.0f64);
    let wn = (k / m).sqrt();
    let z = d / (2.0 * (k * m).sqrt());
    let wd = wn * (1.0 - z * z).sqrt();
    for solver in ["bdf", "esdirk34", "tr_bdf2", "tsit45"] {
        let csv = simulate(&[
            &corpus("oscillator.bg"),
            "--input",
            "F=10*step(0.1)",
            "--t-end",
            "2",
            "--dt-out",
            "0.01",
            "--rtol",
            "1e-8",
            "--atol",
            "1e-11",
            "--solver",
            solver,
        ]);
        let (t, q) = (csv.col("t"), csv.col("q_spring"));
        let (e, dis, sup) = (
            csv.col("energy"),
            csv.col("dissipated"),
            csv.col("supplied"),
        );
        for i in 0..t.len() {
            let tau = (t[i] - 0.1).max(0.0);
            let decay = (-z * wn * tau).exp();
            let x = f / k
                * (1.0 - decay * ((wd * tau).cos() + z / (1.0 - z * z).sqrt() * (wd * tau).sin()));
            assert!(
                (q[i] - x).abs() < 5e-7,
                "{solver}, t = {}: {} vs {x}",
                t[i],
                q[i]
            );
            assert!(
                (e[i] + dis[i] - sup[i]).abs() < 1e-6,
                "{solver}, t = {}",
                t[i]
            );
        }
    }
}
