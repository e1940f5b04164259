//! Simulation of continuous models on diffsol: open-loop runs with dense output, and sampled-data closed
//! loops with a discrete controller, zero-order-hold inputs, seeded noise and measurement delay.
//!
//! - [`options`]: the solver choice ([`Method`]: BDF by default, ESDIRK3(4), TR-BDF2, Tsit5(4)) and
//!   tolerances ([`SolverOptions`]); `integrate`: one segment on diffsol.
//! - [`open_loop`]: [`simulate_open_loop`], the state, input and output at requested times.
//! - [`sampled`]: [`simulate_sampled_loop`], the sampled-data loop and its record (or a stream of samples);
//!   [`simulate_sampled_linear_loop`] for a [`LinearPlant`] with the exact zero-order-hold step ([`linear`]).
//!
//! The ODE solver (diffsol) comes with the crate's default feature `ode`: without it, the linear-plant loop
//! ([`simulate_sampled_linear_loop`], exact) and the plain-data settings remain, and the open-loop and nonlinear
//! sampled-loop simulations are left out, with diffsol and its dense linear algebra (`faer`), which take most of a
//! first build.
//!
//! Solver failures, non-finite states, derivatives, outputs or inputs are returned as [`SimError`] values
//! carrying the simulated time at which they happened; nothing panics.

use nalgebra::SVector;

pub mod error;
#[cfg(feature = "ode")]
pub mod integrate;
pub mod linear;
#[cfg(feature = "ode")]
pub mod open_loop;
pub mod options;
pub mod sampled;

pub use error::SimError;
pub use linear::LinearPlant;
#[cfg(feature = "ode")]
pub use open_loop::{Trajectory, simulate_open_loop};
pub use options::{Method, SolverOptions};
pub use sampled::{
    MAX_MEASUREMENT_DELAY, MAX_RECORD_BYTES, Sample, SampledController, SampledLoopConfig,
    SampledTrajectory, simulate_sampled_linear_loop, simulate_sampled_linear_loop_streaming,
};
#[cfg(feature = "ode")]
pub use sampled::{simulate_sampled_loop, simulate_sampled_loop_streaming};

/// Refuses a non-finite start time or initial state, before any run.
pub(crate) fn check_initial<const NX: usize>(
    t0: f64,
    x0: &SVector<f64, NX>,
) -> Result<(), SimError> {
    if !t0.is_finite() {
        return Err(SimError::BadSetting {
            name: "t0",
            value: t0,
            reason: "the initial time must be finite",
        });
    }
    if let Some(v) = x0.iter().find(|v| !v.is_finite()) {
        return Err(SimError::BadSetting {
            name: "x0",
            value: *v,
            reason: "the initial state must be finite",
        });
    }
    Ok(())
}
