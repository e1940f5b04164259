//! The open documents: the editor's text of each, kept up to date by incremental changes.
//!
//! The server asks for incremental sync: each `didChange` carries edits with a range in the text as it was after
//! the previous edit (of the same notification, in order). A change without a range replaces the whole text.

use super::lines::LineIndex;
use lsp_types::{TextDocumentContentChangeEvent, Uri};
use std::collections::BTreeMap;

/// One open document.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Document {
    pub text: String,
    pub version: i32,
    pub lines: LineIndex,
}

impl Document {
    pub fn new(text: String, version: i32) -> Document {
        let lines = LineIndex::new(&text);
        Document {
            text,
            version,
            lines,
        }
    }

    /// Applies the edits of one `didChange` in order.
    pub fn apply(&mut self, changes: &[TextDocumentContentChangeEvent], version: i32) {
        for change in changes {
            match change.range {
                Some(range) => {
                    let start = self.lines.offset(&self.text, range.start);
                    let end = self.lines.offset(&self.text, range.end).max(start);
                    self.text.replace_range(start..end, &change.text);
                }
                None => self.text.clone_from(&change.text),
            }
            self.lines = LineIndex::new(&self.text);
        }
        self.version = version;
    }
}

/// The open documents by URI.
#[derive(Clone, Debug, Default)]
pub struct Documents {
    open: BTreeMap<String, (Uri, Document)>,
}

impl Documents {
    pub fn open(&mut self, uri: Uri, text: String, version: i32) {
        self.open.insert(
            uri.as_str().to_string(),
            (uri, Document::new(text, version)),
        );
    }

    pub fn close(&mut self, uri: &Uri) {
        self.open.remove(uri.as_str());
    }

    pub fn get(&self, uri: &Uri) -> Option<&Document> {
        self.open.get(uri.as_str()).map(|(_, d)| d)
    }

    pub fn get_mut(&mut self, uri: &Uri) -> Option<&mut Document> {
        self.open.get_mut(uri.as_str()).map(|(_, d)| d)
    }

    /// Every open document, in the order of their URIs.
    pub fn iter(&self) -> impl Iterator<Item = (&Uri, &Document)> {
        self.open.values().map(|(u, d)| (u, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lsp_types::{Position, Range};

    fn edit(l0: u32, c0: u32, l1: u32, c1: u32, text: &str) -> TextDocumentContentChangeEvent {
        TextDocumentContentChangeEvent {
            range: Some(Range::new(Position::new(l0, c0), Position::new(l1, c1))),
            range_length: None,
            text: text.to_string(),
        }
    }

    #[test]
    fn edits_apply_in_order_with_utf16_columns() {
        let mut doc = Document::new("param µ = 1 [1];\nR r = µ;\n".into(), 1);
        // Rename `µ` on line 1 (column 6, one UTF-16 unit), then on line 0, each range in the text before it.
        doc.apply(&[edit(1, 6, 1, 7, "mu"), edit(0, 6, 0, 7, "mu")], 2);
        assert_eq!(doc.text, "param mu = 1 [1];\nR r = mu;\n");
        assert_eq!(doc.version, 2);
        // Join the two lines, then replace everything.
        doc.apply(&[edit(0, 17, 1, 0, " ")], 3);
        assert_eq!(doc.text, "param mu = 1 [1]; R r = mu;\n");
        let whole = TextDocumentContentChangeEvent {
            range: None,
            range_length: None,
            text: "x".into(),
        };
        doc.apply(&[whole], 4);
        assert_eq!(doc.text, "x");
        assert_eq!(doc.lines, LineIndex::new("x"));
    }
}
