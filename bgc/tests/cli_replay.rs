//! `bgc simulate --data`: a measured record's inputs replayed, against the exact discretisation and against the
//! same signal written as an expression.

use crate::cli_support;

use cli_support::{Csv, bgc, bgc_stdin, simulate, temp_model};

/// A mass with a damper pushed by a force: `ṗ = F − (b/m) p`, one state with the pole `a = b/m = 1.5 /s`.
const PUSHED_MASS: &str = "model pushed {
    domain translational;
    param m = 2 [kg];
    param b = 3 [N s/m];
    input F [N];
    Se push = F;
    I mass = m;
    R damper = b;
    1 j;
    bond push -> j;
    bond j -> mass, damper;
    output v [m/s] = f(mass);
}
";

fn record(name: &str, text: &str) -> String {
    let path = crate::scratch::path(&format!("{name}.csv"));
    std::fs::write(&path, text).expect("record written");
    path.display().to_string()
}

/// Held samples are the zero-order hold: at the sample times the state is the exact discretisation
/// `p[k+1] = e^(−aT) p[k] + (1 − e^(−aT))/a · F[k]`, computed here by hand. Every change of the held value
/// restarts the integrator, so no step straddles a jump. The record is a fit's, with a measured output column
/// (some cells empty), which a replay reads past.
#[test]
fn held_samples_give_the_exact_zero_order_hold_response() {
    let model = temp_model("replay_zoh", PUSHED_MASS);
    let forces = [1.0, -2.0, 0.5, 3.0, 3.0];
    let mut text = String::from("t,F,v\n");
    for (k, f) in forces.iter().enumerate() {
        let measured = if k % 2 == 0 { "0.25" } else { "" };
        text += &format!("{},{f},{measured}\n", 0.1 * k as f64);
    }
    let data = record("replay_zoh", &text);
    let csv = simulate(&[
        &model, "--data", &data, "--t-end", "0.4", "--dt-out", "0.1", "--rtol", "1e-11", "--atol",
        "1e-13",
    ]);
    let (a, dt) = (1.5_f64, 0.1_f64);
    let decay = (-a * dt).exp();
    let mut p = 0.0;
    let got = csv.col("p_mass");
    assert_eq!(got.len(), 5);
    for (k, got) in got.iter().enumerate() {
        assert!(
            (got - p).abs() < 1e-9,
            "t = {}: {got} against {p}",
            0.1 * k as f64
        );
        p = decay * p + (1.0 - decay) / a * forces[k];
    }
}

/// Interpolated samples of a ramp are the ramp: the same run as `--input 'F=4*min(t, 0.5)'`, and after the
/// record's last sample its last value holds (with a warning that says so).
#[test]
fn interpolated_samples_are_the_signal_between_them_and_hold_after_the_record() {
    let model = temp_model("replay_linear", PUSHED_MASS);
    let data = record("replay_linear", "t [ms],F [kN]\n0,0\n500,0.002\n");
    let common = [
        "--t-end", "1", "--dt-out", "0.125", "--rtol", "1e-11", "--atol", "1e-13",
    ];
    let mut args = vec![model.as_str(), "--data", &data, "--interp", "linear"];
    args.extend(common);
    let mut all = vec!["simulate"];
    all.extend(&args);
    let (code, out, err) = bgc(&all);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("covers t = 0 to 0.5 s: its last values hold from t = 0.5 to --t-end 1"),
        "{err}"
    );
    let replayed = Csv::parse(&out);
    let mut args = vec![model.as_str(), "--input", "F=4*min(t, 0.5)"];
    args.extend(common);
    let written = simulate(&args);
    for (r, w) in replayed.col("p_mass").iter().zip(written.col("p_mass")) {
        assert!((r - w).abs() < 1e-9, "{r} against {w}");
    }
    assert!(replayed.col("p_mass")[8] > 0.5, "the force acted");
}

/// A record whose time column is `time` (as FMPy and Modelica tools write it), here in milliseconds, is read as
/// one whose column is `t` in seconds.
#[test]
fn a_time_column_named_time_is_the_time() {
    let model = temp_model("replay_time", PUSHED_MASS);
    let args = |data: &str| {
        let mut all = vec![
            "simulate".to_string(),
            model.clone(),
            "--data".into(),
            data.into(),
        ];
        all.extend(["--t-end", "1", "--dt-out", "0.25"].map(String::from));
        all
    };
    let run = |data: &str| {
        let all = args(data);
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        bgc(&refs)
    };
    let (code, with_t, err) = run(&record("replay_t", "t,F\n0,1\n0.5,-1\n1,0\n"));
    assert_eq!(code, 0, "{err}");
    let (code, with_time, err) = run(&record("replay_time", "time [ms],F\n0,1\n500,-1\n1000,0\n"));
    assert_eq!((code, with_time), (0, with_t), "{err}");
}

/// Tab-separated text (a spreadsheet's "Text (Tab delimited)") with a decimal comma and an empty output cell is
/// the record written with commas.
#[test]
fn a_tab_separated_record_is_read_as_a_comma_separated_one() {
    let model = temp_model("replay_tab", PUSHED_MASS);
    let run = |name: &str, text: &str| {
        let data = record(name, text);
        let (code, out, err) = bgc(&[
            "simulate", &model, "--data", &data, "--t-end", "1", "--dt-out", "0.5",
        ]);
        assert_eq!(code, 0, "{text}: {err}");
        out
    };
    let commas = run("replay_commas", "t,F,v\n0,1.5,0.1\n0.5,-1,\n1,0,0.3\n");
    let tabs = run(
        "replay_tabs",
        "t [s]\tF\tv\n0\t1,5\t0,1\n0,5\t-1\t\n1\t0\t0,3\n",
    );
    assert_eq!(tabs, commas);
    // A spreadsheet's "Unicode text": UTF-16 with its byte-order mark (before: "stream did not contain valid
    // UTF-8").
    let text = "t [s]\tF\tv\n0\t1,5\t0,1\n0,5\t-1\t\n1\t0\t0,3\n";
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    let path = crate::scratch::path("replay_utf16.txt");
    std::fs::write(&path, utf16).expect("record written");
    let data = path.display().to_string();
    let (code, out, err) = bgc(&[
        "simulate", &model, "--data", &data, "--t-end", "1", "--dt-out", "0.5",
    ]);
    assert_eq!((code, out), (0, commas), "{err}");
}

/// A record with nothing to replay (a model without inputs, or every input given with `--input`) is said so,
/// instead of being read and silently left unused.
#[test]
fn a_record_with_nothing_to_replay_is_said_so() {
    let model = temp_model("replay_nothing", PUSHED_MASS);
    let only_t = record("replay_nothing_t", "t\n0\n1\n");
    let (code, _, err) = bgc(&[
        "simulate", &model, "--t-end", "1", "--data", &only_t, "--input", "F=1",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("every input is given with --input: nothing of the record"),
        "{err}"
    );
    let pendulum = crate::cli_support::repo("models/pendulum_rig.bg");
    let (code, _, err) = bgc(&["simulate", &pendulum, "--t-end", "0.1", "--data", &only_t]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("the model has no inputs: nothing of the record"),
        "{err}"
    );
}

/// A record read from standard input gives the run of the same record read from a file.
#[test]
fn a_record_may_come_from_standard_input() {
    let model = temp_model("replay_stdin", PUSHED_MASS);
    let text = "t,F\n0,1\n0.5,-1\n1,0\n";
    let data = record("replay_stdin", text);
    let args = [
        "simulate", &model, "--t-end", "1", "--dt-out", "0.25", "--data",
    ];
    let (code, from_file, err) = bgc(&[&args[..], &[data.as_str()]].concat());
    assert_eq!(code, 0, "{err}");
    let dir = crate::scratch::path("replay_stdin_dir");
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let (code, from_stdin, err) = bgc_stdin(&[&args[..], &["-"]].concat(), text, &dir);
    assert_eq!((code, from_stdin), (0, from_file), "{err}");
}

/// Each way a record or the command line can be wrong gets its own error, and no rows.
#[test]
fn a_record_that_cannot_be_replayed_is_refused_with_the_cause() {
    let model = temp_model("replay_errors", PUSHED_MASS);
    let cases = [
        (
            "t,F\n0,1\n1,2\n",
            &["--input", "F=1"][..],
            "input `F` is given on the command line and in column 2 of the record: give it once",
        ),
        (
            "t,G\n0,1\n1,2\n",
            &[][..],
            "the record has no column for the model input `F`",
        ),
        (
            "t,F,x\n0,1,2\n1,2,3\n",
            &[][..],
            "column 3 `x` is no input or output of the model",
        ),
        (
            "t,F\n0,1\n0,2\n",
            &[][..],
            "times must be strictly increasing",
        ),
        ("t,F\n0,1\n1,nan\n", &[][..], "line 3, column `F` is NaN"),
        ("t,F [m]\n0,1\n1,2\n", &[][..], "the record's column"),
        (
            "t,F\n0,1\n",
            &[][..],
            "the record has too few samples (1): it needs a header line and at least two",
        ),
        (
            "t,F,\n0,1,\n1,2,\n",
            &[][..],
            "column 3 has no name in the header",
        ),
    ];
    for (k, (text, extra, want)) in cases.iter().enumerate() {
        let data = record(&format!("replay_error_{k}"), text);
        let mut args = vec!["simulate", model.as_str(), "--t-end", "1", "--data", &data];
        args.extend_from_slice(extra);
        let (code, out, err) = bgc(&args);
        assert_eq!((code, out.as_str()), (1, ""), "{text}: {err}");
        assert!(err.contains(want), "{text}: {err}");
    }
    // The note about a column of `bgc simulate` belongs to that column's error only, not to another one's.
    let data = record("replay_error_twice", "t,F,t,energy\n0,1,0,0\n1,2,1,0\n");
    let (code, _, err) = bgc(&["simulate", &model, "--t-end", "1", "--data", &data]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("column `t` appears twice (columns 1 and 3)") && !err.contains("energy"),
        "{err}"
    );
    let (code, _, err) = bgc(&["simulate", &model, "--t-end", "1", "--interp", "linear"]);
    assert_eq!(code, 2, "--interp without --data: {err}");
    assert!(err.contains("--data"), "{err}");
}

/// Standard input named twice would be read once and then be empty: refused before anything is read.
#[test]
fn standard_input_named_twice_is_refused() {
    let dir = crate::scratch::path("replay_twice");
    std::fs::create_dir_all(&dir).expect("scratch directory");
    for args in [
        &["simulate", "-", "--t-end", "1", "--data", "-"][..],
        &["fit", "-", "--data", "-", "--free", "m"][..],
        &["check", "-", "-"][..],
        &["fmt", "-", "-"][..],
    ] {
        let (code, out, err) = bgc_stdin(args, PUSHED_MASS, &dir);
        assert_eq!((code, out.as_str()), (2, ""), "{args:?}: {err}");
        assert!(
            err.contains("standard input (`-`) is named 2 times, but it can be read only once"),
            "{args:?}: {err}"
        );
    }
}
