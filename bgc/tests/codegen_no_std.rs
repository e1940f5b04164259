//! Generated modules without the runtime's impls need nothing from `std`: each one compiles, with `-D warnings`,
//! as a `#![no_std]` library whose only dependencies are two `#![no_std]` stand-ins with the items it uses:
//! `nalgebra` (`SMatrix`, `SVector`, `zeros`, `fill`, indexing) and `libm` (the elementary functions). With no
//! crate of the graph linking `std`, none of its `f64` methods (`sin`, `powi`, `sqrt`, ...) exists, so a call to
//! one fails to compile (the last test shows it). The real `nalgebra` without default features and `libm` are
//! checked by the `bgc-no-std-check` crate of the workspace (`cargo build -p bgc-no-std-check`).

mod codegen_support;

use codegen_support::{generated_modules, scratch};
use std::path::Path;
use std::process::Command;

/// The part of `nalgebra`'s API generated code uses, without `std`.
const NALGEBRA: &str = r#"
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
const LIBM: &str = r#"
#![no_std]
macro_rules! unary {
    ($($name:ident),*) => { $(pub fn $name(x: f64) -> f64 { x })* };
}
unary!(sin, cos, tan, asin, acos, atan, exp, log, log10, sqrt, fabs, tanh, sinh, cosh);
pub fn atan2(y: f64, x: f64) -> f64 { y - x }
pub fn pow(x: f64, y: f64) -> f64 { x * y }
"#;

fn rustc(dir: &Path, args: &[&str]) -> std::process::Output {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    Command::new(&rustc)
        .current_dir(dir)
        .args(["--edition", "2024", "-D", "warnings"])
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {rustc}: {e}"))
}

/// Builds the two stand-ins in `dir`.
fn stand_ins(dir: &Path) {
    for (name, source) in [("nalgebra", NALGEBRA), ("libm", LIBM)] {
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

/// Compiles `module` as a `#![no_std]` library against the stand-ins; rustc's errors on failure.
fn compile_no_std(dir: &Path, file: &str, module: &str) -> Result<(), String> {
    let root = format!(
        "#![no_std]\n//! One generated module.\n\npub mod model {{\n    include!(\"{file}.module\");\n}}\n"
    );
    std::fs::write(dir.join(format!("{file}.module")), module).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(format!("{file}.rs")), root).map_err(|e| e.to_string())?;
    let out = rustc(
        dir,
        &[
            "--crate-type",
            "rlib",
            "--crate-name",
            file,
            "--extern",
            "nalgebra=libnalgebra.rlib",
            "--extern",
            "libm=liblibm.rlib",
            "-L",
            ".",
            &format!("{file}.rs"),
        ],
    );
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

#[test]
fn modules_without_the_runtime_compile_without_std() {
    let dir = scratch("no-std");
    stand_ins(&dir);
    let modules = generated_modules(false);
    let mut failures = Vec::new();
    for (k, (name, code)) in modules.iter().enumerate() {
        if let Err(errors) = compile_no_std(&dir, &format!("module_{k}"), code) {
            failures.push(format!("{name}:\n{errors}"));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Transcendental functions are among them: the pendulums and the leg call sin and cos.
    assert!(
        modules
            .iter()
            .any(|(name, code)| name.ends_with("pendulum.bg") && code.contains("libm::sin("))
    );
}

/// The check can fail: `std`'s `f64::sin` does not exist in the stand-ins' graph.
#[test]
fn a_std_method_does_not_compile_there() {
    let dir = scratch("no-std-negative");
    stand_ins(&dir);
    let errors = compile_no_std(
        &dir,
        "uses_std",
        "pub fn f(x: nalgebra::SVector<f64, 1>) -> f64 {\n    x[0].sin() + libm::cos(x[0])\n}\n",
    )
    .err()
    .unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        errors.contains("no method named `sin` found for type `f64`"),
        "{errors}"
    );
}
