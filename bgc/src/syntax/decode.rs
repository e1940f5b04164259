//! Checking that a source file is UTF-8, and recognising text in UTF-16.

use crate::diagnostic::Diagnostic;
use crate::span::{FileId, Span};
use std::ops::Range;

/// How text in UTF-16 (what some Windows editors and spreadsheets call "Unicode") shows itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Utf16 {
    /// A byte-order mark: `FF FE` (little-endian) or `FE FF` (big-endian). It says the encoding for certain.
    Marked { little_endian: bool },
    /// No mark, but the zero byte UTF-16 puts beside each ASCII character (no UTF-8 text has any).
    ZeroBytes,
}

impl Utf16 {
    /// What `bytes` are, if they look like UTF-16.
    pub fn detect(bytes: &[u8]) -> Option<Utf16> {
        if bytes.starts_with(&[0xFF, 0xFE]) {
            return Some(Utf16::Marked {
                little_endian: true,
            });
        }
        if bytes.starts_with(&[0xFE, 0xFF]) {
            return Some(Utf16::Marked {
                little_endian: false,
            });
        }
        let head = bytes.get(..bytes.len().min(512)).unwrap_or(&[]);
        // ASCII text in UTF-16 is half zeros.
        let zeros = head.iter().filter(|&&b| b == 0).count();
        (head.len() >= 4 && 4 * zeros >= head.len()).then_some(Utf16::ZeroBytes)
    }

    /// How it was recognised, in words.
    pub fn why(self) -> &'static str {
        match self {
            Utf16::Marked { .. } => "it starts with a UTF-16 byte-order mark",
            Utf16::ZeroBytes => "every other byte is zero, as in UTF-16",
        }
    }
}

/// Why bytes are not a source text: where, and the cause in the words that follow "the file is".
struct Problem {
    at: Range<usize>,
    cause: String,
    utf16: bool,
}

/// The text of a source file, or `BG0100` pointing at the first byte that is not valid UTF-8 (or, for a file
/// saved as UTF-16, saying so once).
pub fn decode(file: FileId, bytes: &[u8]) -> Result<&str, Diagnostic> {
    check(bytes).map_err(|p| {
        let (label, help) = match p.utf16 {
            true => (
                "UTF-16",
                "save the file as UTF-8 text (an editor's \"Save as\" offers the encoding)",
            ),
            false => ("invalid UTF-8", "save the file as UTF-8 text"),
        };
        Diagnostic::error("BG0100", format!("the file is {}", p.cause))
            .with_primary(Span::new(file, p.at.start, p.at.end), label)
            .with_help(help)
    })
}

/// The text of a source file, or why it is not one (the cause of [`decode`]'s error, as an import's error says it).
pub fn text_of(bytes: &[u8]) -> Result<&str, String> {
    check(bytes).map_err(|p| p.cause)
}

/// A file in UTF-16 is one problem (without this, the first is "byte 0xFF at offset 0" and the second, being valid
/// UTF-8, a stream of invalid-character errors, one per letter); otherwise the first byte that is not UTF-8.
fn check(bytes: &[u8]) -> Result<&str, Problem> {
    if let Some(kind) = Utf16::detect(bytes) {
        return Err(Problem {
            at: 0..1,
            cause: format!("UTF-16 text, not UTF-8: {}", kind.why()),
            utf16: true,
        });
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        // An incomplete sequence at the very end has no error length; it runs to the end of the file.
        let len = e.error_len().unwrap_or(bytes.len() - at).max(1);
        let end = (at + len).min(bytes.len());
        let shown: Vec<String> = bytes
            .get(at..end)
            .unwrap_or(&[])
            .iter()
            .map(|b| format!("0x{b:02X}"))
            .collect();
        Problem {
            at: at..end,
            cause: format!("not valid UTF-8: byte {} at offset {at}", shown.join(" ")),
            utf16: false,
        }
    })
}
