//! The bgc runtime: design, estimation, control and simulation for bond-graph models.
//!
//! - [`model`]: the traits generated models implement; [`statespace`]: linear models; [`linearize`]: the linear
//!   model of a nonlinear one at an operating point; [`matrix`]: `SMatrix` ↔ `DMatrix` conversions.
//! - [`linalg`]: Riccati and Lyapunov equations, discretisation, controllability and observability.
//! - [`design`]: LQR (with integral action) and Kalman gains.
//! - [`estimation`]: Kalman filters, the UKF and dual UKF, sensor fusion, filter health.
//! - [`control`]: impedance control and the gait-phase supervisor.
//! - [`analysis`]: frequency response and stability margins.
//! - [`sim`]: sampled-data closed-loop simulation (exact for linear plants, on diffsol for nonlinear ones).
//! - [`fit`]: parameter identification from measured records (Levenberg–Marquardt on forward sensitivities).
//!
//! # Features
//! - `ode` (default): the ODE solver (diffsol) behind `sim`'s open-loop and nonlinear sampled-loop simulation and
//!   behind `fit`'s fits. Without it the crate keeps everything else, including the exact linear-plant loop
//!   (`sim::simulate_sampled_linear_loop`), and a first build skips diffsol and its dense linear algebra.

//! # Re-exports
//! Generated modules reach [`nalgebra`] and [`libm`] through this crate (`bgc_runtime::nalgebra`), so a crate that
//! uses them depends on `bgc-runtime` alone, and its own `nalgebra`, if any, may be another version. Values passed
//! to a generated model are built with `bgc_runtime::nalgebra` (or the same version of nalgebra).

pub use libm;
pub use nalgebra;

pub mod analysis;
pub mod control;
pub mod design;
pub mod estimation;
pub mod fit;
pub mod linalg;
pub mod linearize;
pub mod matrix;
pub mod model;
pub mod noise;
pub mod sim;
pub mod statespace;
