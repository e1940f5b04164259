//! The bgc runtime: design, estimation, control and simulation for bond-graph models.
//!
//! - [`model`]: the traits generated models implement; [`statespace`]: linear models; [`linearize`]: the linear
//!   model of a nonlinear one at an operating point; [`matrix`]: `SMatrix` ↔ `DMatrix` conversions.
//! - [`linalg`]: Riccati and Lyapunov equations, discretisation, controllability and observability.
//! - [`design`]: LQR (with integral action) and Kalman gains.
//! - [`estimation`]: Kalman filters, the UKF and dual UKF, sensor fusion, filter health.
//! - [`control`]: impedance control and the gait-phase supervisor.
//! - [`analysis`]: frequency response and stability margins.
//! - [`sim`]: sampled-data closed-loop simulation on diffsol.
//! - [`fit`]: parameter identification from measured records (Levenberg–Marquardt on forward sensitivities).

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
