//! The front end's syntax: the AST, the parser and the formatter.
//!
//! [`decode`] checks that a file is UTF-8, [`parse`] turns its text into an [`ast::File`] plus diagnostics (it
//! never fails: the tree holds everything that parsed) and [`format()`](fn@format) prints a tree back in the canonical layout.
//! [`format_source`] parses and formats, refusing text with syntax errors; [`format_expr`], [`format_unit`],
//! [`format_node`] and [`format_number`] print pieces of a tree (for messages of later stages).
//!
//! The grammar is in docs/language.md ("Lexical structure"). Diagnostic codes of this stage: `BG0100` invalid UTF-8,
//! `BG0101` unexpected token, `BG0102` unterminated string, `BG0103` bad number, `BG0104` invalid character, `BG0105`
//! nesting too deep, `BG0106` unclosed `{`, `BG0109` keyword as a name, `BG0110` misplaced fan-out, bond name or hint,
//! `BG0111` unmatched closing bracket, `BG0112` unknown string escape, `BG0113` causal stroke not at an end of its bond,
//! `BG0114` (warning) doc comment documenting nothing, `BG0115` bad port count or index, `BG0116` malformed unit,
//! `BG0117` port count on a non-field or missing on a field.

mod allow;
pub mod ast;
mod bond;
mod decode;
mod expr;
pub mod foreign;
mod format;
mod items;
mod lexer;
mod parser;
mod short_list;
mod stmt;
mod suggest;
mod typographic;

#[cfg(test)]
mod format_tests;
#[cfg(test)]
mod snapshot_tests;
#[cfg(test)]
mod tests;

pub use decode::{Utf16, decode, text_of};
pub use format::{
    expr as format_expr, format, format_source, node as format_node, number as format_number,
    unit as format_unit,
};
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
