//! State and parameter estimation on fixed-size vectors and matrices. The filters and the observer keep their
//! `NX × NX` (and sigma-point) matrices and the work space of a step on the heap, allocated when they are built,
//! so that a filter of any size runs on any thread and a step allocates nothing.
//!
//! - [`kalman`]: the discrete linear Kalman filter (time-varying and fixed/steady-state gain, Joseph form),
//!   gain conversions and a steady-state gain by Riccati iteration;
//! - [`observer`]: the continuous-time observer `x̂' = A x̂ + B u + L (y − C x̂ − D u)` as a right-hand side;
//! - [`angle`]: the two-state angle/gyro-bias filter of paper 001 (Eqs. 2, 5, 6);
//! - [`fusion`]: minimum-variance weighted fusion of paper 001 (Eqs. 22–28);
//! - [`sigma`]: Merwe scaled sigma points and weights (paper 000, Eqs. 13, 20);
//! - [`ukf`], [`ukf_augmented`], [`srukf`]: the UKF with additive noise, with non-additive (augmented) noise,
//!   and in square-root form (paper 000, Eqs. 6–22);
//! - `unscented` (private): the input checks, sigma-point evaluation, predicted and innovation moments and Kalman
//!   correction those filters share;
//! - [`dual_ukf`]: joint state and parameter estimation with RLS forgetting (paper 000, Eqs. 23–27);
//! - [`health`]: filter health statistics of paper 000, Table 7;
//! - [`fault`]: the error and outcome types and the fault contract all filters share.
//!
//! Step functions (predict, update, step) of every filter allocate nothing and never panic; see [`fault`] for
//! what happens to bad data.

pub mod angle;
mod dense;
pub mod dual_ukf;
pub mod fault;
pub mod fusion;
pub mod health;
pub mod kalman;
pub mod observer;
pub mod sigma;
pub mod srukf;
pub mod ukf;
pub mod ukf_augmented;
mod unscented;

pub use fault::{CovarianceRepair, EstimationError, FaultPolicy, RejectReason, UpdateOutcome};
pub use kalman::{GainMode, KalmanFilter, LinearDiscreteModel, SteadyStateGain};
pub use sigma::SigmaPoints;
pub use ukf::UnscentedKalmanFilter;
