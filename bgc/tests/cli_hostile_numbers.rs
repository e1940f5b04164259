//! Numbers out of range, in the model or on the command line: a part of an expression that is infinite or NaN, a
//! linearisation or a symbolic entry that overflows, a fit whose squared error overflows or underflows. Each is an
//! error that names the place and the cause (exit 1), never an `inf`, a `NaN` or a `null` printed with exit 0.

use crate::cli_support;

use cli_support::{bgc, corpus};

/// Writes `text` to a file of the tests' scratch directory and returns its path.
fn temp_file(name: &str, text: &str) -> String {
    let path = crate::scratch::path(&format!("numbers-{name}"));
    std::fs::write(&path, text).expect("temporary file written");
    path.display().to_string()
}

/// A damped mass driven by a force, with the damper's law given in braces.
fn with_law(law: &str) -> String {
    format!(
        "model a {{\n    domain translational;\n    param d = 1 [N s/m];\n    input v [m/s];\n    Sf s = v;\n    \
         I m = 1;\n    1 j;\n    R r {{ {law} }}\n    bond s -> j -> m, r;\n}}\n"
    )
}

/// `e = d*f/0`, `ln(0)`, `sqrt(-1)`, `(-8)^(1/3)` in a law: before, `bgc check` passed and `bgc equations` printed
/// `e_r = inf*d*f_m` or `e_r = NaN` with exit 0 (the engine folded the numbers). Now BG0403 at the part.
#[test]
fn a_part_of_a_law_with_no_finite_value_is_bg0403_at_the_part() {
    for (law, part, label) in [
        ("e = d * f / 0;", "d * f / 0", "this divides by zero"),
        ("e = ln(0) * d * f;", "ln(0)", "this is -inf"),
        ("e = sqrt(-1) * d * f;", "sqrt(-1)", "this is NaN"),
        (
            "e = (-8) ^ (1 / 3) * d * f;",
            "(-8) ^ (1 / 3)",
            "this is NaN",
        ),
        (
            "e = 0 * d * f / 0 + d * f;",
            "0 * d * f / 0",
            "this divides by zero",
        ),
    ] {
        let text = with_law(law);
        let path = temp_file("law.bg", &text);
        for cmd in ["check", "equations", "rust"] {
            let (code, out, err) = bgc(&[cmd, &path]);
            assert_eq!(code, 1, "{cmd} {law}: {err}\n{out}");
            assert!(err.contains("error[BG0403]"), "{cmd} {law}: {err}");
            assert!(err.contains(label), "{cmd} {law}: {err}");
            let line = text.lines().position(|l| l.contains(part)).expect("line") + 1;
            let col = text
                .lines()
                .nth(line - 1)
                .and_then(|l| l.find(part))
                .expect("col")
                + 1;
            assert!(
                err.contains(&format!(":{line}:{col}")),
                "{cmd} {law}: {err}"
            );
            assert!(
                !out.contains("inf") && !out.contains("NaN"),
                "{cmd} {law}: {out}"
            );
        }
    }
    // A finite part, a division by a parameter and a zero numerator are not findings.
    let path = temp_file("fine.bg", &with_law("e = 0 / 2 * d * f + d * f / 1e-300;"));
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 0, "{err}");
}

/// An infinite resistance said "a resistance cannot be negative".
#[test]
fn an_infinite_resistance_is_called_infinite() {
    let path = temp_file(
        "inf_r.bg",
        "model a {\n    domain translational;\n    param big = 1e300 [N s/m];\n    input v [m/s];\n    Sf s = v;\n    \
         I m = 1;\n    R r = big * big;\n    1 j;\n    bond s -> j -> m, r;\n}\n",
    );
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("`r` has a resistance of inf (it must be finite)"),
        "{err}"
    );
}

/// `--param b=1e308 --at theta=1` on the pendulum (a mass-matrix model): A[0][0] overflowed in the solve with the
/// mass matrix and was printed as `null`, exit 0.
#[test]
fn a_linearisation_through_a_mass_matrix_that_overflows_is_refused() {
    let (code, out, err) = bgc(&[
        "statespace",
        &corpus("pendulum.bg"),
        "--param",
        "b=1e308",
        "--at",
        "theta=1",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        err.contains("error: no state space: A[0][0] evaluates to a non-finite number"),
        "{err}"
    );
    assert!(!out.contains("null"), "{out}");
}

/// `--symbolic --param d=1e308 --param m=1e-308`: `d/m` was folded to `inf` and printed as the entry `-inf`.
#[test]
fn a_symbolic_entry_that_overflows_is_refused() {
    let (code, out, err) = bgc(&[
        "statespace",
        &corpus("oscillator.bg"),
        "--symbolic",
        "--param",
        "d=1e308",
        "--param",
        "m=1e-308",
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        err.contains("no symbolic state space: A[0][0] holds the number -inf"),
        "{err}"
    );
    assert!(!out.contains("inf"), "{out}");
    // In range, the same command still prints the entries.
    let (code, out, err) = bgc(&["statespace", &corpus("oscillator.bg"), "--symbolic"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"-d/m\""), "{out}");
}

const OSC: &str = "model osc {\n    domain translational;\n    param m = 2 [kg];\n    param k = 800 [N/m];\n    \
param d = 4 [N s/m];\n    input F [N];\n    Se push = F;\n    I mass = m;\n    C spring = 1 / k;\n    \
R damper = d;\n    1 v;\n    bond push -> v -> mass, spring, damper;\n    output x [m] = q(spring);\n}\n";

/// A record whose squared errors overflow (values of 1e308), or a weight so small that they underflow, made the fit
/// stop at its start with "the gradient vanished (a minimum); converged", exit 0, and a residual RMS of `inf`.
#[test]
fn a_fit_whose_squared_error_is_out_of_range_is_refused() {
    let model = temp_file("osc.bg", OSC);
    let huge = temp_file("huge.csv", "t,F,x\n0,0,1e308\n0.1,1,1e308\n0.2,1,1e308\n");
    let (code, out, err) = bgc(&["fit", &model, "--data", &huge, "--free", "k"]);
    assert_eq!(code, 1, "{err}\n{out}");
    assert!(
        err.contains("the weighted squared error at the start is inf"),
        "{err}"
    );
    let fine = temp_file("fine.csv", "t,F,x\n0,0,0\n0.1,1,1e-3\n0.2,1,3e-3\n");
    let (code, out, err) = bgc(&[
        "fit", &model, "--data", &fine, "--free", "k", "--weight", "x=1e-320",
    ]);
    assert_eq!(code, 1, "{err}\n{out}");
    assert!(err.contains("out of the range of f64"), "{err}");
}

/// A record saved as "CSV UTF-8" by a spreadsheet starts with a byte-order mark: it was refused with "no `t`
/// column (the header is `\u{feff}t,F,x`)".
#[test]
fn a_record_with_a_byte_order_mark_is_read() {
    let model = temp_file("osc_bom.bg", OSC);
    let mut csv = String::from("\u{feff}t,F,x\r\n");
    for i in 0..=20 {
        let t = i as f64 * 0.01;
        // The static deflection F/k under a held unit force, far from it at the start: a record the model can fit.
        csv.push_str(&format!(
            "{t},1,{}\r\n",
            if i == 0 { 0.0 } else { 1.0 / 800.0 }
        ));
    }
    let data = temp_file("bom.csv", &csv);
    let (code, out, err) = bgc(&["fit", &model, "--data", &data, "--free", "k"]);
    assert!(!err.contains("no `t` column"), "{err}");
    assert!(code == 0 || code == 3, "{err}\n{out}");
    assert!(out.contains("fit of `osc` to 21 samples"), "{out}");
}

/// `--param n=0` on a gear's ratio: the file's own default would be BG0401, but on the command line the ratio was
/// taken, and `statespace` printed B = 0 and `simulate` a load that never moves, with exit 0.
#[test]
fn a_zero_transformer_ratio_on_the_command_line_is_refused() {
    let path = temp_file(
        "gear.bg",
        "model gear {\n    domain rotational;\n    param n = 10 [1];\n    param J = 1 [kg m^2];\n    \
         input tau [N m];\n    Se s = tau;\n    1 j1;\n    TF g = n;\n    1 j2;\n    I load = J;\n    \
         bond s -> j1 -> g -> j2 -> load;\n}\n",
    );
    for args in [
        vec!["statespace", &path, "--param", "n=0"],
        vec![
            "simulate", &path, "--t-end", "1", "--input", "tau=1", "--param", "n=-0",
        ],
    ] {
        let (code, out, err) = bgc(&args);
        assert_eq!(code, 1, "{args:?}: {out}");
        assert!(
            err.contains("TF `g` =") && err.contains("a transformer ratio must not be zero"),
            "{args:?}: {err}"
        );
    }
    let (code, _, err) = bgc(&["statespace", &path, "--param", "n=2"]);
    assert_eq!(code, 0, "{err}");
}

/// `--param m=1e-320` (a positive inertia whose reciprocal overflows) ran into "the initial energy is not finite",
/// which named neither the element nor the parameter; `--param k=1e-320` likewise for a compliance `1/k`
/// (`k = 1e320` is refused as not finite). Now each is refused at the element, with the value written short.
#[test]
fn a_coefficient_whose_reciprocal_overflows_is_refused_at_the_element() {
    for (param, element) in [("m=1e-320", "I `mass` = 1e-320"), ("k=1e308", "")] {
        let (code, out, err) = bgc(&[
            "simulate",
            &corpus("oscillator.bg"),
            "--t-end",
            "0.01",
            "--param",
            param,
        ]);
        if element.is_empty() {
            // 1/k = 1e-308 is a compliance whose reciprocal is finite: it runs.
            assert_eq!(code, 0, "{param}: {err}");
            continue;
        }
        assert_eq!(code, 1, "{param}: {out}");
        assert!(
            err.contains(element) && err.contains("its reciprocal is not finite"),
            "{param}: {err}"
        );
    }
    let path = temp_file(
        "tiny_c.bg",
        "model tiny {\n    domain translational;\n    param c = 1 [m/N];\n    input v [m/s];\n    Sf s = v;\n    \
         C spring = c;\n    1 j;\n    bond s -> j -> spring;\n}\n",
    );
    let (code, _, err) = bgc(&["statespace", &path, "--param", "c=4e-324"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("C `spring` = 5e-324"), "{err}");
    assert!(err.lines().all(|l| l.len() < 200), "{err}");
    // The same value as a default is BG0401 at the element (`bgc check` passed it), written short.
    let text = std::fs::read_to_string(corpus("oscillator.bg")).expect("corpus model");
    let path = temp_file(
        "tiny_m.bg",
        &text.replace("param m = 2 [kg]", "param m = 1e-320 [kg]"),
    );
    let (code, _, err) = bgc(&["check", &path]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(
            "error[BG0401]: `mass` has an inertia of 1e-320, whose reciprocal is not finite"
        ) && err.contains("`m` is 1e-320"),
        "{err}"
    );
    assert!(err.lines().all(|l| l.len() < 200), "{err}");
}

/// A finite initial state whose stored energy overflows said "the initial energy is not finite", which named no
/// element; it now names the storage whose energy overflows, and says so when each term is finite and their sum
/// is not.
#[test]
fn an_initial_stored_energy_that_overflows_names_its_element() {
    let model = corpus("oscillator.bg");
    let run = |extra: &[&str]| {
        let mut args = vec!["simulate", &model, "--t-end", "0.01"];
        args.extend(extra);
        bgc(&args)
    };
    // q²/(2·(1/k)) = 1e320·800/2 overflows; the rates (k·q = 8e162) do not.
    let (code, _, err) = run(&["--x0", "q_spring=1e160"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("error: the initial stored energy of `spring` is not finite"),
        "{err}"
    );
    // With m = 0.5 and k = 1, p²/(2m) = 1.69e308 and k·q²/2 = 8.45e307 are finite, and their sum is not.
    let (code, _, err) = run(&[
        "--param",
        "m=0.5",
        "--param",
        "k=1",
        "--x0",
        "p_mass=1.3e154",
        "--x0",
        "q_spring=1.3e154",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(
            "the initial energy (its terms are finite; their sum overflows) is not finite"
        ),
        "{err}"
    );
}

/// A record with times 0 and 1e308 said "the exact discretisation failed: matrix A has a non-finite entry -inf at
/// (0, 0)", a matrix the user never wrote; the error now names the sample interval.
#[test]
fn a_sample_interval_too_long_to_discretise_is_named() {
    let model = temp_file("osc_long.bg", OSC);
    let long = temp_file("long.csv", "t,F,x\n0,1,0\n1e308,1,1e-3\n");
    let (code, out, err) = bgc(&["fit", &model, "--data", &long, "--free", "k"]);
    assert_eq!(code, 1, "{err}\n{out}");
    assert!(
        err.contains("the sample interval of 1e308 s is too long for the exact discretisation"),
        "{err}"
    );
}

/// `--data /dev/zero` read without end (the run was killed after 20 s with its memory growing); a device and a
/// directory are refused without being read.
#[test]
fn a_record_that_is_a_device_is_refused_without_being_read() {
    let model = temp_file("osc_dev.bg", OSC);
    for data in ["/dev/zero", "/"] {
        let (code, _, err) = bgc(&["fit", &model, "--data", data, "--free", "k"]);
        assert_eq!(code, 2, "{data}: {err}");
        assert!(err.contains("not a regular file"), "{data}: {err}");
    }
}

/// `--dt-out 1e-300` was refused with the row count written out in 301 digits.
#[test]
fn too_many_rows_are_counted_in_scientific_notation() {
    let (code, _, err) = bgc(&[
        "simulate",
        &corpus("oscillator.bg"),
        "--t-end",
        "1",
        "--dt-out",
        "1e-300",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("the sampling gives 1.000e300 rows"), "{err}");
    assert!(err.lines().all(|l| l.len() < 200), "{err}");
}

/// A part that is zero for every parameter value only once simplified (`big - big`) passed lowering, and
/// `bgc equations` printed `speed = inf*e_r` (or a rate `inf*d*f_m`) with exit 0; `bgc rust` generated
/// `f64::INFINITY * e_r`. Now BG0608 at the output or the element whose rate it is, for every command that
/// derives equations.
#[test]
fn a_rate_or_output_with_no_finite_value_after_simplification_is_bg0608() {
    let head = "model a {\n    domain translational;\n    param d = 1 [N s/m];\n    param big = 2 [1];\n    \
                input F [N];\n    Se s = F;\n    I m = 1;\n    1 j;\n    bond s -> j -> m, r;\n";
    for (body, subject, place) in [
        (
            "    R r { e = d * f; }\n    output speed [N] = e(r) / (big - big);\n",
            "output `speed`",
            "output speed",
        ),
        (
            "    R r { e = d * f / (big - big); }\n",
            "the rate of `p_m`",
            "I m = 1",
        ),
        (
            "    R r { e = d * f * ln(big - big); }\n",
            "the rate of `p_m`",
            "I m = 1",
        ),
    ] {
        let text = format!("{head}{body}}}\n");
        let path = temp_file("simplified.bg", &text);
        let line = text.lines().position(|l| l.contains(place)).expect("line") + 1;
        for cmd in ["equations", "rust", "statespace"] {
            let (code, out, err) = bgc(&[cmd, &path]);
            assert_eq!(code, 1, "{cmd} {body}: {err}\n{out}");
            assert!(err.contains("error[BG0608]"), "{cmd} {body}: {err}");
            assert!(err.contains(subject), "{cmd} {body}: {err}");
            assert!(err.contains(&format!(":{line}:")), "{cmd} {body}: {err}");
            assert!(!out.contains("INFINITY"), "{cmd} {body}: {out}");
        }
    }
}

/// An explicit method under a forcing of 1e150 at 1 MHz made steps too short to advance `t`: the run went on for
/// minutes, bounded only by the budget of 10,000,000 steps. Now the pace of each 10,000 steps is checked as it
/// is for BDF, and a run that cannot finish at that pace stops at once, saying so.
#[test]
fn an_explicit_run_too_slow_to_finish_stops_at_once() {
    let model = corpus("oscillator.bg");
    let (code, _, err) = bgc(&[
        "simulate",
        &model,
        "--t-end",
        "1e-3",
        "--solver",
        "tsit45",
        "--input",
        "F=1e150*sin(1e6*t)",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("advanced too slowly"), "{err}");
    assert!(err.contains("--solver bdf"), "{err}");
}

/// `--rtol 1e10` was accepted: the run went on with a tolerance that bounds nothing, and the energy-balance warning
/// (at 1000 × rtol) could never fire. A relative tolerance of 1 or more is refused, naming the setting.
#[test]
fn a_relative_tolerance_of_one_or_more_is_refused() {
    let model = corpus("oscillator.bg");
    for rtol in ["1", "1e10"] {
        let (code, _, err) = bgc(&["simulate", &model, "--t-end", "0.1", "--rtol", rtol]);
        assert_eq!(code, 1, "{rtol}: {err}");
        assert!(err.contains("rtol"), "{rtol}: {err}");
        assert!(err.contains("100 %"), "{rtol}: {err}");
    }
    let (code, _, err) = bgc(&["simulate", &model, "--t-end", "0.1", "--rtol", "0.5"]);
    assert_eq!(code, 0, "{err}");
}

/// An input signal that is not finite (`1/0`, `sqrt(t - 1)` before t = 1, `ln(t)` at 0) gave "the derivative of
/// `p_rotor` became non-finite at t = 0.0", which blamed a state for the user's signal; the error now names the
/// input, its value and the time.
#[test]
fn a_non_finite_input_signal_is_named_not_the_state_it_reaches() {
    let model = cli_support::repo("models/back_support.bg");
    for (signal, value) in [("1/0", "inf"), ("sqrt(t-1)", "NaN"), ("-ln(t)", "inf")] {
        let input = format!("tau_m={signal}");
        let (code, _, err) = bgc(&[
            "simulate",
            &model,
            "--t-end",
            "0.1",
            "--input",
            &input,
            "--input",
            "omega_h=0",
        ]);
        assert_eq!(code, 1, "{signal}: {err}");
        assert!(
            err.contains(&format!("error: the input `tau_m` is {value} at t = 0.0")),
            "{signal}: {err}"
        );
    }
    // A finite signal whose power overflows later is still the model's: the supplied power is named.
    let (code, _, err) = bgc(&[
        "simulate",
        &model,
        "--t-end",
        "1",
        "--input",
        "tau_m=exp(1000*t)",
        "--input",
        "omega_h=0",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("error: the derivative of `supplied` became non-finite"),
        "{err}"
    );
}

/// A resistance of 0 is physical (a short) and passes the coefficient checks, but a resistor in conductance
/// causality divides by it: `--param r2=0` on a divider said "the initial i is not finite" (`simulate`), "D[0][0]
/// evaluates to a non-finite number" (`statespace`) or "output `i` evaluates to a non-finite number" (`fit`). Each
/// now names the parameter and the element. Zero where the equations only multiply by it is still accepted.
#[test]
fn a_zero_parameter_the_equations_divide_by_is_named() {
    let model = cli_support::repo("bgc/tests/fmu_support/no_states.bg");
    let record = temp_file("divider.csv", "t,v,i\n0,1,0.025\n0.1,2,0.05\n0.2,3,0.075\n");
    let runs: [&[&str]; 3] = [
        &[
            "simulate", &model, "--t-end", "1", "--input", "v=1", "--param", "r2=0",
        ],
        &["statespace", &model, "--param", "r2=0"],
        &[
            "fit", &model, "--data", &record, "--free", "r1", "--param", "r2=0",
        ],
    ];
    for args in runs {
        let (code, _, err) = bgc(args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.contains(
                "error: parameter `r2` = 0 with these parameter values: the derived equations divide by it \
                 (the coefficient of R `lower`)"
            ),
            "{args:?}: {err}"
        );
    }
    // `upper` sets the effort, e = r1·f: a short there leaves the current v/r2.
    let (code, out, err) = bgc(&[
        "simulate", &model, "--t-end", "1", "--input", "v=3", "--param", "r1=0",
    ]);
    assert_eq!(code, 0, "{err}");
    let last = out.lines().last().unwrap_or_default();
    assert!(last.starts_with("1,1e-1,3e0,"), "{last}");
}

/// A resistor across an effort source with no output reading it: only its dissipated power `u²/R0` divides by
/// `R0`. With `R0 = 0` the run used to start and stop at once with "the derivative of `dissipated` became
/// non-finite"; it is now refused before it starts, naming the parameter and the element, as for a rate.
#[test]
fn a_zero_parameter_only_an_energy_term_divides_by_is_named() {
    let path = temp_file(
        "zero_r_power.bg",
        "model m {\n    domain electrical;\n    param R0 = 1 [Ohm];\n    input u [V];\n    Se a = u;\n    0 n;\n    \
         R r = R0;\n    R r2 = 1;\n    bond a -> n -> r, r2;\n}\n",
    );
    let (code, _, err) = bgc(&[
        "simulate", &path, "--t-end", "1", "--input", "u=1", "--param", "R0=0",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(
            "error: parameter `R0` = 0 with these parameter values: the derived equations divide by it (the \
             coefficient of R `r`)"
        ),
        "{err}"
    );
    // With R0 = 2: dissipated = (1/2 + 1/1) u² t = 1.5 J after 1 s at u = 1, all of it supplied.
    let (code, out, err) = bgc(&[
        "simulate", &path, "--t-end", "1", "--input", "u=1", "--param", "R0=2",
    ]);
    assert_eq!(code, 0, "{err}");
    let last: Vec<f64> = out
        .lines()
        .last()
        .unwrap_or_default()
        .split(',')
        .map(|x| x.parse().unwrap_or(f64::NAN))
        .collect();
    assert!(
        (last[2] - 1.5).abs() < 1e-9 && (last[3] - 1.5).abs() < 1e-9,
        "{last:?}"
    );
}
