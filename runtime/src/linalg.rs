//! Dense linear algebra for control design: Riccati and Lyapunov equations, the matrix exponential and
//! discretisation, controllability and observability.
//!
//! All functions take `DMatrix<f64>` (design time, not the control loop), validate their inputs (shapes,
//! finiteness, symmetry, definiteness) and return `Result`s with structured errors; none panics on bad input.
//!
//! - [`care`], [`care_with_cross`], [`dare`], [`dare_with_cross`]: stabilising solutions of the algebraic Riccati
//!   equations, with balancing, a structured base solver and Newton (Kleinman/Hewer) refinement.
//! - [`lyap`], [`dlyap`], [`sylvester()`], [`stein`]: Lyapunov, Sylvester and Stein equations (Bartels–Stewart,
//!   `O(n³)`).
//! - [`expm()`], [`c2d_zoh`], [`van_loan`]: matrix exponential, zero-order-hold discretisation, discrete
//!   process-noise covariance.
//! - [`pbh`]: PBH tests naming uncontrollable/unobservable modes, stabilisability, detectability, Kalman ranks.

pub mod balance;
mod care;
pub mod check;
mod dare;
pub mod discretize;
pub mod expm;
pub mod lyapunov;
pub mod pbh;
mod refine;
pub mod riccati;
pub mod schur;
pub mod sign;
pub mod sylvester;

pub use care::{care, care_with_cross};
pub use check::MatrixError;
pub use dare::{dare, dare_with_cross};
pub use discretize::{DiscretizeError, c2d_zoh, van_loan, zoh_blocks};
pub use expm::{ExpmError, expm};
pub use lyapunov::{LyapunovError, dlyap, lyap};
pub use pbh::{
    Domain, Mode, PbhError, controllability_matrix, controllability_rank, is_detectable,
    is_stabilizable, observability_matrix, observability_rank, uncontrollable_modes,
    unobservable_modes,
};
pub use riccati::{Riccati, RiccatiError};
pub use schur::{SchurError, eigenvalues};
pub use sylvester::{stein, sylvester};
