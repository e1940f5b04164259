//! Generates the model modules from the `.bg` files: the exoskeleton models into `$OUT_DIR`, and the compiler's
//! test corpus into `$OUT_DIR/corpus` (checked by this crate's tests against the compiler's own evaluation).

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

fn main() -> Result<(), bgc::build::Error> {
    bgc::build::compile(MODELS)?;
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").ok_or(bgc::build::Error::NoOutDir)?);
    let corpus: Vec<String> = CORPUS
        .iter()
        .map(|name| format!("../bgc/tests/corpus/{name}.bg"))
        .collect();
    bgc::build::Config::new()
        .out_dir(out_dir.join("corpus"))
        .compile(&corpus)?;
    Ok(())
}
