//! The exoskeleton models, generated at build time from the `.bg` files of this crate by `bgc::build` (see
//! `build.rs`).
//!
//! Each module is the generated code of one file (see `bgc::codegen::rust` for what it contains): `Params` with
//! the file's defaults and `validate`, `rhs`/`outputs` and their Jacobians on fixed-size `nalgebra` types, the
//! linear state space where the model is linear, energy and power, and `Model`, which implements
//! `bgc_runtime::model::ContinuousModel` and `Parametric` so it plugs into the estimators, controllers and the
//! simulator of `bgc_runtime`.
//!
//! - [`back_support`]: the industrial back-support exoskeleton of Shojaei Barjuei et al. (Designs 2020): motor,
//!   harmonic drive, torque sensor and trunk; 10 states (6 energy states and 4 angles), inputs motor torque and
//!   trunk velocity; `state_space_declared` is the paper's Eq. (3).
//! - [`pendulum_rig`]: the stepper-driven pendulum test rig of Yang et al. (Sensors 2018).
//! - [`rehab_leg`]: the rehabilitation leg of the same paper.
//! - [`walking_leg`]: the three-link leg of the lower-limb exoskeleton of Sado et al. (2018), an I-field with
//!   `M(q)` whose rates are solved from the mass-matrix form; states `[q, q̇]`, free link masses.

pub mod back_support {
    include!(concat!(env!("OUT_DIR"), "/back_support.rs"));
}

pub mod pendulum_rig {
    include!(concat!(env!("OUT_DIR"), "/pendulum_rig.rs"));
}

pub mod rehab_leg {
    include!(concat!(env!("OUT_DIR"), "/rehab_leg.rs"));
}

pub mod walking_leg {
    include!(concat!(env!("OUT_DIR"), "/walking_leg.rs"));
}

/// The compiler's test corpus, for this crate's tests (feature `corpus`).
#[cfg(feature = "corpus")]
#[doc(hidden)]
pub mod corpus;
