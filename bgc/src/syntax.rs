//! The front end's syntax: the AST, the parser and the formatter.

pub mod ast;
