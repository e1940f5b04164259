//! Controllers of the exoskeleton papers.
//!
//! - [`impedance`]: the impedance-based computed-torque law of Sado et al. (2018), Eqs. 28–29, for an
//!   `N`-joint manipulator with user-supplied `M(q)`, `C(q, q̇) q̇`, `G(q)`.
//! - [`gait`]: the 4-state gait-phase supervisor of the same paper (Eq. 30, Tables 2–3), driven by insole
//!   ground-reaction forces.

pub mod error;
pub mod gait;
pub mod impedance;

pub use error::ControlError;
pub use gait::{
    FootEvent, GaitState, GaitSupervisor, GaitThresholds, GrfFault, GrfSample, GrfSensor, Leg,
    LegMode, SupervisorStep, Transition, classify, ground_reaction_index,
};
pub use impedance::{
    DynamicsFn, ImpedanceCommand, ImpedanceController, ImpedanceGains, JointReference, JointState,
    ManipulatorDynamics,
};
