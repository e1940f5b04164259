//! Workspace root: integration tests and examples.
//!
//! - [`back_support`]: the back-support exoskeleton study behind the `back_support` example.

pub mod back_support;
