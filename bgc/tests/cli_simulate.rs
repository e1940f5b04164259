//! `bgc simulate`, run as a user would: solutions against analytic ones, energy balances, errors.

use crate::cli_support;

use cli_support::{Csv, bgc, corpus, repo, simulate, temp_model};

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
    // The motor is driven and the wearer moves the trunk (omega_h = 0.5 sin 3t): the trunk-motion source imposes
    // the trunk inertia's velocity, so its power J_h d(omega_h)/dt omega_h + (torques) needs the input's derivative,
    // which the simulation takes from the input's expression. Without that term the balance would be off by the
    // source's whole work (checked below to be more than 1 J).
    let (code, out, err) = bgc(&[
        "simulate",
        &repo("models/back_support.bg"),
        "--input",
        "tau_m=0.5*step(0.1) + 0.2*sin(20*t)",
        "--input",
        "omega_h=0.5*sin(3*t)",
        "--t-end",
        "2",
        "--dt-out",
        "0.001",
        "--rtol",
        "1e-9",
        "--atol",
        "1e-12",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("BG0607"), "{err}");
    assert!(!err.contains("left out"), "{err}");
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
    let (t, e, dis, sup) = (
        csv.col("t"),
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    let scale = sup.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 1.0, "the sources do work: {scale} J");
    assert!(dis.last().copied().unwrap_or(0.0) > 0.1);
    let worst = (0..e.len())
        .map(|i| (e[i] + dis[i] - sup[i]).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-7 * scale,
        "balance off by {worst} J of {scale} J"
    );
    // The motor's work, integral of tau_m omega_m by the trapezoidal rule on the 1 ms samples (a few mJ of error
    // at most); the rest of `supplied` is the trunk source's work, which is what the column used to miss.
    let omega_m = csv.col("omega_m");
    let tau_m = |t: f64| if t >= 0.1 { 0.5 } else { 0.0 } + 0.2 * (20.0 * t).sin();
    let mut motor = vec![0.0];
    for i in 1..t.len() {
        let (p0, p1) = (tau_m(t[i - 1]) * omega_m[i - 1], tau_m(t[i]) * omega_m[i]);
        motor.push(motor[i - 1] + 0.5 * (p0 + p1) * (t[i] - t[i - 1]));
    }
    let trunk_work = (0..t.len())
        .map(|i| (sup[i] - motor[i]).abs())
        .fold(0.0, f64::max);
    assert!(
        trunk_work > 1.0,
        "the trunk source's work peaks at {trunk_work} J"
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
fn back_support_counts_the_energy_of_a_trunk_velocity_step() {
    // omega_h jumps from 0 to 0.3 rad/s at t = 0.5: the trunk's kinetic energy jumps by J_h 0.3^2 / 2 with the
    // states unchanged, and the source supplies exactly that (the limit of a steep ramp); the balance holds on
    // both sides of the jump and in the row at the jump itself.
    let csv = simulate(&[
        &repo("models/back_support.bg"),
        "--input",
        "tau_m=0.5*step(0.1)",
        "--input",
        "omega_h=0.3*step(0.5)",
        "--t-end",
        "1",
        "--dt-out",
        "0.01",
        "--rtol",
        "1e-10",
        "--atol",
        "1e-13",
    ]);
    let (t, e, dis, sup) = (
        csv.col("t"),
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    // Left out, the jump's energy J_h 0.3^2 / 2 = 2.2 mJ would break the balance from t = 0.5 on by far more than
    // the tolerance.
    let jump = 0.0491 * 0.3 * 0.3 / 2.0;
    let scale = sup.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let tolerance = 1e-8 * scale;
    assert!(jump > 100.0 * tolerance, "{jump} vs {tolerance}");
    for i in 0..t.len() {
        assert!(
            (e[i] + dis[i] - sup[i]).abs() < tolerance,
            "t = {}: {} + {} - {}",
            t[i],
            e[i],
            dis[i],
            sup[i]
        );
    }
    assert!(t.contains(&0.5), "a row at the jump");
}

const DRIVEN_INERTIA: &str = "/// A flow source imposing the velocity of an inertia.
model driven_inertia {
    domain rotational;
    param J = 2 [kg m^2];
    input omega [rad/s];

    Sf drive = omega;
    1  shaft;
    I  wheel = J;

    bond drive -> shaft -> wheel;
}
";

#[test]
fn a_flow_source_supplies_the_kinetic_energy_of_the_inertia_it_drives() {
    // The inertia has no state (its velocity is the input), so E = J omega(t)^2 / 2 and, with nothing dissipating,
    // supplied = E - E(0) = J omega(t)^2 / 2 for omega(0) = 0: for a sinusoid, a ramp and a step (whose jump is
    // counted at the breakpoint).
    let path = temp_model("driven_inertia", DRIVEN_INERTIA);
    let j = 2.0;
    type Omega = fn(f64) -> f64;
    let cases: [(&str, Omega); 3] = [
        ("omega=3*sin(2*t) + t^2", |t| 3.0 * (2.0 * t).sin() + t * t),
        ("omega=ramp(0.25)", |t| (t - 0.25).max(0.0)),
        ("omega=4*step(0.5)", |t| if t >= 0.5 { 4.0 } else { 0.0 }),
    ];
    for (input, omega) in cases {
        let csv = simulate(&[
            &path, "--input", input, "--t-end", "1", "--dt-out", "0.05", "--rtol", "1e-10",
            "--atol", "1e-12",
        ]);
        let (t, e, sup) = (csv.col("t"), csv.col("energy"), csv.col("supplied"));
        assert_eq!(t.len(), 21);
        for i in 0..t.len() {
            let want = j * omega(t[i]).powi(2) / 2.0;
            assert!(
                (e[i] - want).abs() <= 1e-12 * want.max(1.0),
                "{input}, t = {}: energy {} vs {want}",
                t[i],
                e[i]
            );
            assert!(
                (sup[i] - want).abs() <= 1e-8 * want.max(1.0),
                "{input}, t = {}: supplied {} vs {want}",
                t[i],
                sup[i]
            );
        }
        assert!(csv.col("dissipated").iter().all(|x| *x == 0.0));
    }
    let _ = std::fs::remove_file(&path);
}

#[test]
fn simulate_errors_are_reported() {
    let osc = corpus("oscillator.bg");
    let cases: [(&[&str], &str); 9] = [
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
        // A unit stuck to the number, and two states in one option, as other tools take them.
        (
            &["--param", "k=800N/m"],
            "not a number; a unit goes in brackets after the number: '800 [N/m]'",
        ),
        (
            &["--x0", "q_spring=1,p_mass=2"],
            "not a number; give each NAME=VALUE its own option",
        ),
        // An expression is not a number with a unit stuck to it (the hint had proposed the unit `[*10]`).
        (
            &["--param", "k=1e3*10"],
            "`1e3*10`: not a number; a value is a number (with an optional unit in brackets, `0.5 [deg]`), not an \
             expression: write its value",
        ),
        (
            &["--x0", "q_spring=1/3"],
            "not a number; a value is a number",
        ),
    ];
    for (extra, message) in cases {
        let mut args = vec!["simulate", osc.as_str(), "--t-end", "1"];
        args.extend_from_slice(extra);
        let (code, out, err) = bgc(&args);
        assert_eq!(code, 1, "{extra:?}: {err}");
        assert!(out.is_empty(), "{extra:?}");
        assert!(err.contains(message), "{extra:?}: {err}");
    }
    // Rows stream out as they are computed: a run that fails on the way has printed those before the failure, and
    // the message says so.
    let (code, out, err) = bgc(&["simulate", &osc, "--t-end", "1", "--input", "F=1/(t-0.5)"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("the solver failed at t = 0.4"), "{err}");
    let rows: Vec<&str> = out.lines().skip(1).collect();
    assert!(
        !rows.is_empty()
            && err.contains(&format!("(the {} rows before it were printed)", rows.len())),
        "{err}"
    );
    assert!(
        rows.iter().all(|r| r
            .split(',')
            .next()
            .and_then(|t| t.parse::<f64>().ok())
            .is_some_and(|t| t < 0.5)),
        "{out}"
    );
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

#[test]
fn a_diode_loop_is_solved_by_newton_at_every_step() {
    // corpus/diode_rc.bg: u = 2 sin(4 pi t) charges C through R_s and a diode, i = I_s (exp(v_d/V_t) - 1) with
    // u - q/C = R_s i + v_d: a nonlinear algebraic loop in the current. The reference solves the loop with brentq
    // inside the right-hand side:
    //   R, Is, Vt, C = 100.0, 1e-6, 0.05, 1e-3
    //   u = lambda t: 2*np.sin(4*np.pi*t)
    //   def current(q, t):
    //       g = lambda i: Is*(np.exp((u(t) - q/C - R*i)/Vt) - 1) - i
    //       return scipy.optimize.brentq(g, -Is, 1.0, xtol=1e-300, rtol=1e-15, maxiter=500)
    //   sol = scipy.integrate.solve_ivp(lambda t, y: [current(y[0], t)], (0, 1), [0.0], method='DOP853',
    //                                   rtol=1e-12, atol=1e-16, dense_output=True)
    //   (t, sol.sol(t)[0], current(sol.sol(t)[0], t))
    let reference = [
        (0.05, 1.221142253384171e-04, 6.170698140284477e-03),
        (0.1, 5.345596054896531e-04, 9.116555752244031e-03),
        (0.2, 1.038153776714162e-03, 1.417993790833362e-05),
        (0.3, 1.038090885879596e-03, -1e-06),
        (0.5, 1.037890885879598e-03, -9.999999990320276e-07),
        (0.6, 1.127678442667608e-03, 3.643815400005494e-03),
        (0.75, 1.327821010630361e-03, -9.999999999970652e-07),
        (1.0, 1.327571010630361e-03, -9.999999999970506e-07),
    ];
    let (code, out, err) = bgc(&[
        "simulate",
        &corpus("diode_rc.bg"),
        "--input",
        "u=2*sin(4*pi*t)",
        "--t-end",
        "1",
        "--dt-out",
        "0.05",
        "--rtol",
        "1e-10",
        "--atol",
        "1e-14",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    let (t, q, i, v_d) = (csv.col("t"), csv.col("q_cap"), csv.col("i"), csv.col("v_d"));
    for (tr, qr, ir) in reference {
        let k = t
            .iter()
            .position(|x| (x - tr).abs() < 1e-9)
            .expect("a row at the reference time");
        assert!(
            (q[k] - qr).abs() <= 1e-8 * qr.abs(),
            "t = {tr}: q = {}, want {qr}",
            q[k]
        );
        // The current peaks near 9.1 mA; near the diode's cut-off it is a sensitive function of q.
        assert!(
            (i[k] - ir).abs() <= 1e-9,
            "t = {tr}: i = {}, want {ir}",
            i[k]
        );
    }
    // Every row satisfies the loop's two laws: the diode's (to the Newton tolerance, 1e-12 of the residual's terms
    // I_s exp(v_d/V_t) + I_s + |i|, about 2 |i|) and Kirchhoff's voltage law (exactly: v_d is computed from it).
    for k in 0..t.len() {
        let u = 2.0 * (4.0 * std::f64::consts::PI * t[k]).sin();
        let diode = 1e-6 * ((v_d[k] / 0.05).exp() - 1.0);
        let terms = 1e-6 * (v_d[k] / 0.05).exp() + 1e-6 + i[k].abs();
        assert!(
            (i[k] - diode).abs() <= 1e-12 * terms,
            "t = {}: {} vs {diode}",
            t[k],
            i[k]
        );
        let kvl = u - q[k] / 1e-3 - 100.0 * i[k] - v_d[k];
        assert!(kvl.abs() <= 1e-12 * u.abs().max(1.0), "t = {}: {kvl}", t[k]);
    }
    // The energy balance holds through the loop.
    let (e, dis, sup) = (
        csv.col("energy"),
        csv.col("dissipated"),
        csv.col("supplied"),
    );
    let scale = sup.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for k in 0..t.len() {
        assert!(
            (e[k] + dis[k] - sup[k]).abs() <= 1e-8 * scale,
            "t = {}",
            t[k]
        );
    }
}

#[test]
fn a_loop_without_a_solution_stops_the_run_with_its_residual() {
    let path = repo("bgc/tests/fixtures/loops/valve_loop.bg");
    // u = -10 from the start: i^2 + 19 i + 100 = 0 has no real root; the smallest |r| over real i is
    // 100 - 19^2/4 = 9.75 (at i = -9.5), which is where the damped iteration stops.
    let (code, out, err) = bgc(&["simulate", &path, "--t-end", "1", "--input", "u=-10"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(
        err.contains("the algebraic loop for `loop_f_valve` could not be solved at t = 0.0:"),
        "{err}"
    );
    assert!(
        err.contains("the residual of `loop_f_valve` is 9.750e0"),
        "{err}"
    );
    // u = -0.2 - t: the two roots of i^2 - (2a + 1) i + a^2 = 0 (a = u - q) merge and vanish when a = -1/4, a
    // little before t = 0.05 (q is slightly negative by then); the run stops there, not at the start.
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1", "--input", "u=-0.2 - t"]);
    assert_eq!(code, 1, "{err}");
    let time: f64 = err
        .split("could not be solved at t = ")
        .nth(1)
        .and_then(|rest| rest.split(':').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no time in {err}"));
    assert!(time > 0.04 && time < 0.05, "{err}");
    // With u = 0.5 the loop has its solution (the smaller root) and the run completes.
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1", "--input", "u=0.5"]);
    assert_eq!(code, 0, "{err}");
}

/// Breakpoints that differ by rounding (`step(0.3)` and `step(0.1 + 0.2)`, 0.3 and 0.30000000000000004) made a
/// segment shorter than the solver resolves at its start, and the run failed: "the solver failed at t = 0.3: ODE
/// solver error: Stop time is at the current state time". The state now goes on unchanged over such a segment,
/// and the run equals the one with a single step of twice the height. A whole run that short gets a warning.
#[test]
fn breakpoints_that_differ_by_rounding_are_one_time() {
    let model = corpus("oscillator.bg");
    let run = |signal: &str| {
        let input = format!("F={signal}");
        simulate(&[
            &model, "--t-end", "1", "--dt-out", "0.01", "--input", &input,
        ])
    };
    let reference = run("2*step(0.3)");
    for signal in ["step(0.3)+step(0.1+0.2)", "step(0.3)+step(0.3+1e-15)"] {
        let got = run(signal);
        assert_eq!(got.rows.len(), reference.rows.len(), "{signal}");
        for (a, b) in got.rows.iter().zip(&reference.rows) {
            for (x, y) in a.iter().zip(b) {
                assert!(
                    (x - y).abs() <= 1e-9 * (1e-3 + y.abs()),
                    "{signal}: {a:?} vs {b:?}"
                );
            }
        }
    }
    let (code, _, err) = bgc(&["simulate", &model, "--t-end", "1e-30", "--input", "F=1"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains(
            "warning: the interval from t = 0e0 to 1e-30 s is shorter than the solver resolves"
        ),
        "{err}"
    );
}

/// The time column is decimal where that is short and has an exponent at the ends of the range: `--t-end 1e-300`
/// printed each time as three hundred digits (`0.000…0001`), `--t-end 1e20` as twenty-one.
#[test]
fn times_at_the_ends_of_the_range_are_written_with_an_exponent() {
    let osc = corpus("oscillator.bg");
    for (t_end, dt, last) in [
        ("1e-300", "2.5e-301", "1e-300"),
        ("1e20", "2.5e19", "1e20"),
        ("1", "0.25", "1"),
        ("1e-3", "5e-5", "0.001"),
    ] {
        let (code, out, err) = bgc(&[
            "simulate", &osc, "--t-end", t_end, "--dt-out", dt, "--input", "F=1",
        ]);
        assert_eq!(code, 0, "{err}");
        let times: Vec<&str> = out
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap_or(""))
            .collect();
        assert_eq!(times.last(), Some(&last), "{out}");
        assert!(times.iter().all(|t| t.len() <= 24), "{times:?}");
        // Each reads back as a number no larger than the end.
        let end: f64 = t_end.parse().unwrap_or(f64::NAN);
        assert!(
            times
                .iter()
                .all(|t| t.parse::<f64>().is_ok_and(|v| (0.0..=end).contains(&v))),
            "{times:?}"
        );
    }
}

/// A mass matrix that is singular where the run is (the cart-pole I-field with a massless bob: `M = [[2, 0],
/// [0, 0]]`) is named as the cause, with its element and the time, rather than a non-finite derivative of one of
/// its states.
#[test]
fn a_singular_mass_matrix_stops_the_run_naming_its_element() {
    let path = repo("bgc/tests/fixtures/fields/cart_pole_field.bg");
    let (code, out, err) = bgc(&["simulate", &path, "--t-end", "1", "--param", "m=0"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.starts_with("t [s],"), "{out}");
    assert!(
        err.contains("error: the mass matrix of `body` is singular at t = 0.0"),
        "{err}"
    );
    // With the bob's mass the same run completes.
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1"]);
    assert_eq!(code, 0, "{err}");
}

/// `y = -e(c)` at rest is `-0.0`, which the CSV printed as `-0e0` (it reads back exactly, but reads as a negative
/// number to a person and to a plot's axis); a zero is now `0e0` whatever its sign.
#[test]
fn a_zero_is_printed_without_a_sign() {
    let path = temp_model(
        "negative_zero",
        "model m {\n    domain electrical;\n    input u [V];\n    Se s = u;\n    1 j;\n    R r = 1;\n    C c = 1;\n    \
         bond s -> j -> r, c;\n    output y [V] = -e(c);\n}\n",
    );
    let (code, out, err) = bgc(&["simulate", &path, "--t-end", "1", "--input", "u=0"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.lines().count() > 2, "{out}");
    assert!(!out.contains("-0e0"), "{out}");
    assert!(
        out.lines()
            .nth(1)
            .is_some_and(|row| row == "0,0e0,0e0,0e0,0e0,0e0"),
        "{out}"
    );
}
