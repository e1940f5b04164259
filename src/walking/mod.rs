//! The lower-limb walking exoskeleton of Sado et al. (2018), end to end: the coupled human–exoskeleton leg
//! (Eqs. 1–5, Tables 1 and 8), the dual UKF that generates the wearer's trajectory and learns the link
//! masses (Eqs. 6–27), the impedance controller (Eqs. 28–29) and the gait supervisor (Eq. 30, Tables 2–3),
//! run against a synthetic wearer.
//!
//! - [`anthropometry`]: segment parameters and joint friction;
//! - [`dynamics`]: the hand-derived Euler–Lagrange model `M(q)`, `C(q, q̇)`, `G(q)`: the estimator's and the
//!   controller's model, and the independent reference of the equations bgc derives from `models/walking_leg.bg`;
//! - [`generated`]: the simulated leg on the model generated from `models/walking_leg.bg`;
//! - [`plant`]: the leg as a runtime `ContinuousModel`, alone and worn by the wearer;
//! - [`wearer`]: the synthetic wearer (trajectories, insoles, torso load, human torque);
//! - [`estimator`]: the dual UKF;
//! - [`reference`](mod@reference): the controller's reference at the control rate from the filter's predictions;
//! - [`scenario`]: the closed loop, its settings and records, and the figures of Tables 7 and 9.

pub mod anthropometry;
mod config;
pub mod dynamics;
pub mod estimator;
pub mod generated;
pub mod plant;
mod records;
pub mod reference;
pub mod scenario;
pub mod wearer;
