//! Checking that a source file is UTF-8.

use crate::diagnostic::Diagnostic;
use crate::span::{FileId, Span};

/// The text of a source file, or `BG0100` pointing at the first byte that is not valid UTF-8.
pub fn decode(file: FileId, bytes: &[u8]) -> Result<&str, Diagnostic> {
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
        Diagnostic::error(
            "BG0100",
            format!(
                "the file is not valid UTF-8: byte {} at offset {at}",
                shown.join(" ")
            ),
        )
        .with_primary(Span::new(file, at, end), "invalid UTF-8")
        .with_help("save the file as UTF-8 text")
    })
}
