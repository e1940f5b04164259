//! Simulation of continuous models on diffsol: open-loop runs with dense output, and sampled-data closed
//! loops with a discrete controller, zero-order-hold inputs, seeded noise and measurement delay.
//!
//! - [`integrate`]: the solver choice ([`Method`]: BDF by default, ESDIRK3(4), TR-BDF2, Tsit5(4)) and
//!   tolerances ([`SolverOptions`]).
//! - [`open_loop`]: [`simulate_open_loop`], the state, input and output at requested times.
//! - [`sampled`]: [`simulate_sampled_loop`], the sampled-data loop and its record (or a stream of samples);
//!   [`simulate_sampled_linear_loop`] for a [`LinearPlant`] with the exact zero-order-hold step ([`linear`]).
//!
//! Solver failures, non-finite states, derivatives, outputs or inputs are returned as [`SimError`] values
//! carrying the simulated time at which they happened; nothing panics.

pub mod error;
pub mod integrate;
pub mod linear;
pub mod open_loop;
pub mod sampled;

pub use error::SimError;
pub use integrate::{Method, SolverOptions};
pub use linear::LinearPlant;
pub use open_loop::{Trajectory, simulate_open_loop};
pub use sampled::{
    MAX_MEASUREMENT_DELAY, MAX_RECORD_BYTES, Sample, SampledController, SampledLoopConfig,
    SampledTrajectory, simulate_sampled_linear_loop, simulate_sampled_linear_loop_streaming,
    simulate_sampled_loop, simulate_sampled_loop_streaming,
};
