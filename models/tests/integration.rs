//! The integration tests of this crate, in one test binary: one module per concern.

#[path = "support/eq3.rs"]
mod eq3;
mod support;

mod agreement;
mod energy;
mod loops;
mod no_alloc;
mod param_jacobians;
mod params;
mod runtime;
