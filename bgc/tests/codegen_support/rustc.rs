//! Compiling generated modules with `rustc` alone, as `#![no_std]` libraries against minimal `no_std`
//! stand-ins of `nalgebra` (a fixed-size matrix with `zeros`, `fill` and indexing: all the generated code uses)
//! and `libm` (the function names only). Used by the no-std test and by the compile-time benchmark.

use std::path::Path;
use std::process::Command;

pub const NALGEBRA: &str = r#"
#![no_std]
use core::ops::{Index, IndexMut};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SMatrix<T, const R: usize, const C: usize> {
    data: [[T; R]; C],
}

pub type SVector<T, const R: usize> = SMatrix<T, R, 1>;

impl<const R: usize, const C: usize> SMatrix<f64, R, C> {
    pub fn zeros() -> Self {
        SMatrix { data: [[0.0; R]; C] }
    }
}

impl<T: Copy, const R: usize, const C: usize> SMatrix<T, R, C> {
    pub fn fill(&mut self, value: T) {
        for column in self.data.iter_mut() {
            for entry in column.iter_mut() {
                *entry = value;
            }
        }
    }
}

impl<T, const R: usize, const C: usize> Index<usize> for SMatrix<T, R, C> {
    type Output = T;
    fn index(&self, i: usize) -> &T {
        &self.data[i / R][i % R]
    }
}

impl<T, const R: usize, const C: usize> IndexMut<usize> for SMatrix<T, R, C> {
    fn index_mut(&mut self, i: usize) -> &mut T {
        &mut self.data[i / R][i % R]
    }
}

impl<T, const R: usize, const C: usize> Index<(usize, usize)> for SMatrix<T, R, C> {
    type Output = T;
    fn index(&self, (r, c): (usize, usize)) -> &T {
        &self.data[c][r]
    }
}

impl<T, const R: usize, const C: usize> IndexMut<(usize, usize)> for SMatrix<T, R, C> {
    fn index_mut(&mut self, (r, c): (usize, usize)) -> &mut T {
        &mut self.data[c][r]
    }
}
"#;

/// `libm`'s signatures (the values do not matter: the test only compiles).
pub const LIBM: &str = r#"
#![no_std]
macro_rules! unary {
    ($($name:ident),*) => { $(pub fn $name(x: f64) -> f64 { x })* };
}
unary!(sin, cos, tan, asin, acos, atan, exp, log, log10, sqrt, fabs, tanh, sinh, cosh);
pub fn atan2(y: f64, x: f64) -> f64 { y - x }
pub fn pow(x: f64, y: f64) -> f64 { x * y }
"#;

pub fn rustc(dir: &Path, args: &[&str]) -> std::process::Output {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    Command::new(&rustc)
        .current_dir(dir)
        .args(["--edition", "2024", "-D", "warnings"])
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {rustc}: {e}"))
}

/// Builds the two stand-ins in `dir`.
pub fn stand_ins(dir: &Path) {
    stand_ins_with(dir, LIBM);
}

/// Builds the nalgebra stand-in and `libm_source` as `libm` in `dir` (the real functions where a test runs
/// the code and checks its numbers).
pub fn stand_ins_with(dir: &Path, libm_source: &str) {
    for (name, source) in [("nalgebra", NALGEBRA), ("libm", libm_source)] {
        std::fs::write(dir.join(format!("{name}.rs")), source).unwrap_or_else(|e| panic!("{e}"));
        let out = rustc(
            dir,
            &[
                "--crate-type",
                "rlib",
                "--crate-name",
                name,
                &format!("{name}.rs"),
            ],
        );
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Compiles `root` in `dir` as a crate of `crate_type` named `crate_name` against the stand-ins, with `extra`
/// arguments; rustc's errors on failure.
pub fn compile_against_stand_ins(
    dir: &Path,
    crate_type: &str,
    crate_name: &str,
    root: &str,
    extra: &[&str],
) -> Result<(), String> {
    let args = [
        "--crate-type",
        crate_type,
        "--crate-name",
        crate_name,
        "--extern",
        "nalgebra=libnalgebra.rlib",
        "--extern",
        "libm=liblibm.rlib",
        "-L",
        ".",
        root,
    ];
    let out = rustc(
        dir,
        &args
            .into_iter()
            .chain(extra.iter().copied())
            .collect::<Vec<_>>(),
    );
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

/// Builds the program `main` (which includes `NAME.module`, here `code`) against the stand-ins with the real
/// `libm_source`, runs it and returns what it printed.
pub fn build_and_run(dir: &Path, name: &str, code: &str, main: &str, libm_source: &str) -> String {
    stand_ins_with(dir, libm_source);
    std::fs::write(dir.join(format!("{name}.module")), code).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(dir.join("main.rs"), main).unwrap_or_else(|e| panic!("{e}"));
    if let Err(e) = compile_against_stand_ins(dir, "bin", name, "main.rs", &["-o", name]) {
        panic!("{e}");
    }
    let run = Command::new(dir.join(name))
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    String::from_utf8_lossy(&run.stdout).into_owned()
}

/// Compiles `module` as a `#![no_std]` library against the stand-ins; rustc's errors on failure.
pub fn compile_no_std(dir: &Path, file: &str, module: &str) -> Result<(), String> {
    compile_no_std_with(dir, file, module, &[])
}

/// [`compile_no_std`] with more `rustc` arguments (`-O`).
pub fn compile_no_std_with(
    dir: &Path,
    file: &str,
    module: &str,
    extra: &[&str],
) -> Result<(), String> {
    let root = format!(
        "#![no_std]\n//! One generated module.\n\npub mod model {{\n    include!(\"{file}.module\");\n}}\n"
    );
    std::fs::write(dir.join(format!("{file}.module")), module).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(format!("{file}.rs")), root).map_err(|e| e.to_string())?;
    compile_against_stand_ins(dir, "rlib", file, &format!("{file}.rs"), extra)
}

/// Runs `rustdoc` on `module` as a `#![no_std]` library against the stand-ins (built by [`stand_ins`]): once to
/// document it with `-D warnings`, once with `--test` for its doctests. rustdoc's output of each on success, its
/// errors on failure.
pub fn document_no_std(dir: &Path, file: &str, module: &str) -> Result<(String, String), String> {
    let root = format!(
        "#![no_std]\n//! One generated module.\n\npub mod model {{\n    include!(\"{file}.module\");\n}}\n"
    );
    std::fs::write(dir.join(format!("{file}.module")), module).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(format!("{file}.rs")), root).map_err(|e| e.to_string())?;
    let rustdoc = std::env::var("RUSTDOC").unwrap_or_else(|_| "rustdoc".into());
    let run = |extra: &[&str]| {
        let out = Command::new(&rustdoc)
            .current_dir(dir)
            .args(["--edition", "2024", "-D", "warnings", "--crate-name", file])
            .args([
                "--extern",
                "nalgebra=libnalgebra.rlib",
                "--extern",
                "libm=liblibm.rlib",
            ])
            .args(["-L", ".", "-o", "doc"])
            .args(extra)
            .arg(format!("{file}.rs"))
            .output()
            .map_err(|e| format!("cannot run {rustdoc}: {e}"))?;
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if out.status.success() {
            Ok(text)
        } else {
            Err(text)
        }
    };
    Ok((run(&[])?, run(&["--test"])?))
}
