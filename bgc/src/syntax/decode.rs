//! Checking that a source file is UTF-8.

use crate::diagnostic::Diagnostic;
use crate::span::{FileId, Span};

/// The text of a source file, or `BG0100` pointing at the first byte that is not valid UTF-8 (or, for a file
/// saved as UTF-16, saying so once).
pub fn decode(file: FileId, bytes: &[u8]) -> Result<&str, Diagnostic> {
    if let Some(d) = utf16(file, bytes) {
        return Err(d);
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

/// A file saved as UTF-16 (what some Windows editors call "Unicode"): known by its byte-order mark, or by the zero
/// byte that UTF-16 puts beside each ASCII character. Without this, the first is "byte 0xFF at offset 0" and the
/// second, being valid UTF-8, a stream of invalid-character errors, one per letter.
fn utf16(file: FileId, bytes: &[u8]) -> Option<Diagnostic> {
    let bom = bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]);
    let head = bytes.get(..bytes.len().min(512)).unwrap_or(&[]);
    let zeros = head.iter().filter(|&&b| b == 0).count();
    // ASCII text in UTF-16 is half zeros; no source file has any.
    let zero_bytes = head.len() >= 4 && 4 * zeros >= head.len();
    let why = match (bom, zero_bytes) {
        (true, _) => "it starts with a UTF-16 byte-order mark",
        (false, true) => "every other byte is zero, as in UTF-16",
        (false, false) => return None,
    };
    Some(
        Diagnostic::error(
            "BG0100",
            format!("the file is UTF-16 text, not UTF-8: {why}"),
        )
        .with_primary(Span::new(file, 0, 1), "UTF-16")
        .with_help("save the file as UTF-8 text (an editor's \"Save as\" offers the encoding)"),
    )
}
