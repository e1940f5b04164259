//! Helpers of the CLI tests: running `bgc` and reading its JSON and CSV output.
// Each test crate uses a part of these.
#![allow(dead_code)]

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

pub fn repo(path: &str) -> String {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    root.join("..").join(path).display().to_string()
}

pub fn corpus(name: &str) -> String {
    repo(&format!("bgc/tests/corpus/{name}"))
}

/// Runs `bgc` and returns the exit code, standard output and standard error.
pub fn bgc(args: &[&str]) -> (i32, String, String) {
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

/// Runs `bgc` in `dir` with `input` on its standard input; the exit code, standard output and standard error.
pub fn bgc_stdin(args: &[&str], input: &str, dir: &std::path::Path) -> (i32, String, String) {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_bgc"))
        .args(args)
        .arg("--color=never")
        .current_dir(dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("bgc runs");
    if let Some(mut stdin) = child.stdin.take() {
        // A command refused before it reads its input closes the pipe: that is its answer, not a failure here.
        match stdin.write_all(input.as_bytes()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                panic!("bgc reads its input: {e}")
            }
            _ => {}
        }
    }
    let out = child.wait_with_output().expect("bgc runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

pub fn ok_json(args: &[&str]) -> Value {
    let (code, out, err) = bgc(args);
    assert_eq!(code, 0, "stderr: {err}");
    serde_json::from_str(&out).expect("valid JSON")
}

pub fn matrix(v: &Value, key: &str) -> Vec<Vec<f64>> {
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

pub fn names(v: &Value, key: &str) -> Vec<String> {
    v[key]
        .as_array()
        .expect("names")
        .iter()
        .map(|x| x.as_str().expect("name").to_string())
        .collect()
}

pub fn assert_close(got: &[Vec<f64>], want: &[Vec<f64>], rel: f64) {
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
pub struct Csv {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Csv {
    /// Parses the CSV; the header's names without their units (`q_spring [m]` is `q_spring`, see [`Csv::units`]).
    pub fn parse(text: &str) -> Csv {
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(|h| h.split(" [").next().unwrap_or(h).to_string())
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().expect("number")).collect())
            .collect();
        Csv { header, rows }
    }

    pub fn col(&self, name: &str) -> Vec<f64> {
        let i = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"));
        self.rows.iter().map(|r| r[i]).collect()
    }
}

/// The units of the header's columns, `t [s]` giving `s`.
pub fn units(text: &str) -> Vec<String> {
    let header = text.lines().next().unwrap_or("");
    header
        .split(',')
        .map(|h| {
            h.split_once(" [")
                .map(|(_, u)| u.trim_end_matches(']').to_string())
                .unwrap_or_default()
        })
        .collect()
}

pub fn simulate(args: &[&str]) -> Csv {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    let (code, out, err) = bgc(&all);
    assert_eq!(code, 0, "stderr: {err}");
    Csv::parse(&out)
}

/// Writes a model to a file of the tests' scratch directory and returns its path.
pub fn temp_model(name: &str, text: &str) -> String {
    let path = crate::scratch::path(&format!("{name}.bg"));
    std::fs::write(&path, text).expect("temporary model written");
    path.display().to_string()
}
