//! Positions: byte offsets of bgc's spans and the LSP's (line, UTF-16 code unit) positions.
//!
//! The protocol counts columns in UTF-16 code units by default (the client may offer others; this server always
//! asks for UTF-16, which every client supports), so a line with `µ` or `Ω` has columns that differ from both its
//! byte and its character offsets. A position past the end of its line is clamped to the line's end, and one
//! inside a character that takes two UTF-16 units is moved to the start of that character, as the protocol asks.

use lsp_types::{Position, Range};

/// The starts of the lines of one text, for conversions in both directions.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LineIndex {
    /// Byte offset of the start of each line (the first is 0).
    starts: Vec<usize>,
    /// Whether each line is ASCII: its UTF-16 columns are then its byte offsets, and a conversion costs no walk
    /// of the line (a generated model on one line of 500 kB has thousands of positions to convert).
    ascii: Vec<bool>,
    len: usize,
}

impl LineIndex {
    /// The lines of `text`, each ended by `\n`, `\r\n` or a lone `\r` (the protocol's three line breaks).
    pub fn new(text: &str) -> LineIndex {
        let bytes = text.as_bytes();
        let lone_cr = |i: usize| bytes.get(i + 1) != Some(&b'\n');
        let starts = std::iter::once(0)
            .chain(
                text.match_indices(['\n', '\r'])
                    .filter(|&(i, m)| m == "\n" || lone_cr(i))
                    .map(|(i, _)| i + 1),
            )
            .collect::<Vec<usize>>();
        let ascii = starts
            .iter()
            .zip(starts.iter().skip(1).chain(std::iter::once(&text.len())))
            .map(|(&a, &b)| text.as_bytes().get(a..b).is_some_and(<[u8]>::is_ascii))
            .collect();
        LineIndex {
            starts,
            ascii,
            len: text.len(),
        }
    }

    fn is_ascii(&self, line: usize) -> bool {
        self.ascii.get(line).copied().unwrap_or(false)
    }

    /// The position of a byte offset (clamped to the text, and moved back to a character boundary).
    pub fn position(&self, text: &str, offset: usize) -> Position {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = match self.starts.binary_search(&offset) {
            Ok(l) => l,
            Err(l) => l.saturating_sub(1),
        };
        let start = self.starts.get(line).copied().unwrap_or(0);
        let column: usize = match self.is_ascii(line) {
            true => offset.saturating_sub(start),
            false => text
                .get(start..offset)
                .map(|s| s.chars().map(char::len_utf16).sum())
                .unwrap_or(0),
        };
        Position::new(line as u32, column as u32)
    }

    /// The byte offset of a position: a line past the end is the end of the text, a column past the end of its
    /// line is the line's end (before its line break).
    pub fn offset(&self, text: &str, position: Position) -> usize {
        let Some(&start) = self.starts.get(position.line as usize) else {
            return self.len.min(text.len());
        };
        let end = self
            .starts
            .get(position.line as usize + 1)
            .map(|&next| next - 1)
            .unwrap_or(text.len());
        let ascii = self.is_ascii(position.line as usize);
        let line = text.get(start..end).unwrap_or("");
        let line = line.strip_suffix('\r').unwrap_or(line);
        if ascii {
            return start + line.len().min(position.character as usize);
        }
        let mut units = 0usize;
        for (i, c) in line.char_indices() {
            let width = c.len_utf16();
            if units + width > position.character as usize {
                return start + i;
            }
            units += width;
        }
        start + line.len()
    }

    /// The range of a byte range.
    pub fn range(&self, text: &str, bytes: std::ops::Range<usize>) -> Range {
        Range::new(
            self.position(text, bytes.start),
            self.position(text, bytes.end.max(bytes.start)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_count_utf16_units() {
        // `µ` is 2 bytes and 1 UTF-16 unit; `𝜔` (U+1D714) is 4 bytes and 2 units.
        let text = "a µ𝜔 b\nsecond\n";
        let index = LineIndex::new(text);
        let b = text.find('b').unwrap_or(0);
        assert_eq!(index.position(text, b), Position::new(0, 6));
        assert_eq!(index.offset(text, Position::new(0, 6)), b);
        let second = text.find("second").unwrap_or(0);
        assert_eq!(index.position(text, second + 3), Position::new(1, 3));
        assert_eq!(index.offset(text, Position::new(1, 3)), second + 3);
    }

    /// ASCII lines convert by arithmetic, the others by walking their characters: both agree with counting the
    /// UTF-16 units from the line's start, on every offset of a text that mixes them and every line break.
    #[test]
    fn ascii_lines_and_the_others_convert_alike() {
        let text = "model m { param a = 1 [1]; }\r\n// µ 𝜔 x\nplain line\rτ_m = 2\n\nlast";
        let index = LineIndex::new(text);
        let mut line = 0u32;
        let mut start = 0usize;
        let mut chars = text.char_indices().peekable();
        while let Some((i, c)) = chars.next() {
            let column: usize = text[start..i].chars().map(char::len_utf16).sum();
            let at = Position::new(line, column as u32);
            assert_eq!(index.position(text, i), at, "offset {i}");
            if c != '\r' && c != '\n' {
                assert_eq!(index.offset(text, at), i, "{at:?}");
            }
            let ends_line = c == '\n' || (c == '\r' && chars.peek().map(|&(_, n)| n) != Some('\n'));
            if ends_line {
                line += 1;
                start = i + 1;
            }
        }
        assert_eq!(
            index.offset(text, Position::new(0, 500)),
            text.find('\r').unwrap_or(0)
        );
    }

    #[test]
    fn positions_out_of_range_are_clamped() {
        let text = "ab\r\ncd";
        let index = LineIndex::new(text);
        // Past the end of line 0: before its `\r\n`.
        assert_eq!(index.offset(text, Position::new(0, 99)), 2);
        // Past the last line: the end of the text.
        assert_eq!(index.offset(text, Position::new(7, 0)), text.len());
        // Inside the surrogate pair of `𝜔`: the start of the character.
        let text = "𝜔x";
        let index = LineIndex::new(text);
        assert_eq!(index.offset(text, Position::new(0, 1)), 0);
        assert_eq!(index.offset(text, Position::new(0, 2)), 4);
        assert_eq!(index.position(text, 2), Position::new(0, 0));
    }

    #[test]
    fn a_lone_carriage_return_ends_a_line_as_the_protocol_says() {
        let text = "ab\rcd\r\nef\ngh";
        let index = LineIndex::new(text);
        for (offset, line, column) in [(1, 0, 1), (3, 1, 0), (4, 1, 1), (7, 2, 0), (10, 3, 0)] {
            assert_eq!(index.position(text, offset), Position::new(line, column));
            assert_eq!(index.offset(text, Position::new(line, column)), offset);
        }
        // Past the end of a line: before its break, whichever it is.
        assert_eq!(index.offset(text, Position::new(0, 9)), 2);
        assert_eq!(index.offset(text, Position::new(1, 9)), 5);
    }
}
