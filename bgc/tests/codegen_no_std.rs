//! Generated modules without the runtime's impls need nothing from `std`: each one compiles, with `-D warnings`,
//! as a `#![no_std]` library whose only dependencies are two `#![no_std]` stand-ins with the items it uses:
//! `nalgebra` (`SMatrix`, `SVector`, `zeros`, `fill`, indexing) and `libm` (the elementary functions). With no
//! crate of the graph linking `std`, none of its `f64` methods (`sin`, `powi`, `sqrt`, ...) exists, so a call to
//! one fails to compile (the last test shows it). The real `nalgebra` without default features and `libm` are
//! checked by the `bgc-no-std-check` crate of the workspace (`cargo build -p bgc-no-std-check`).

use crate::codegen_support;

use codegen_support::rustc::{compile_no_std, stand_ins};
use codegen_support::{generated_modules, scratch};

/// The part of `nalgebra`'s API generated code uses, without `std`.
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
