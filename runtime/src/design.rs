//! Controller and estimator design on linear models: LQR (continuous and discrete, with integral action) and
//! steady-state Kalman gains.
//!
//! Conventions: state feedback is `u = −K x`; gains come from the stabilising Riccati solutions of
//! [`crate::linalg`], so every function here inherits its checks (shapes, finiteness, symmetry, definiteness,
//! stabilisability, detectability, residual and closed-loop stability) and its errors.
//!
//! - [`lqr`], [`lqr_with_cross`], [`dlqr`], [`dlqr_with_cross`]: optimal state feedback;
//! - [`lqi`]: LQR with single or double integral action on chosen outputs (sign conventions in [`lqi`]'s
//!   documentation);
//! - [`lqe`], [`dlqe`]: steady-state Kalman gains (continuous; discrete predictor and innovation gains).

mod kalman;
mod lqi;
mod lqr;
mod ltr;

pub use kalman::{DiscreteKalman, Kalman, dlqe, lqe};
pub use lqi::{IntegralAction, Lqi, lqi};
pub use lqr::{dlqr, dlqr_with_cross, lqr, lqr_with_cross};
pub use ltr::{
    LtrError, ObserverNoise, RecoveryPoint, recovery_lqe, recovery_sweep, recovery_sweep_with,
    state_feedback_margins,
};

use crate::linalg::{MatrixError, RiccatiError};

/// Why a design failed: bad input, or the Riccati equation of the design.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DesignError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error(transparent)]
    Riccati(#[from] RiccatiError),
}
