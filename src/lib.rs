//! Workspace root: integration tests and examples.
pub mod walking;
