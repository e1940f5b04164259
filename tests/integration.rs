//! The integration tests of this crate, in one test binary: one module per concern.

mod back_support;
mod coverage;
mod fit_back_support;
mod fit_pendulum;
mod rehab_fusion;
mod walking;
mod walking_equations;
