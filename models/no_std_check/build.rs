//! Generates models without the runtime's trait implementations (`Config::runtime(false)`): the back-support
//! exoskeleton (linear), the pendulum rig, the rehabilitation leg, the walking leg (an I-field: the mass-matrix
//! solve in generated code) and the corpus pendulum (sines and cosines of states).

fn main() -> Result<(), bgc::build::Error> {
    // The corpus pendulum's derivative causality is intended (its tests check the warning): not printed here.
    bgc::build::Config::new()
        .runtime(false)
        .warnings(false)
        .compile(&[
            "../back_support.bg",
            "../pendulum_rig.bg",
            "../rehab_leg.bg",
            "../walking_leg.bg",
            "../../bgc/tests/corpus/pendulum.bg",
        ])?;
    Ok(())
}
