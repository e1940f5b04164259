//! Numbers that mean what the user wrote: declared units of outputs, inputs, vars and parameters, units on the
//! command line, repeated names, inputs held at zero, and the state space's text form.

use crate::cli_support;

use cli_support::{Csv, bgc, matrix, ok_json, repo, temp_model, units};

/// A rotor driven by a torque in mN m, with its speed in rad/s and in rpm and its angle in degrees.
const ROTOR: &str = "model rotor_rpm {
    domain rotational;
    param J = 2 [kg m^2];
    input tau [mN m];
    Se drive = tau;
    1 w;
    I rotor = J;
    bond drive -> w -> rotor;
    var theta [deg] = int(f(rotor));
    output speed [rad/s] = f(rotor);
    output speed_rpm [rpm] = f(rotor);
    output angle [rad] = theta;
}
";

/// An inductor on a voltage source, with its inductance declared in mH.
const COIL: &str = "model coil {
    domain electrical;
    param L = 0.5 [mH];
    input u [V];
    Se supply = u;
    I coil = L;
    bond supply -> coil;
    output i [A] = f(coil);
}
";

/// 60/(2 pi): rad/s to rpm.
const RPM_PER_RAD_S: f64 = 9.549296585513721;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

#[test]
fn an_output_in_rpm_is_printed_in_rpm_with_its_unit_in_the_header() {
    let path = temp_model("rotor_rpm", ROTOR);
    // tau = 1000 mN m = 1 N m on J = 2: the speed is t/2 rad/s, 0.5 rad/s = 4.7746 rpm at t = 1.
    let (code, out, err) = bgc(&[
        "simulate", &path, "--t-end", "1", "--input", "tau=1000", "--rtol", "1e-10", "--atol",
        "1e-12",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    let last = |c: &str| *csv.col(c).last().expect("rows");
    assert!(close(last("speed"), 0.5, 1e-9), "{}", last("speed"));
    assert!(
        close(last("speed_rpm"), 0.5 * RPM_PER_RAD_S, 1e-9),
        "{}",
        last("speed_rpm")
    );
    // The var is in degrees: the angle t^2/4 rad = 0.25 rad at t = 1 is 14.32 deg; the output in rad reads it back.
    assert!(close(
        last("theta"),
        0.25 * 180.0 / std::f64::consts::PI,
        1e-9
    ));
    assert!(close(last("angle"), 0.25, 1e-9));
    assert_eq!(
        units(&out),
        ["s", "N m s", "deg", "rad/s", "rpm", "rad", "J", "J", "J"]
    );
    // The same factor in the state space: C = [1/J, 0; 60/(2 pi J), 0; 0, pi/180].
    let v = ok_json(&["statespace", &path]);
    let c = matrix(&v, "C");
    assert!(close(c[0][0], 0.5, 1e-15));
    assert!(close(c[1][0], 0.5 * RPM_PER_RAD_S, 1e-15), "{c:?}");
    // B in the input's unit: 1 mN m is 1e-3 N m.
    let b = matrix(&v, "B");
    assert!(close(b[0][0], 1e-3, 1e-15), "{b:?}");
    // The generated code multiplies by 60/(2 pi).
    let (code, rust, err) = bgc(&["rust", &path]);
    assert_eq!(code, 0, "{err}");
    assert!(
        rust.contains("y[1] = 9.549296585513721 * f_rotor;"),
        "no rpm factor in the generated code"
    );
}

#[test]
fn a_bare_number_on_the_command_line_is_in_the_declared_unit() {
    let path = temp_model("coil", COIL);
    // C = 1/L: 1/(2.5 mH) = 400 1/H, whether 2.5 is read in the declared mH or written 2.5e-3 [H] or 2500 [uH].
    for given in ["L=2.5", "L=2.5e-3 [H]", "L=2500 [uH]", "L = 2.5 [mH]"] {
        let v = ok_json(&["statespace", &path, "--param", given]);
        let c = matrix(&v, "C");
        assert!(close(c[0][0], 400.0, 1e-12), "{given}: {c:?}");
    }
    // The default 0.5 mH: C = 2000.
    let c = matrix(&ok_json(&["statespace", &path]), "C");
    assert!(close(c[0][0], 2000.0, 1e-12), "{c:?}");
    // A unit of another dimension names both.
    let (code, _, err) = bgc(&["statespace", &path, "--param", "L=2.5 [mm]"]);
    assert_eq!(code, 1);
    assert!(err.contains("parameter `L` is in [mH]"), "{err}");
    assert!(err.contains("[mm] is in m"), "{err}");
    let (code, _, err) = bgc(&["statespace", &path, "--param", "L=2.5 [furlong]"]);
    assert_eq!(code, 1);
    assert!(err.contains("unknown unit `furlong`"), "{err}");
}

/// A hertz is 1/s and so is a radian per second, but a hertz counts cycles of 2π rad: 50 Hz is 3000 rpm as a speed
/// of turning and 477 rpm as a value of 1/s. The command line converts neither way between hertz and an angle unit;
/// within the angle units (and within the frequency units) it converts as usual.
#[test]
fn a_value_is_not_converted_between_hertz_and_an_angle_unit() {
    let shaft = |unit: &str, value: &str| {
        format!(
            "model shaft {{ domain rotational; param w0 = {value} [{unit}]; Sf drive = w0; 1 s; R fr = 2; \
             bond drive -> s -> fr; output torque [N m] = e(fr); }}"
        )
    };
    let rpm = temp_model("shaft_rpm", &shaft("rpm", "3000"));
    let hz = temp_model("shaft_hz", &shaft("Hz", "50"));
    for (path, given) in [
        (&rpm, "w0=50 [Hz]"),
        (&rpm, "w0=3 [kHz]"),
        (&hz, "w0=3000 [rpm]"),
        (&hz, "w0=314 [rad/s]"),
        (&hz, "w0=1 [deg/s]"),
    ] {
        let (code, _, err) = bgc(&["simulate", path, "--t-end", "0.1", "--param", given]);
        assert_eq!(code, 1, "{given}: {err}");
        assert!(err.contains("ambiguous by 2π"), "{given}: {err}");
    }
    // 3000 rpm = 314.159 rad/s: the friction torque 2 × 314.159 N m, given in any angle unit; 50 Hz = 50 1/s.
    let (code, out, err) = bgc(&[
        "simulate",
        &rpm,
        "--t-end",
        "0.1",
        "--param",
        "w0=18000 [deg/s]",
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = Csv::parse(&out);
    let tau = csv.col("torque")[0];
    assert!(close(tau, 200.0 * std::f64::consts::PI, 1e-12), "{tau}");
    let (code, out, err) = bgc(&[
        "simulate",
        &hz,
        "--t-end",
        "0.1",
        "--param",
        "w0=0.05 [kHz]",
    ]);
    assert_eq!(code, 0, "{err}");
    let tau = Csv::parse(&out).col("torque")[0];
    assert!(close(tau, 100.0, 1e-12), "{tau}");
}

#[test]
fn initial_states_inputs_and_operating_points_take_units() {
    let path = temp_model("rotor_rpm_x0", ROTOR);
    // theta(0) = 1 rad is 57.2958 deg in the var's unit; with no torque it stays there.
    let csv = cli_support::simulate(&[
        &path,
        "--t-end",
        "1",
        "--x0",
        "theta=1 [rad]",
        "--input",
        "tau=0",
    ]);
    assert!(close(
        csv.col("theta")[0],
        180.0 / std::f64::consts::PI,
        1e-12
    ));
    // An input given in N m is converted to the declared mN m: 1 N m on J = 2 gives 0.5 rad/s at t = 1.
    let csv = cli_support::simulate(&[
        &path,
        "--t-end",
        "1",
        "--input",
        "tau=1 [N m]",
        "--rtol",
        "1e-10",
        "--atol",
        "1e-12",
    ]);
    assert!(close(*csv.col("speed").last().expect("rows"), 0.5, 1e-9));
    // An energy state in its SI unit; p_rotor = 2 N m s is 1 rad/s.
    let csv = cli_support::simulate(&[
        &path,
        "--t-end",
        "1",
        "--x0",
        "p_rotor=2",
        "--input",
        "tau=0",
    ]);
    assert!(close(csv.col("speed")[0], 1.0, 1e-12));
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1", "--x0", "p_rotor=2 [m]"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("state `p_rotor` is in [N m s], but [m] is in m"),
        "{err}"
    );
    // The SI form is not repeated when it reads as the declared unit (it was `[N m s] (N m s)`).
    assert!(!err.contains("(N m s)"), "{err}");
    let (code, out, err) = bgc(&["statespace", &path, "--at", "tau=1 [N m]", "--verbose"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.is_empty());
    assert!(err.contains("tau = 1000 [mN m] = 1 N m (given)"), "{err}");
}

#[test]
fn verbose_prints_the_effective_values_with_their_units() {
    let path = temp_model("coil_verbose", COIL);
    let (code, _, err) = bgc(&[
        "simulate",
        &path,
        "--t-end",
        "1e-3",
        "--param",
        "L=2.5",
        "--input",
        "u=1",
        "--verbose",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("L = 2.5 [mH] = 0.0025 H (given)"), "{err}");
    assert!(err.contains("p_coil = 0 [V s] (not given)"), "{err}");
    let (code, _, err) = bgc(&["statespace", &path, "-v"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("L = 0.5 [mH] = 0.0005 H (default)"), "{err}");
}

#[test]
fn a_repeated_name_is_an_error() {
    let path = temp_model("coil_repeat", COIL);
    let cases: [&[&str]; 4] = [
        &["statespace", &path, "--param", "L=1", "--param", "L=2"],
        &[
            "simulate", &path, "--t-end", "1", "--x0", "p_coil=1", "--x0", "p_coil=2",
        ],
        &["statespace", &path, "--at", "u=1,u=2"],
        &[
            "simulate", &path, "--t-end", "1", "--input", "u=1", "--input", "u=sin(t)",
        ],
    ];
    for args in cases {
        let (code, out, err) = bgc(args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?}");
        assert!(err.contains("is given twice"), "{args:?}: {err}");
    }
}

#[test]
fn inputs_not_given_are_named_on_stderr() {
    let path = temp_model("rotor_zero", ROTOR);
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: input `tau` is not given and is held at 0"),
        "{err}"
    );
    let (code, _, err) = bgc(&["simulate", &path, "--t-end", "1", "--input", "tau=1"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("held at 0"), "{err}");
}

#[test]
fn simulate_help_lists_every_input_function() {
    let (code, out, _) = bgc(&["simulate", "--help"]);
    assert_eq!(code, 0);
    for f in [
        "step", "ramp", "sin", "cos", "tan", "exp", "ln", "sqrt", "abs", "sign", "min", "max",
    ] {
        assert!(
            out.contains(&format!(" {f}")),
            "`{f}` missing from simulate --help"
        );
    }
}

#[test]
fn a_bare_number_times_t_inside_a_function_is_a_rate() {
    let ok = temp_model(
        "sin_3t",
        "model m {
    domain rotational;
    param w = 2 [rad/s];
    Se drive = 0.1 * sin(3*t) + sin(w*t) * exp(-t/2) + cos(2*pi*5*t + 1);
    I rotor = 1;
    bond drive -> rotor;
}
",
    );
    let (code, _, err) = bgc(&["check", &ok]);
    assert_eq!(code, 0, "{err}");
    let bad = temp_model(
        "sin_lt",
        "model m {
    domain rotational;
    param L = 2 [m];
    Se drive = sin(L*t);
    I rotor = 1;
    bond drive -> rotor;
}
",
    );
    let (code, _, err) = bgc(&["check", &bad]);
    assert_eq!(code, 1);
    assert!(err.contains("BG0309"), "{err}");
    assert!(err.contains("m s"), "{err}");
}

#[test]
fn structural_zeros_of_the_declared_coordinates_are_exact_and_text_is_readable() {
    let path = repo("models/back_support.bg");
    let v = ok_json(&["statespace", &path, "--coords", "declared"]);
    for key in ["A", "B", "C", "D"] {
        for (r, row) in matrix(&v, key).iter().enumerate() {
            for (c, x) in row.iter().enumerate() {
                // Every entry is 0 or of a physical size: no rounding residue (5e-11, -6.7e-8, -2.9e-14).
                assert!(
                    *x == 0.0 || x.abs() > 1e-6,
                    "{key}[{r}][{c}] = {x:e}: residue where the structure has a zero"
                );
                assert!(
                    !(*x == 0.0 && x.is_sign_negative()),
                    "{key}[{r}][{c}] is -0"
                );
            }
        }
    }
    let (code, out, err) = bgc(&[
        "statespace",
        &path,
        "--coords",
        "declared",
        "--format",
        "text",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("0.000000e0"), "{out}");
    assert!(!out.contains("-0 "), "{out}");
    insta::assert_snapshot!("back_support_declared_statespace_text", out);
}
