//! The text of a measured record, from the bytes that logging tools and spreadsheets write.
//!
//! UTF-8 (with or without a byte-order mark) is read as it is. UTF-16 with its byte-order mark (a spreadsheet's
//! "Unicode text" export) is decoded: the mark says the encoding for certain. Anything else is refused with where
//! the first byte that is not UTF-8 is, and what it is in Latin-1, the usual other encoding of a record's header
//! (`µs`, `°`): the record is one the user can re-save, not one bgc should guess at.

use bgc::syntax::Utf16;
use std::io::{Error, ErrorKind};

/// The record's text, or why its bytes are not text bgc reads.
pub fn record_text(bytes: Vec<u8>) -> std::io::Result<String> {
    let invalid = |why: String| Error::new(ErrorKind::InvalidData, why);
    let unit = match Utf16::detect(&bytes) {
        Some(Utf16::Marked {
            little_endian: true,
        }) => u16::from_le_bytes,
        Some(Utf16::Marked {
            little_endian: false,
        }) => u16::from_be_bytes,
        Some(Utf16::ZeroBytes) => {
            return Err(invalid(
                "the record looks like UTF-16 without a byte-order mark (every other byte is zero): save it as \
                 UTF-8, or as UTF-16 with its byte-order mark"
                    .into(),
            ));
        }
        None => {
            return String::from_utf8(bytes)
                .map_err(|e| invalid(not_utf8(e.as_bytes(), e.utf8_error().valid_up_to())));
        }
    };
    utf16(bytes.get(2..).unwrap_or(&[]), unit).map_err(invalid)
}

/// UTF-16 code units from pairs of bytes, decoded; an odd byte or a lone surrogate is an error.
fn utf16(bytes: &[u8], unit: fn([u8; 2]) -> u16) -> Result<String, String> {
    if !bytes.len().is_multiple_of(2) {
        return Err(
            "the record is UTF-16 (by its byte-order mark) but has an odd number of bytes".into(),
        );
    }
    let units = bytes.chunks_exact(2).map(|p| unit([p[0], p[1]]));
    char::decode_utf16(units)
        .collect::<Result<String, _>>()
        .map_err(|e| {
            format!(
                "the record is UTF-16 (by its byte-order mark) but holds a lone surrogate 0x{:04X}",
                e.unpaired_surrogate()
            )
        })
}

/// Where the first byte that is not UTF-8 is (line and column, counted in characters), and what it would be in
/// Latin-1.
fn not_utf8(bytes: &[u8], at: usize) -> String {
    let before = String::from_utf8_lossy(bytes.get(..at).unwrap_or(&[]));
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    let byte = bytes.get(at).copied().unwrap_or(0);
    let latin1 = match byte {
        0xA0..=0xFF => format!(" (`{}` in Latin-1 or Windows-1252)", char::from(byte)),
        _ => String::new(),
    };
    format!(
        "the record is not UTF-8: byte 0x{byte:02X}{latin1} at line {line}, column {column}: save it as UTF-8"
    )
}

#[cfg(test)]
mod tests {
    use super::record_text;

    fn text(bytes: &[u8]) -> Result<String, String> {
        record_text(bytes.to_vec()).map_err(|e| e.to_string())
    }

    #[test]
    fn utf16_with_its_mark_is_read_in_either_byte_order() {
        let record = "t\tF [µN]\n0\t1\n";
        let le: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain(record.encode_utf16().flat_map(u16::to_le_bytes))
            .collect();
        let be: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain(record.encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        assert_eq!(text(&le).as_deref(), Ok(record));
        assert_eq!(text(&be).as_deref(), Ok(record));
        assert!(text(&le[..le.len() - 1]).is_err_and(|e| e.contains("odd number of bytes")));
        let lone = [0xFF, 0xFE, 0x00, 0xD8, 0x41, 0x00];
        assert!(text(&lone).is_err_and(|e| e.contains("lone surrogate 0xD800")));
    }

    #[test]
    fn other_encodings_are_refused_with_where_and_what() {
        let no_mark: Vec<u8> = "t,F\n0,1\n"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        assert!(text(&no_mark).is_err_and(|e| e.contains("UTF-16 without a byte-order mark")));
        // `t [µs]` saved as Latin-1 on the second line.
        let latin1 = b"# rig 3\nt [\xB5s],F\n0,1\n";
        assert_eq!(
            text(latin1),
            Err("the record is not UTF-8: byte 0xB5 (`µ` in Latin-1 or Windows-1252) at line 2, column 4: save \
                 it as UTF-8"
                .into())
        );
        assert_eq!(text("t,F\n".as_bytes()).as_deref(), Ok("t,F\n"));
    }
}
