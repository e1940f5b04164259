//! Source files and byte spans.

use serde::Serialize;

/// Index of a file in a [`SourceMap`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct FileId(pub u32);

/// A half-open byte range `[start, end)` in one file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Span {
    pub file: FileId,
    pub start: u32,
    pub end: u32,
}

impl Span {
    pub fn new(file: FileId, start: usize, end: usize) -> Self {
        // Files above 4 GiB are refused when they are loaded, so the casts cannot truncate.
        Span {
            file,
            start: start as u32,
            end: end as u32,
        }
    }

    /// The smallest span covering both.
    pub fn to(self, other: Span) -> Span {
        Span {
            file: self.file,
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }

    pub fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// One loaded source file.
#[derive(Clone, Debug)]
pub struct SourceFile {
    /// The name shown in diagnostics (the path as given).
    pub name: String,
    /// The text, with each carriage return that is a line break of its own written as `\n` (see
    /// [`SourceFile::new`]).
    pub text: String,
    /// Byte offset of the start of each line.
    line_starts: Vec<usize>,
}

impl SourceFile {
    /// The file `name` with `text`. A line may end in `\n`, `\r\n` or (as classic Mac OS wrote it, and as the
    /// Language Server Protocol allows) `\r` alone; the last is made `\n` here, a byte for a byte, so that the
    /// lexer, the line numbers and the rendered excerpts all see one kind of line break at the same offsets.
    pub fn new(name: impl Into<String>, text: impl Into<String>) -> Self {
        let text = lone_carriage_returns_as_newlines(text.into());
        let line_starts = line_starts(text.as_bytes());
        SourceFile {
            name: name.into(),
            text,
            line_starts,
        }
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = match self.line_starts.binary_search(&offset) {
            Ok(l) => l,
            Err(l) => l - 1,
        };
        let start = self.line_starts[line];
        let col = self
            .text
            .get(start..offset)
            .map(|s| s.chars().count())
            .unwrap_or(offset - start);
        (line + 1, col + 1)
    }
}

/// The byte offset of the start of each line. Searching for each `\n` in turn costs more than the short lines it
/// skips; instead, eight bytes at a time are tested for a `\n` at once (a test the compiler vectorises), and only
/// those that have one are scanned.
fn line_starts(bytes: &[u8]) -> Vec<usize> {
    let mut starts = vec![0];
    for (c, chunk) in bytes.chunks(8).enumerate() {
        if chunk.iter().fold(false, |any, &b| any | (b == b'\n')) {
            let base = c * 8;
            starts.extend(
                chunk
                    .iter()
                    .enumerate()
                    .filter(|&(_, &b)| b == b'\n')
                    .map(|(i, _)| base + i + 1),
            );
        }
    }
    starts
}

/// `text` with every `\r` that is not followed by `\n` replaced by `\n`.
fn lone_carriage_returns_as_newlines(text: String) -> String {
    if !text.contains('\r') {
        return text;
    }
    let mut bytes = text.into_bytes();
    for i in 0..bytes.len() {
        if bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n') {
            bytes[i] = b'\n';
        }
    }
    // One ASCII byte for another keeps the text UTF-8.
    String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned())
}

/// All files of one compilation; a [`FileId`] indexes into it.
#[derive(Clone, Debug, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn add(&mut self, name: impl Into<String>, text: impl Into<String>) -> FileId {
        self.files.push(SourceFile::new(name, text));
        FileId((self.files.len() - 1) as u32)
    }

    pub fn get(&self, id: FileId) -> Option<&SourceFile> {
        self.files.get(id.0 as usize)
    }

    pub fn files(&self) -> impl Iterator<Item = (FileId, &SourceFile)> {
        self.files
            .iter()
            .enumerate()
            .map(|(i, f)| (FileId(i as u32), f))
    }

    /// The text a span covers, or "" when the span is out of range.
    pub fn snippet(&self, span: Span) -> &str {
        self.get(span.file)
            .and_then(|f| f.text.get(span.range()))
            .unwrap_or("")
    }
}

#[cfg(test)]
mod tests {
    use super::{SourceFile, line_starts};

    #[test]
    fn a_lone_carriage_return_is_a_line_break_at_the_same_offset() {
        let f = SourceFile::new("a.bg", "ab\rcd\r\nef\r");
        assert_eq!(f.text, "ab\ncd\r\nef\n");
        assert_eq!(f.line_col(3), (2, 1));
        assert_eq!(f.line_col(7), (3, 1));
        let unchanged = "µ\r\nx\n";
        assert_eq!(SourceFile::new("b.bg", unchanged).text, unchanged);
    }

    #[test]
    fn line_starts_follow_every_newline() {
        for text in [
            "",
            "a",
            "\n",
            "ab\ncd\n",
            "\n\n\n",
            "0123456\n89abcdef\n",
            "0123456789abcdef\nx",
            "µ\nµ",
        ] {
            let expected: Vec<usize> = std::iter::once(0)
                .chain(text.match_indices('\n').map(|(i, _)| i + 1))
                .collect();
            assert_eq!(line_starts(text.as_bytes()), expected, "{text:?}");
        }
    }
}
