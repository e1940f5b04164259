//! The syntax fixtures: every valid file parses without diagnostics and is already in canonical layout; every invalid
//! file gives the code its name starts with, with the primary label where its second line says.
//!
//! An invalid fixture starts with two comment lines: what is wrong, and `// expect: CODE WHERE`, with `WHERE` one of
//! `at "TEXT"` (the first occurrence of TEXT after the two lines), `at "TEXT" in "CONTEXT"` (TEXT inside the first
//! occurrence of CONTEXT), `after "TEXT"` (the empty span just after it), `at end` (the end of the file) or
//! `at byte N`.

use bgc::diagnostic::Diagnostic;
use bgc::span::{FileId, Span};
use bgc::syntax::{decode, format, parse};
use std::path::{Path, PathBuf};

fn fixtures(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(kind);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "bg"))
        .collect();
    files.sort();
    files
}

/// Decodes and parses a file; a decoding error is the only diagnostic then.
fn check(bytes: &[u8]) -> Vec<Diagnostic> {
    match decode(FileId(0), bytes) {
        Ok(text) => parse(FileId(0), text).1,
        Err(d) => vec![d],
    }
}

/// The span a fixture's `// expect:` line designates.
fn expected_span(bytes: &[u8], where_: &str) -> Span {
    let text = String::from_utf8_lossy(bytes);
    let header = text
        .match_indices('\n')
        .nth(1)
        .map(|(i, _)| i + 1)
        .unwrap_or(0);
    let body = &text[header..];
    let find = |needle: &str, from: usize| -> usize {
        body[from..]
            .find(needle)
            .map(|i| i + from)
            .unwrap_or_else(|| panic!("`{needle}` not found in the fixture"))
    };
    if where_ == "at end" {
        return Span::new(FileId(0), bytes.len(), bytes.len());
    }
    if let Some(n) = where_.strip_prefix("at byte ") {
        let n: usize = n.trim().parse().expect("a byte offset");
        return Span::new(FileId(0), n, n + 1);
    }
    if let Some(q) = where_.strip_prefix("after \"") {
        let needle = q.strip_suffix('"').expect("a quoted text");
        let end = header + find(needle, 0) + needle.len();
        return Span::new(FileId(0), end, end);
    }
    let q = where_
        .strip_prefix("at \"")
        .expect("`at`, `after` or `at end`");
    let q = q.strip_suffix('"').expect("a quoted text");
    let (needle, start) = match q.split_once("\" in \"") {
        Some((needle, context)) => {
            let c = find(context, 0);
            (needle, find(needle, c))
        }
        None => (q, find(q, 0)),
    };
    Span::new(FileId(0), header + start, header + start + needle.len())
}

#[test]
fn every_invalid_fixture_gives_its_code_at_the_expected_place() {
    // The syntax stage's fixtures are the BG01xx ones; later stages' fixtures parse cleanly by design.
    let files: Vec<_> = fixtures("invalid")
        .into_iter()
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(is_syntax_fixture)
        })
        .collect();
    assert!(files.len() >= 20, "only {} invalid fixtures", files.len());
    let mut codes_seen = std::collections::BTreeSet::new();
    for path in files {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("")
            .to_string();
        let code = name.get(..6).unwrap_or("");
        let bytes = std::fs::read(&path).unwrap_or_default();
        let text = String::from_utf8_lossy(&bytes);
        let expect_line = text.lines().nth(1).unwrap_or("");
        let rest = expect_line
            .strip_prefix("// expect: ")
            .unwrap_or_else(|| panic!("{name}: second line must be `// expect: ...`"));
        let (expect_code, where_) = rest.split_once(' ').unwrap_or((rest, ""));
        assert_eq!(
            expect_code, code,
            "{name}: the expect line names another code"
        );
        let want = expected_span(&bytes, where_);
        let diags = check(&bytes);
        let hit = diags.iter().find(|d| d.code.0 == code);
        let Some(hit) = hit else {
            panic!("{name}: no {code} among {diags:#?}");
        };
        let got = hit
            .primary_span()
            .unwrap_or_else(|| panic!("{name}: no primary label"));
        if where_.starts_with("at byte") {
            assert_eq!(got.start, want.start, "{name}: {hit:#?}");
        } else {
            assert_eq!(got, want, "{name}: {hit:#?}");
        }
        assert!(hit.help.is_some(), "{name}: no help line");
        // Exactly one diagnostic: recovery must not cascade into spurious errors.
        assert_eq!(diags.len(), 1, "{name}: {diags:#?}");
        codes_seen.insert(code.to_string());
    }
    for code in [
        "BG0100", "BG0101", "BG0102", "BG0103", "BG0104", "BG0105", "BG0106", "BG0109", "BG0110",
        "BG0111", "BG0112", "BG0113", "BG0114", "BG0115", "BG0116", "BG0117",
    ] {
        assert!(codes_seen.contains(code), "no fixture for {code}");
    }
}

#[test]
fn every_valid_fixture_parses_cleanly_and_is_canonical() {
    let files = fixtures("valid");
    assert!(files.len() >= 5);
    for path in files {
        let bytes = std::fs::read(&path).unwrap_or_default();
        let text =
            decode(FileId(0), &bytes).unwrap_or_else(|d| panic!("{}: {d:?}", path.display()));
        let (tree, diags) = parse(FileId(0), text);
        assert!(diags.is_empty(), "{}: {diags:#?}", path.display());
        assert_eq!(
            format(&tree),
            text,
            "{} is not in canonical layout",
            path.display()
        );
    }
}

/// The syntax stage's fixtures: BG01xx, except the import codes BG0107 and BG0108 that lowering reports.
fn is_syntax_fixture(name: &str) -> bool {
    name.starts_with("BG01") && !name.starts_with("BG0107") && !name.starts_with("BG0108")
}
