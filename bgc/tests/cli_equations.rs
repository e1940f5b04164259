//! The equation commands of the CLI: `bgc equations`, `bgc statespace`, `bgc simulate`, run as a user would.

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn repo(path: &str) -> String {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    root.join("..").join(path).display().to_string()
}

fn corpus(name: &str) -> String {
    repo(&format!("bgc/tests/corpus/{name}"))
}

/// Runs `bgc` and returns the exit code, standard output and standard error.
fn bgc(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(args)
        .arg("--color=never")
        .output()
        .expect("bgc runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok_json(args: &[&str]) -> Value {
    let (code, out, err) = bgc(args);
    assert_eq!(code, 0, "stderr: {err}");
    serde_json::from_str(&out).expect("valid JSON")
}

fn matrix(v: &Value, key: &str) -> Vec<Vec<f64>> {
    v[key]
        .as_array()
        .expect("matrix")
        .iter()
        .map(|r| {
            r.as_array()
                .expect("row")
                .iter()
                .map(|x| x.as_f64().expect("number"))
                .collect()
        })
        .collect()
}

fn names(v: &Value, key: &str) -> Vec<String> {
    v[key]
        .as_array()
        .expect("names")
        .iter()
        .map(|x| x.as_str().expect("name").to_string())
        .collect()
}

fn assert_close(got: &[Vec<f64>], want: &[Vec<f64>], rel: f64) {
    assert_eq!(got.len(), want.len());
    for (r, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len());
        for (c, (g, w)) in g.iter().zip(w).enumerate() {
            assert!(
                (g - w).abs() <= rel * w.abs().max(1.0),
                "[{r}][{c}]: got {g}, want {w}"
            );
        }
    }
}

/// A simulation's CSV: the header and the rows.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn parse(text: &str) -> Csv {
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().expect("number")).collect())
            .collect();
        Csv { header, rows }
    }

    fn col(&self, name: &str) -> Vec<f64> {
        let i = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"));
        self.rows.iter().map(|r| r[i]).collect()
    }
}

fn simulate(args: &[&str]) -> Csv {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    let (code, out, err) = bgc(&all);
    assert_eq!(code, 0, "stderr: {err}");
    Csv::parse(&out)
}

#[test]
fn back_support_state_space_in_energy_coordinates_is_the_hand_derived_one() {
    let v = ok_json(&[
        "statespace",
        &repo("models/back_support.bg"),
        "--format",
        "json",
    ]);
    assert_eq!(
        names(&v, "states"),
        [
            "p_rotor",
            "q_gear_spring",
            "p_sensor_in",
            "q_sensor_spring",
            "p_sensor_out",
            "q_coupling_spring"
        ]
    );
    assert_eq!(names(&v, "inputs"), ["tau_m", "omega_h"]);
    assert_eq!(names(&v, "outputs"), ["omega_m", "tau_s", "tau_h"]);
    // By hand, from the physics of Fig. 6 in speeds and twist angles z = [w_m, th_gc, w_si, th_sc, w_se, th_hc]
    // (rotor and gearbox input merged, J1 = J_m + J_g; gearbox output speed w_m / r), then x = S z with
    // S = diag(J_m, 1, J_sint, 1, J_sext, 1) since p_rotor = J_m w_m:
    //   Jm,Jg,bf,r,bg,kg,dg,Js,ks,ds,Je,keh,deh = 3.06e-4,0.40e-4,0,160,0.65,2.64e4,6,1e-4,3.38e4,0,1.19e-3,1125,0
    //   J1 = Jm + Jg; Az = zeros((6,6)); Bz = zeros((6,2))
    //   Az[0] = [-bf/J1-(bg/r**2)/J1-(dg/r**2)/J1, -(kg/r)/J1, (dg/r)/J1, 0, 0, 0]; Bz[0,0] = 1/J1
    //   Az[1] = [1/r, 0, -1, 0, 0, 0]
    //   Az[2] = [(dg/r)/Js, kg/Js, (-dg-ds)/Js, -ks/Js, ds/Js, 0]
    //   Az[3] = [0, 0, 1, 0, -1, 0]
    //   Az[4] = [0, 0, ds/Je, ks/Je, (-ds-deh)/Je, -keh/Je]; Bz[4,1] = deh/Je
    //   Az[5] = [0, 0, 0, 0, 1, 0]; Bz[5,1] = -1
    //   S = diag([Jm, 1, Js, 1, Je, 1]); A = S @ Az @ inv(S); B = S @ Bz
    let a = vec![
        vec![
            -7.507677023121e-01,
            -1.459248554913e+02,
            3.316473988439e+02,
            0.0,
            0.0,
            0.0,
        ],
        vec![2.042483660131e+01, 0.0, -1.0e+04, 0.0, 0.0, 0.0],
        vec![1.225490196078e+02, 2.64e+04, -6.0e+04, -3.38e+04, 0.0, 0.0],
        vec![0.0, 0.0, 1.0e+04, 0.0, -8.403361344538e+02, 0.0],
        vec![0.0, 0.0, 0.0, 3.38e+04, 0.0, -1.125e+03],
        vec![0.0, 0.0, 0.0, 0.0, 8.403361344538e+02, 0.0],
    ];
    assert_close(&matrix(&v, "A"), &a, 1e-11);
    let b = vec![
        vec![0.884393063584, 0.0],
        vec![0.0, 0.0],
        vec![0.0, 0.0],
        vec![0.0, 0.0],
        vec![0.0, 0.0],
        vec![0.0, -1.0],
    ];
    assert_close(&matrix(&v, "B"), &b, 1e-11);
    // omega_m = p_rotor / J_m, tau_s = k_s q_sensor_spring, tau_h = k_eh q_coupling_spring.
    let c = vec![
        vec![1.0 / 3.06e-4, 0.0, 0.0, 0.0, 0.0, 0.0],
        vec![0.0, 0.0, 0.0, 3.38e4, 0.0, 0.0],
        vec![0.0, 0.0, 0.0, 0.0, 0.0, 1125.0],
    ];
    assert_close(&matrix(&v, "C"), &c, 1e-12);
    assert_close(
        &matrix(&v, "D"),
        &[vec![0.0; 2], vec![0.0; 2], vec![0.0; 2]],
        0.0,
    );
}

#[test]
fn back_support_state_space_follows_parameter_overrides() {
    // k_s doubled: A[2][3] = -k_s, A[4][3] = k_s, C[1][3] = k_s.
    let v = ok_json(&[
        "statespace",
        &repo("models/back_support.bg"),
        "--param",
        "k_s=6.76e4",
    ]);
    let a = matrix(&v, "A");
    assert_eq!(a[2][3], -6.76e4);
    assert_eq!(a[4][3], 6.76e4);
    assert_eq!(matrix(&v, "C")[1][3], 6.76e4);
}

#[test]
fn back_support_state_space_in_declared_coordinates_has_the_seven_of_eq_2() {
    let v = ok_json(&[
        "statespace",
        &repo("models/back_support.bg"),
        "--coords",
        "declared",
    ]);
    assert_eq!(
        names(&v, "states"),
        [
            "theta_m",
            "f_rotor",
            "theta_sint",
            "f_sensor_in",
            "theta_sext",
            "f_sensor_out",
            "theta_h"
        ]
    );
    let a = matrix(&v, "A");
    let b = matrix(&v, "B");
    assert_eq!(a.len(), 7);
    // The kinematic rows: d(theta_m)/dt = f_rotor, d(theta_sint)/dt = f_sensor_in, d(theta_sext)/dt = f_sensor_out,
    // d(theta_h)/dt = omega_h.
    for (row, col) in [(0, 1), (2, 3), (4, 5)] {
        for (c, x) in a[row].iter().enumerate() {
            assert_eq!(*x, if c == col { 1.0 } else { 0.0 }, "A[{row}][{c}]");
        }
    }
    assert!(a[6].iter().all(|x| *x == 0.0));
    assert_eq!(b[6], [0.0, 1.0]);
    // The motor row: J1 d(w_m)/dt = tau_m - (b_g + d_g)/r^2 w_m - k_g/r (theta_m/r - theta_sint) + d_g/r w_si.
    let j1 = 3.06e-4 + 0.40e-4;
    let r = 160.0;
    let want = [
        -2.64e4 / (r * r) / j1,
        -(0.65 + 6.0) / (r * r) / j1,
        2.64e4 / r / j1,
        6.0 / r / j1,
    ];
    let got = [a[1][0], a[1][1], a[1][2], a[1][3]];
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= 1e-9 * w.abs(), "got {g}, want {w}");
    }
    assert!((b[1][0] - 1.0 / j1).abs() <= 1e-9 / j1);
}

#[test]
fn symbolic_state_space_is_in_the_parameters() {
    let v = ok_json(&["statespace", &corpus("oscillator.bg"), "--symbolic"]);
    assert_eq!(names(&v, "states"), ["p_mass", "q_spring"]);
    // p' = F - d p/m - k q, q' = p/m.
    assert_eq!(v["A"], serde_json::json!([["-d/m", "-k"], ["1/m", "0"]]));
    assert_eq!(v["B"], serde_json::json!([["1"], ["0"]]));
    let v = ok_json(&[
        "statespace",
        &corpus("oscillator.bg"),
        "--symbolic",
        "--param",
        "m=4",
    ]);
    assert_eq!(
        v["A"],
        serde_json::json!([["-0.25*d", "-k"], ["0.25", "0"]])
    );
}

#[test]
fn state_space_text_and_json_forms_are_stable() {
    let (code, out, _) = bgc(&["statespace", &corpus("oscillator.bg"), "--format", "text"]);
    assert_eq!(code, 0);
    insta::assert_snapshot!("oscillator_statespace_text", out);
    let (code, out, _) = bgc(&["statespace", &corpus("oscillator.bg")]);
    assert_eq!(code, 0);
    insta::assert_snapshot!("oscillator_statespace_json", out);
}

#[test]
fn nonlinear_model_needs_an_operating_point() {
    let (code, out, err) = bgc(&["statespace", &corpus("pendulum.bg")]);
    assert_eq!(code, 1);
    assert!(out.is_empty());
    assert!(err.contains("not linear"), "{err}");
    assert!(err.contains("--at"), "{err}");
    // At theta = 0.3 rad, at rest: the state is [p_mass_x, theta] and d(theta)/dt = p_mass_x / (m l cos(theta)).
    let v = ok_json(&["statespace", &corpus("pendulum.bg"), "--at", "theta=0.3"]);
    assert_eq!(names(&v, "states"), ["p_mass_x", "theta"]);
    let a = matrix(&v, "A");
    let (m, l, th) = (1.0f64, 0.5f64, 0.3f64);
    assert!((a[1][0] - 1.0 / (m * l * th.cos())).abs() < 1e-12, "{a:?}");
    assert_eq!(a[1][1], 0.0);
    let (code, _, err) = bgc(&["statespace", &corpus("pendulum.bg"), "--at", "phi=1"]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown state or input `phi`"), "{err}");
}

#[test]
fn parameter_errors_are_reported() {
    let (code, _, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--param", "q=1"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("unknown parameter `q`; the model has m, k, d"),
        "{err}"
    );
    let (code, _, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--param", "k=stiff"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("parameter `k` = `stiff`: not a number"),
        "{err}"
    );
    let (code, _, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--param", "m=-2"]);
    assert_eq!(code, 1);
    assert!(err.contains("I `mass` = -2"), "{err}");
    assert!(err.contains("an inertia must be positive"), "{err}");
    let (code, _, err) = bgc(&[
        "simulate",
        &corpus("oscillator.bg"),
        "--t-end",
        "1",
        "--param",
        "d=-1",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("a resistance must not be negative"), "{err}");
    let (code, _, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--param", "k=inf"]);
    assert_eq!(code, 1);
    assert!(err.contains("must be finite"), "{err}");
    // Not of the form NAME=VALUE: a usage error.
    let (code, _, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--param", "k"]);
    assert_eq!(code, 2);
    assert!(err.contains("not of the form NAME=VALUE"), "{err}");
}

#[test]
fn equations_are_printed_in_three_formats() {
    let (code, out, _) = bgc(&["equations", &corpus("oscillator.bg"), "--format", "json"]);
    assert_eq!(code, 0);
    let v: Value = serde_json::from_str(&out).expect("JSON");
    let states: Vec<&str> = v["states"]
        .as_array()
        .expect("states")
        .iter()
        .map(|s| s["name"].as_str().expect("name"))
        .collect();
    assert_eq!(states, ["p_mass", "q_spring"]);
    assert_eq!(v["states"][1]["explicit"], "p_mass/m");
    let (code, out, _) = bgc(&["equations", &corpus("oscillator.bg")]);
    assert_eq!(code, 0);
    assert!(out.contains("p_mass"), "{out}");
    let (code, out, _) = bgc(&["equations", &corpus("oscillator.bg"), "--format", "latex"]);
    assert_eq!(code, 0);
    assert!(out.contains("\\begin{align"), "{out}");
}

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

#[test]
fn declared_coordinates_symbolically_and_their_errors() {
    let v = ok_json(&[
        "statespace",
        &repo("models/back_support.bg"),
        "--coords",
        "declared",
        "--symbolic",
    ]);
    let a = &v["A"];
    assert_eq!(a.as_array().map(Vec::len), Some(7));
    assert_eq!(a[0], serde_json::json!(["0", "1", "0", "0", "0", "0", "0"]));
    // d(f_rotor)/dt: the gearbox spring acts through k_g/r_g on the merged inertia J_m + J_g.
    assert_eq!(a[1][0], "-k_g/((J_m + J_g)*r_g^2)");
    assert_eq!(a[1][2], "k_g/((J_m + J_g)*r_g)");
    let (code, _, err) = bgc(&[
        "statespace",
        &corpus("oscillator.bg"),
        "--coords",
        "declared",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("the model declares no coordinates"), "{err}");
    let (code, _, err) = bgc(&[
        "statespace",
        &repo("models/back_support.bg"),
        "--coords",
        "declared",
        "--at",
        "tau_m=1",
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("--at applies to the energy coordinates only"),
        "{err}"
    );
}
