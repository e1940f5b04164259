//! The integration tests of this crate, in one test binary: one module per concern.

mod back_support;
mod rehab_fusion;
mod walking;
mod walking_equations;
