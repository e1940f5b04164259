//! The measurement system of a rehabilitation exoskeleton (Yang et al., Sensors 2018, 18, 2588): IMU and vision
//! angle measurements of a pendulum test rig and of an exoskeleton's thigh and calf, each IMU's angle from the
//! Kalman filter of Eqs. 5–6, and the minimum-variance fusion of Eqs. 22–27 with weights measured on the rig.
//!
//! - [`generated`]: the plants, the models generated from `models/pendulum_rig.bg` and `models/rehab_leg.bg`, and
//!   where the segments' angles and rates sit in their vectors.
//! - [`plant`]: hand-derived implementations of the same two models, the independent reference the generated
//!   ones are tested against.
//! - [`truth`]: the true motion of the instrumented segments from a simulation of the generated models.
//! - [`sensors`]: the synthetic IMU and camera.
//! - [`pipeline`]: the estimation chain and the error measure E (Eq. 28).
//! - [`experiment`]: the rig run and the exoskeleton test with their sensor set-ups.

pub mod error;
pub mod experiment;
pub mod generated;
pub mod pipeline;
pub mod plant;
pub mod sensors;
pub mod truth;

pub use error::RehabError;
