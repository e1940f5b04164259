//! The `bgc` command as a user meets it: exit codes, what it prints, and what it does with hostile input.
//!
//! Every fixture under `tests/fixtures/{valid,invalid}` gets one snapshot of `bgc check`: the exit status, stdout
//! and stderr.

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

struct Run {
    status: i32,
    stdout: String,
    stderr: String,
}

/// Runs bgc in `dir` so that paths in messages are the relative paths given.
fn bgc(dir: &Path, args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("cannot start bgc: {e}"));
    Run {
        status: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

impl Run {
    fn transcript(&self) -> String {
        format!(
            "exit: {}\n--- stdout\n{}--- stderr\n{}",
            self.status, self.stdout, self.stderr
        )
    }
}

fn bg_files(sub: &str) -> Vec<String> {
    let dir = fixtures_dir().join(sub);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".bg"))
        .collect();
    names.sort();
    names
}

#[test]
fn every_invalid_fixture_reports_its_code_at_a_location() {
    let names = bg_files("invalid");
    assert!(names.len() >= 40, "only {} invalid fixtures", names.len());
    for name in names {
        let rel = format!("invalid/{name}");
        let run = bgc(&fixtures_dir(), &["check", "--color", "never", &rel]);
        // The file name starts with the code it exercises: BG0302_domain_mismatch.bg.
        let code = &name[..6];
        assert!(
            run.stderr.contains(&format!("[{code}]")),
            "{rel}: expected diagnostic {code}\n{}",
            run.transcript()
        );
        // Errors fail the check; a file with only warnings passes it with the warnings printed.
        let expected = i32::from(run.stderr.contains("error["));
        assert_eq!(run.status, expected, "{rel}\n{}", run.transcript());
        assert!(
            run.stderr.contains(&format!("{rel}:")),
            "{rel}: no FILE:LINE:COL\n{}",
            run.transcript()
        );
        insta::assert_snapshot!(
            format!("check_invalid_{}", name.trim_end_matches(".bg")),
            run.transcript()
        );
    }
}

#[test]
fn every_valid_fixture_passes() {
    for name in bg_files("valid") {
        let rel = format!("valid/{name}");
        let run = bgc(&fixtures_dir(), &["check", "--color", "never", &rel]);
        assert_eq!(run.status, 0, "{rel}\n{}", run.transcript());
        insta::assert_snapshot!(
            format!("check_valid_{}", name.trim_end_matches(".bg")),
            run.transcript()
        );
    }
}

#[test]
fn back_support_model_checks_clean() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    let run = bgc(&models, &["check", "--color", "never", "back_support.bg"]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    // The paper's graph has two derivative-causality findings (J_g behind J_m on the motor junction, the trunk
    // inertia driven by the trunk-velocity source); the model acknowledges both with `allow`, so none is printed.
    assert_eq!(
        run.stderr.matches("warning[BG0510]").count(),
        0,
        "{}",
        run.transcript()
    );
    assert!(!run.stderr.contains("warning"), "{}", run.transcript());
    insta::assert_snapshot!(run.transcript());
}

#[test]
fn json_diagnostics_carry_code_and_line_and_column() {
    let run = bgc(
        &fixtures_dir(),
        &[
            "check",
            "--format",
            "json",
            "invalid/BG0201_unknown_name.bg",
        ],
    );
    assert_eq!(run.status, 1, "{}", run.transcript());
    let v: serde_json::Value = serde_json::from_str(&run.stdout)
        .unwrap_or_else(|e| panic!("not JSON: {e}\n{}", run.stdout));
    let first = &v[0];
    assert_eq!(first["code"], "BG0201");
    assert_eq!(first["severity"], "error");
    let label = &first["labels"][0];
    assert!(label["line"].as_u64().unwrap_or(0) >= 1);
    assert!(label["column"].as_u64().unwrap_or(0) >= 1);
    assert_eq!(label["file"], "invalid/BG0201_unknown_name.bg");
}

#[test]
fn usage_and_io_errors_exit_2() {
    let dir = fixtures_dir();
    assert_eq!(bgc(&dir, &["check"]).status, 2);
    assert_eq!(bgc(&dir, &["frobnicate"]).status, 2);
    let missing = bgc(&dir, &["check", "no/such/file.bg"]);
    assert_eq!(missing.status, 2);
    assert!(
        missing.stderr.contains("no/such/file.bg"),
        "{}",
        missing.transcript()
    );
}

/// A scratch directory of this test binary's own.
fn scratch(name: &str) -> PathBuf {
    let dir = crate::scratch::path(&format!("cli-{name}"));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    dir
}

/// Hostile inputs: each must give a clean exit 1 with a located diagnostic, never a crash or a hang.
#[test]
fn hostile_inputs_get_located_errors() {
    let dir = scratch("hostile");
    let valid = std::fs::read(fixtures_dir().join("../../../models/back_support.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated.bg", valid[..valid.len() / 2].to_vec()),
        (
            "binary.bg",
            (0..4096u32)
                .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
                .collect(),
        ),
        (
            "bad_utf8.bg",
            b"model m {\n  param k = 1 [N/m] \"\xff\xfe\";\n}\n".to_vec(),
        ),
        ("deep_parens.bg", {
            let mut s = String::from("model m { param k = ");
            s.push_str(&"(".repeat(10_000));
            s.push('1');
            s.push_str(&")".repeat(10_000));
            s.push_str(" [1]; }");
            s.into_bytes()
        }),
        ("megabyte_line.bg", {
            let mut s = String::from("model m { param k = 1");
            s.push_str(&" + 1".repeat(300_000));
            s.push_str(" [1] ; bond x -> ; }");
            s.into_bytes()
        }),
        ("nul_bytes.bg", b"model m {\0\0\0}".to_vec()),
    ];
    // Mutations of the valid model: a byte flipped every 97 bytes, a byte deleted every 53.
    let mut flipped = valid.clone();
    for i in (0..flipped.len()).step_by(97) {
        flipped[i] ^= 0x5a;
    }
    cases.push(("flipped.bg", flipped));
    let deleted: Vec<u8> = valid
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 53 != 7)
        .map(|(_, b)| *b)
        .collect();
    cases.push(("deleted.bg", deleted));
    for (name, bytes) in cases {
        std::fs::write(dir.join(name), &bytes).unwrap_or_else(|e| panic!("{e}"));
        let run = bgc(&dir, &["check", "--color", "never", name]);
        assert_eq!(run.status, 1, "{name}\n{}", run.transcript());
        assert!(
            run.stderr.contains(&format!("{name}:")),
            "{name}: no location\n{}",
            run.transcript()
        );
        assert!(
            !run.stderr.contains("panicked"),
            "{name}\n{}",
            run.transcript()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fmt_check_is_clean_on_canonical_files_and_fmt_is_idempotent() {
    let dir = scratch("fmt");
    for name in bg_files("valid") {
        let src = fixtures_dir().join("valid").join(&name);
        let dst = dir.join(&name);
        std::fs::copy(&src, &dst).unwrap_or_else(|e| panic!("{e}"));
        let first = bgc(&dir, &["fmt", &name]);
        assert_eq!(first.status, 0, "{name}\n{}", first.transcript());
        let once = std::fs::read_to_string(&dst).unwrap_or_default();
        let check = bgc(&dir, &["fmt", "--check", &name]);
        assert_eq!(check.status, 0, "{name} not stable\n{}", check.transcript());
        let second = bgc(&dir, &["fmt", &name]);
        assert_eq!(second.status, 0);
        let twice = std::fs::read_to_string(&dst).unwrap_or_default();
        assert_eq!(once, twice, "{name}: fmt is not idempotent");
        // Formatting never changes meaning: the formatted file still checks clean.
        let checked = bgc(&dir, &["check", "--color", "never", &name]);
        assert_eq!(checked.status, 0, "{name}\n{}", checked.transcript());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fmt_refuses_a_file_with_syntax_errors_and_leaves_it_alone() {
    let dir = scratch("fmt-bad");
    let name = "bad.bg";
    let text = "model m { param k = ; }\n";
    std::fs::write(dir.join(name), text).unwrap_or_else(|e| panic!("{e}"));
    let run = bgc(&dir, &["fmt", name]);
    assert_eq!(run.status, 1, "{}", run.transcript());
    assert_eq!(
        std::fs::read_to_string(dir.join(name)).unwrap_or_default(),
        text
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bgc rust FILE` prints exactly what the build-script API writes for the same file.
/// `bgc rust` prints the model's warnings and notes on standard error, as `bgc fmu` and the build script give them
/// (the diode's algebraic loop, BG0520), and the module alone on standard output.
#[test]
fn rust_command_prints_the_warnings_on_standard_error() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus/diode_rc.bg");
    let run = bgc(&fixtures_dir(), &["rust", &model.display().to_string()]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    assert!(
        run.stderr.contains("warning[BG0520]"),
        "{}",
        run.transcript()
    );
    assert!(!run.stdout.contains("BG0520"), "{}", run.transcript());
}

#[test]
fn rust_command_prints_what_the_build_script_generates() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/back_support.bg");
    let model = model.canonicalize().unwrap_or(model);
    let name = model.display().to_string();
    let run = bgc(&fixtures_dir(), &["rust", &name]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    let out = scratch("rust");
    let generated = bgc::build::Config::new()
        .out_dir(&out)
        .cargo_output(false)
        .compile(&[&model])
        .unwrap_or_else(|e| panic!("{e}"));
    let written = std::fs::read_to_string(&generated[0].output).unwrap_or_default();
    assert_eq!(run.stdout, written);
    assert!(
        written.contains("pub fn rhs_into("),
        "no rhs in the generated module"
    );
    let bad = bgc(
        &fixtures_dir(),
        &["rust", "invalid/BG0302_domain_mismatch.bg"],
    );
    assert_eq!(bad.status, 1, "{}", bad.transcript());
    assert!(
        bad.stderr
            .contains("invalid/BG0302_domain_mismatch.bg:8:18"),
        "{}",
        bad.transcript()
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `bgc rust --no-runtime FILE` prints what `Config::runtime(false)` writes: no `bgc_runtime` in it.
#[test]
fn rust_command_without_the_runtime() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/rehab_leg.bg");
    let model = model.canonicalize().unwrap_or(model);
    let name = model.display().to_string();
    let run = bgc(&fixtures_dir(), &["rust", "--no-runtime", &name]);
    assert_eq!(run.status, 0, "{}", run.transcript());
    let out = scratch("rust-no-runtime");
    let generated = bgc::build::Config::new()
        .out_dir(&out)
        .cargo_output(false)
        .runtime(false)
        .compile(&[&model])
        .unwrap_or_else(|e| panic!("{e}"));
    let written = std::fs::read_to_string(&generated[0].output).unwrap_or_default();
    assert_eq!(run.stdout, written);
    assert!(!written.contains("bgc_runtime"), "{written}");
    assert!(written.contains("pub enum ParamError {"));
    let with = bgc(&fixtures_dir(), &["rust", &name]);
    assert!(
        with.stdout
            .contains("impl bgc_runtime::model::Parametric for Model {")
    );
    let _ = std::fs::remove_dir_all(&out);
}
