//! The generated modules are what `rustfmt --edition 2024` makes of them (`rustfmt --check` passes, run as CI
//! runs `cargo fmt`, with the toolchain's `rustfmt`), and no line is longer than 100 columns: for every model of
//! `models/` and of the compiler's corpus that compiles, and a file with two models and long names, with and
//! without the runtime's trait implementations.

use crate::codegen_support;

use codegen_support::{generated_modules, scratch};
use std::process::Command;

/// Runs `rustfmt --edition 2024 --check` on each module; returns the failures with rustfmt's diff.
fn rustfmt_failures(modules: &[(String, String)], dir: &std::path::Path) -> Vec<String> {
    let mut failures = Vec::new();
    for (k, (name, code)) in modules.iter().enumerate() {
        let path = dir.join(format!("module_{k}.rs"));
        std::fs::write(&path, code).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let out = Command::new("rustfmt")
            .args(["--edition", "2024", "--check"])
            .arg(&path)
            .output()
            .unwrap_or_else(|e| {
                panic!("cannot run rustfmt (install it with `rustup component add rustfmt`): {e}")
            });
        if !out.status.success() {
            failures.push(format!(
                "{name}: rustfmt --check fails:\n{}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    failures
}

fn check(runtime: bool) {
    let modules = generated_modules(runtime);
    let dir = scratch(if runtime {
        "fmt-runtime"
    } else {
        "fmt-no-runtime"
    });
    let mut failures = rustfmt_failures(&modules, &dir);
    for (name, code) in &modules {
        for (n, line) in code.lines().enumerate() {
            let columns = line.chars().count();
            if columns > 100 {
                failures.push(format!("{name}:{}: {columns} columns: {line}", n + 1));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn modules_with_the_runtime_are_rustfmt_clean_and_fit_in_100_columns() {
    check(true);
}

#[test]
fn modules_without_the_runtime_are_rustfmt_clean_and_fit_in_100_columns() {
    check(false);
}

/// The check can fail: a module that rustfmt would change is reported with its diff.
#[test]
fn a_module_rustfmt_would_change_is_reported() {
    let dir = scratch("fmt-negative");
    let bad = vec![(
        "bad.bg".to_string(),
        "pub fn f(x: f64) -> f64 { x*2.0 }\n".to_string(),
    )];
    let failures = rustfmt_failures(&bad, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(failures.len(), 1);
    assert!(failures[0].contains("x * 2.0"), "{}", failures[0]);
}
