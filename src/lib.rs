//! Workspace root: integration tests and examples.
