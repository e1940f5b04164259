//! Generates the model modules from the `.bg` files: the exoskeleton models into `$OUT_DIR`, and, with the
//! feature `corpus` (this crate's tests turn it on), the compiler's test corpus and this crate's test models into
//! `$OUT_DIR/corpus`, checked by the tests against the compiler's own evaluation and against hand derivations. A
//! normal build leaves the test models (and their intended warnings) out.

use std::path::PathBuf;

/// The models of this crate, each with a module in `src/lib.rs`.
const MODELS: &[&str] = &[
    "back_support.bg",
    "pendulum_rig.bg",
    "rehab_leg.bg",
    "walking_leg.bg",
];

/// The compiler's corpus (`bgc/tests/corpus`), each with a module in `src/corpus.rs`.
const CORPUS: &[&str] = &[
    "dc_motor_load",
    "diode_rc",
    "gear_train",
    "hydraulic_cylinder",
    "msd_chain",
    "oscillator",
    "parallel_rlc",
    "pendulum",
    "quarter_car",
    "resistive_network",
    "series_rlc",
    "two_tank",
];

/// Test models of this crate (`tests/models`), generated with the corpus.
const TEST_MODELS: &[&str] = &["chained_loops", "ladder_closed", "ladder_loops"];

fn main() -> Result<(), bgc::build::Error> {
    bgc::build::compile(MODELS)?;
    if std::env::var_os("CARGO_FEATURE_CORPUS").is_none() {
        return Ok(());
    }
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").ok_or(bgc::build::Error::NoOutDir)?);
    let corpus: Vec<String> = CORPUS
        .iter()
        .map(|name| format!("../bgc/tests/corpus/{name}.bg"))
        .chain(
            TEST_MODELS
                .iter()
                .map(|name| format!("tests/models/{name}.bg")),
        )
        .collect();
    bgc::build::Config::new()
        .out_dir(out_dir.join("corpus"))
        .warnings(false)
        .compile(&corpus)?;
    Ok(())
}
