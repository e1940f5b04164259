//! Workspace root: integration tests and examples.
//!
//! - [`back_support`]: the back-support exoskeleton study behind the `back_support` example.
//! - [`rehab`]: the rehabilitation-exoskeleton measurement study (IMU, vision and their fusion).
//! - [`walking`]: the lower-limb walking exoskeleton behind the `walking` example.

pub mod back_support;
pub mod rehab;
pub mod walking;
