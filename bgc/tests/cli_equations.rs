//! `bgc equations` and `bgc statespace`, run as a user would.

use crate::cli_support;

use cli_support::{assert_close, bgc, corpus, matrix, names, ok_json, repo};
use serde_json::Value;

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
fn sparse_state_space_lists_the_nonzero_entries() {
    // The oscillator: p' = F - d p/m - k q, q' = p/m; the structural zero A[1][1] and B[1][0] are left out.
    let v = ok_json(&[
        "statespace",
        &corpus("oscillator.bg"),
        "--symbolic",
        "--sparse",
    ]);
    assert_eq!(names(&v, "states"), ["p_mass", "q_spring"]);
    assert_eq!(
        v["A"],
        serde_json::json!({"rows": 2, "cols": 2, "entries": [[0, 0, "-d/m"], [0, 1, "-k"], [1, 0, "1/m"]]})
    );
    assert_eq!(
        v["B"],
        serde_json::json!({"rows": 2, "cols": 1, "entries": [[0, 0, "1"]]})
    );
    // The numeric triplets are the dense form's nonzeros, in row-major order.
    let dense = ok_json(&["statespace", &corpus("oscillator.bg")]);
    let sparse = ok_json(&["statespace", &corpus("oscillator.bg"), "--sparse"]);
    for m in ["A", "B", "C", "D"] {
        let rows = dense[m].as_array().cloned().unwrap_or_default();
        let mut nonzeros = Vec::new();
        for (i, row) in rows.iter().enumerate() {
            for (j, x) in row
                .as_array()
                .cloned()
                .unwrap_or_default()
                .iter()
                .enumerate()
            {
                if x.as_f64() != Some(0.0) {
                    nonzeros.push(serde_json::json!([i, j, x]));
                }
            }
        }
        assert_eq!(sparse[m]["entries"], Value::Array(nonzeros), "{m}");
        assert_eq!(sparse[m]["rows"], rows.len());
    }
    let (code, out, _) = bgc(&[
        "statespace",
        &corpus("oscillator.bg"),
        "--sparse",
        "--format",
        "text",
    ]);
    assert_eq!(code, 0);
    assert!(out.contains("\nA: 2 x 2, 3 nonzero\n"), "{out}");
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
    // At theta = 0.3 rad, at rest: the state is [f_pivot, theta] (the pivot's angular velocity: the bob's
    // inertias are coupled through l cos(theta), l sin(theta)); m l² ω̇ = -m g l sin θ - b ω.
    let v = ok_json(&["statespace", &corpus("pendulum.bg"), "--at", "theta=0.3"]);
    assert_eq!(names(&v, "states"), ["f_pivot", "theta"]);
    let a = matrix(&v, "A");
    let (m, l, g, b, th) = (1.0f64, 0.5f64, 9.81f64, 0.01f64, 0.3f64);
    assert!((a[0][0] + b / (m * l * l)).abs() < 1e-12, "{a:?}");
    assert!((a[0][1] + g * th.cos() / l).abs() < 1e-12, "{a:?}");
    assert_eq!(a[1], [1.0, 0.0]);
    let (code, _, err) = bgc(&["statespace", &corpus("pendulum.bg"), "--at", "phi=1"]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown state or input `phi`"), "{err}");
}

#[test]
fn an_operating_point_names_what_a_wrong_name_is() {
    let model = repo("models/back_support.bg");
    // A typo gets the nearest name.
    let (code, _, err) = bgc(&["statespace", &model, "--at", "p_rotr=1"]);
    assert_eq!(code, 1);
    assert!(
        err.contains(
            "unknown state or input `p_rotr` (did you mean `p_rotor`?); the model has p_rotor,"
        ),
        "{err}"
    );
    // An integrated flow that no rate or output reads is a state of the model, not of its state space.
    let (code, _, err) = bgc(&["statespace", &model, "--at", "theta_m=0.1"]);
    assert_eq!(code, 1);
    assert!(
        err.contains(
            "`theta_m` is an integrated flow (`var`) that neither the rates nor the outputs read"
        ),
        "{err}"
    );
    // A parameter's typo, through the same path as every `NAME=VALUE` option.
    let (code, _, err) = bgc(&["statespace", &model, "--param", "J_mm=1"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("unknown parameter `J_mm` (did you mean `J_m`?)"),
        "{err}"
    );
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
    assert_eq!(a[1][0], "-k_g/(r_g^2*(J_m + J_g))");
    assert_eq!(a[1][2], "k_g/(r_g*(J_m + J_g))");
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
