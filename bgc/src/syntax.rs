//! The front end's syntax: the AST, the parser and the formatter.
//!
//! [`decode`] checks that a file is UTF-8, [`parse`] turns its text into an [`ast::File`] plus diagnostics (it
//! never fails: the tree holds everything that parsed) and [`format`] prints a tree back in the canonical layout.
//! The grammar is in docs/language.md; the diagnostic codes of this stage are `BG0100`-`BG0117`.

pub mod ast;
mod decode;
mod expr;
mod format;
mod lexer;
mod parser;
mod stmt;
mod suggest;

#[cfg(test)]
mod format_tests;
#[cfg(test)]
mod snapshot_tests;
#[cfg(test)]
mod tests;

pub use decode::decode;
pub use format::{format, format_source};
pub use parser::{KEYWORDS, MAX_DEPTH};

use crate::diagnostic::Diagnostic;
use crate::span::FileId;

/// Parses the text of one file.
///
/// Parsing never fails: the returned tree holds every item and statement that parsed, and the diagnostics list every
/// syntax error found (a statement with an error is left out of the tree and parsing resumes after it). Spans are
/// byte ranges into `text`. Time and memory are linear in the length of `text`.
pub fn parse(file: FileId, text: &str) -> (ast::File, Vec<Diagnostic>) {
    parser::parse_file(file, text)
}
