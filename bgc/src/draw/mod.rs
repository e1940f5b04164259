//! Drawing bond graphs.
