//! Parameter identification from measured records: `bgc fit` and the same from Rust.
//!
//! - [`record`]: a measured record (CSV or built in code), checked, with its input interpolation.
//! - [`sensitivity`]: the [`FitModel`] trait and the outputs' forward sensitivities over a record;
//!   [`linear`]: the same, exactly and in milliseconds, for a linear time-invariant model with held inputs (one
//!   matrix exponential of the plant augmented with its sensitivity system per parameter set).
//! - [`lm`]: Levenberg–Marquardt with bounds; [`stats`]: standard errors, correlations, and the parameter
//!   combinations a record does not determine.
//! - [`problem`]: [`fit`], which ties them together, and its [`FitReport`].
//! - [`generated`]: [`Generated`], a generated model (or any [`crate::model::ContinuousModel`] with
//!   [`crate::model::Parametric`]) as a [`FitModel`].

pub mod generated;
pub mod linear;
pub mod lm;
pub mod problem;
pub mod record;
pub mod sensitivity;
pub mod stats;

pub use generated::Generated;
pub use lm::{Convergence, LmOptions, StopReason};
pub use problem::{
    Estimate, FitError, FitReport, FitSpec, FreeParam, FreeState, Undetermined, fit,
};
pub use record::{Interp, Record, RecordError};
pub use sensitivity::FitModel;
