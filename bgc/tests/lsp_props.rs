//! Property: whatever sequence of edits the editor sends, the server's diagnostics are those of a fresh analysis
//! of the same text (its copy of the document never drifts from the editor's, UTF-16 columns included).

use crate::lsp_support::{Client, back_support_text, edit, unsaved, uri};
use lsp_types::Position;
use proptest::prelude::*;

/// Pieces to insert: names, punctuation that breaks statements, line breaks, and characters of one and two
/// UTF-16 units.
const PIECES: [&str; 14] = [
    "J_m",
    "k",
    ";",
    "}",
    "{",
    "\n",
    " ",
    "µ",
    "𝜔",
    "𝜔µ",
    "Ω𝜔 x",
    "bond a -> b;",
    "//",
    "= 1 [N m]",
];

#[derive(Clone, Debug)]
struct Edit {
    at: prop::sample::Index,
    /// Instead of `at`: this many characters after the end of the previous insertion, so that edits land on the
    /// same line behind characters of two UTF-16 units, where byte, character and UTF-16 columns all differ.
    near: Option<usize>,
    delete: usize,
    insert: &'static str,
    /// Sent in the same notification as the previous edit.
    batched: bool,
}

fn edit_strategy() -> impl Strategy<Value = Edit> {
    (
        any::<prop::sample::Index>(),
        prop::option::weighted(0.6, 0usize..4),
        0usize..6,
        prop::sample::select(&PIECES[..]),
        any::<bool>(),
    )
        .prop_map(|(at, near, delete, insert, batched)| Edit {
            at,
            near,
            delete,
            insert,
            batched,
        })
}

/// The UTF-16 position of a byte offset (a character boundary), counted here independently of the server.
fn position(text: &str, offset: usize) -> Position {
    let before = &text[..offset];
    let line = before.matches('\n').count() as u32;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    Position::new(line, before[start..].encode_utf16().count() as u32)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn diagnostics_after_random_edits_are_those_of_a_fresh_analysis(
        edits in prop::collection::vec(edit_strategy(), 1..8),
    ) {
        let path = unsaved("props.bg");
        let doc = uri(&path);
        let mut text = back_support_text();
        let mut client = Client::start();
        client.open(&doc, &text);
        let mut version = 1;
        let mut batch = Vec::new();
        let mut previous_end = 0usize;
        for e in &edits {
            let boundaries: Vec<usize> = text.char_indices().map(|(i, _)| i).chain([text.len()]).collect();
            let start_index = match e.near {
                Some(d) => {
                    let after = boundaries.iter().position(|&b| b >= previous_end).unwrap_or(0);
                    (after + d).min(boundaries.len() - 1)
                }
                None => e.at.index(boundaries.len()),
            };
            let start = boundaries[start_index];
            let end = boundaries[(start_index + e.delete).min(boundaries.len() - 1)];
            let range = lsp_types::Range::new(position(&text, start), position(&text, end));
            text.replace_range(start..end, e.insert);
            previous_end = start + e.insert.len();
            if !e.batched && !batch.is_empty() {
                version += 1;
                client.change(&doc, version, std::mem::take(&mut batch));
            }
            batch.push(edit(range, e.insert));
        }
        version += 1;
        client.change(&doc, version, batch);
        let served = client.diagnostics(&doc, version);

        let name = path.display().to_string();
        let fresh = bgc::lsp::analysis::analyse(&name, &text, &mut bgc::lower::MemoryLoader::new());
        let expected = bgc::lsp::diagnostics::document_diagnostics(&fresh);
        prop_assert_eq!(served, expected);
        prop_assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
    }
}
