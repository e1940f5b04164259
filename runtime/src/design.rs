//! Controller and estimator design on linear models: LQR (continuous and discrete, with integral action) and
//! steady-state Kalman gains.
//!
//! Conventions: state feedback is `u = −K x`; gains come from the stabilising Riccati solutions of
//! [`crate::linalg`], so every function here inherits its checks (shapes, finiteness, symmetry, definiteness,
//! stabilisability, detectability, residual and closed-loop stability) and its errors.

mod lqr;

pub use lqr::{lqr, lqr_with_cross};
