//! Parameter identification from measured records: `bgc fit` and the same from Rust.
//!
//! The fit simulates the model over the record, so it needs the default feature `ode` (diffsol); without it only
//! the records, the optimiser and the statistics remain, with [`generated::ParamJacobians`], which every generated
//! model implements.
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

pub mod csv;
pub mod generated;
#[cfg(feature = "ode")]
pub mod linear;
pub mod lm;
#[cfg(feature = "ode")]
pub mod problem;
pub mod record;
#[cfg(feature = "ode")]
pub mod sensitivity;
pub mod stats;

#[cfg(feature = "ode")]
pub use generated::Generated;
pub use lm::{Convergence, LmOptions, StopReason};
#[cfg(feature = "ode")]
pub use problem::{
    Estimate, FitError, FitReport, FitSpec, FreeParam, FreeState, Undetermined, fit,
};
pub use record::{Interp, Record, RecordError};
#[cfg(feature = "ode")]
pub use sensitivity::FitModel;
