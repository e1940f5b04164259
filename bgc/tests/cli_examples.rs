//! The example commands of docs/cli.md run as written, from the repository's root, and succeed.
//!
//! A command is a line `$ bgc …` of a ```` ```console ```` block or an indented line `    bgc …`. A trailing
//! `# comment` and a `> FILE` redirection are dropped (the output is read, not written); `-o FILE` writes into a
//! scratch directory. Commands that read a file the repository does not hold (a recorded `--data` CSV, or `…`
//! standing for the rest of a command) cannot run here. `bgc fmu` is run by `fmu_cli`, which builds and checks the
//! same FMUs; running the documented lines again would only compile them twice.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The documented commands: the line number and the arguments after `bgc`.
fn commands() -> Vec<(usize, Vec<String>)> {
    let path = root().join("docs/cli.md");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let Some(rest) = line
            .strip_prefix("$ bgc ")
            .or_else(|| line.strip_prefix("    bgc "))
        else {
            continue;
        };
        let rest = rest.split(" # ").next().unwrap_or(rest);
        let rest = rest.split(" > ").next().unwrap_or(rest);
        out.push((i + 1, words(rest)));
    }
    out
}

/// The words of a command line as a POSIX shell splits them, for the quoting the docs use (single quotes).
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word: Option<String> = None;
    let mut quoted = false;
    for ch in line.chars() {
        match ch {
            '\'' => {
                quoted = !quoted;
                word.get_or_insert_with(String::new);
            }
            c if c.is_whitespace() && !quoted => out.extend(word.take()),
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    out.extend(word);
    out
}

/// Why a documented command cannot run here, if it cannot.
fn cannot_run(args: &[String]) -> Option<&'static str> {
    if args.first().map(String::as_str) == Some("fmu") {
        return Some("FMUs are built and checked by fmu_cli");
    }
    if args.iter().any(|a| a.contains('…') || a == "\\") {
        return Some("an abridged command");
    }
    let data = args
        .windows(2)
        .find(|w| w[0] == "--data")
        .map(|w| root().join(&w[1]));
    if data.is_some_and(|d| !d.exists()) {
        return Some("a recorded data file the repository does not hold");
    }
    None
}

#[test]
fn documented_commands_succeed() {
    let scratch = crate::scratch::path("cli-examples");
    std::fs::create_dir_all(&scratch).unwrap_or_else(|e| panic!("{}: {e}", scratch.display()));
    let all = commands();
    let mut ran = 0;
    let mut failed = Vec::new();
    for (line, mut args) in all.iter().cloned() {
        if cannot_run(&args).is_some() {
            continue;
        }
        if let Some(k) = args.iter().position(|a| a == "-o")
            && let Some(out) = args.get_mut(k + 1)
        {
            *out = scratch.join(&*out).display().to_string();
        }
        let out = Command::new(env!("CARGO_BIN_EXE_bgc"))
            .args(&args)
            .current_dir(root())
            .output()
            .unwrap_or_else(|e| panic!("cannot start bgc: {e}"));
        ran += 1;
        if !out.status.success() {
            failed.push(format!(
                "docs/cli.md:{line}: bgc {}\n{}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    assert!(
        ran >= 10,
        "only {ran} of {} documented commands ran",
        all.len()
    );
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn shell_words_are_split_as_a_shell_splits_them() {
    assert_eq!(
        words("simulate a.bg --input 'F=10*step(0.1)'  --x0 q=1"),
        [
            "simulate",
            "a.bg",
            "--input",
            "F=10*step(0.1)",
            "--x0",
            "q=1"
        ]
    );
    assert_eq!(words("x '' 'a b'"), ["x", "", "a b"]);
}
