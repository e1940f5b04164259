//! `bgc fmu`'s errors: they come before any build, name the place and the cause, and exit as the other commands
//! do (1 for errors in the file, 2 for usage).

use crate::fmu_support::{scratch, workspace};
use std::process::{Command, Output};

fn bgc_fmu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bgc"))
        .current_dir(workspace())
        .arg("fmu")
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run bgc: {e}"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn an_error_in_the_file_is_a_diagnostic_and_no_fmu_is_written() {
    let dir = scratch().join("cli");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let file = dir.join("broken.bg");
    std::fs::write(
        &file,
        "model m {\n    domain rotational;\n    I a = J;\n}\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = dir.join("broken.fmu");
    let _ = std::fs::remove_file(&out);
    let o = bgc_fmu(&[
        &file.display().to_string(),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("broken.bg:3:"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn an_unknown_model_or_version_is_a_usage_error() {
    let out = scratch().join("cli-unused.fmu");
    let o = bgc_fmu(&[
        "models/back_support.bg",
        "--model",
        "nope",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("has no model `nope`; it declares back_support"),
        "{}",
        stderr(&o)
    );
    let o = bgc_fmu(&[
        "models/back_support.bg",
        "--fmi",
        "4",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--fmi"), "{}", stderr(&o));
    let o = bgc_fmu(&["models/missing.bg", "-o", &out.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("models/missing.bg"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn the_command_list_describes_fmu_and_fmt_each_by_its_own_text() {
    let o = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .arg("--help")
        .output()
        .unwrap_or_else(|e| panic!("cannot run bgc: {e}"));
    let help = String::from_utf8_lossy(&o.stdout).into_owned();
    let line = |cmd: &str| {
        help.lines()
            .find(|l| l.trim_start().starts_with(&format!("{cmd} ")))
            .unwrap_or_else(|| panic!("no `{cmd}` in:\n{help}"))
            .to_string()
    };
    assert!(line("fmu").contains("Functional Mock-up Unit"), "{help}");
    assert!(!line("fmu").contains("canonical layout"), "{help}");
    assert!(line("fmt").contains("canonical layout"), "{help}");
}
