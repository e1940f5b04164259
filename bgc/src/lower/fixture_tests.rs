//! The invalid fixtures of `bgc/tests/fixtures/invalid/` for the lowering stage's codes (BG02xx-BG04xx): each file
//! gives exactly one diagnostic, of the code its name starts with, with the primary label where its second line says.

use super::tests::lower_text;
use crate::diagnostic::Severity;
use std::path::PathBuf;

/// One fixture's expectation, in the fixtures' shared format: `// expect: CODE at "TEXT"` (the first occurrence of
/// TEXT after the two header lines) or `// expect: CODE at "TEXT" in "CONTEXT"` (TEXT inside the first occurrence of
/// CONTEXT). Returns the code and the expected byte range.
fn fixture_expectation(text: &str) -> Option<(String, std::ops::Range<usize>)> {
    let line = text.lines().nth(1)?.strip_prefix("// expect: ")?;
    let (code, rest) = line.split_once(" at \"")?;
    let quoted = rest.strip_suffix('"')?;
    let header = text.match_indices('\n').nth(1).map(|(i, _)| i + 1)?;
    let body = &text[header..];
    let (needle, from) = match quoted.split_once("\" in \"") {
        Some((needle, context)) => (needle, body.find(context)?),
        None => (quoted, 0),
    };
    let start = header + from + body[from..].find(needle)?;
    Some((code.to_string(), start..start + needle.len()))
}

#[test]
fn invalid_fixtures_report_their_code_at_their_place() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/invalid");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    paths.sort();
    let mut checked = Vec::new();
    let mut failures = Vec::new();
    for path in paths {
        let file = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("")
            .to_string();
        if !["BG02", "BG03", "BG04"].iter().any(|p| file.starts_with(p)) {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let Some((code, want)) = fixture_expectation(&text) else {
            panic!("{file}: no valid `// expect:` line");
        };
        assert!(file.starts_with(&code), "{file} expects {code}");
        let (_, diags, sources) = lower_text(&text);
        let rendered = crate::diagnostic::render::to_text(&sources, &diags, false);
        // Exactly the expected diagnostic, nothing else.
        let ok = match &diags[..] {
            [d] => {
                let span = d.primary_span().unwrap_or_default();
                let warning = matches!(code.as_str(), "BG0308" | "BG0402");
                d.code.0 == code
                    && span.range() == want
                    && d.help.is_some()
                    && (d.severity == Severity::Warning) == warning
            }
            _ => false,
        };
        if !ok {
            failures.push(format!("{file}: expected {code} at {want:?}:\n{rendered}"));
        }
        checked.push(code);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    checked.dedup();
    let expected = [
        "BG0201", "BG0202", "BG0203", "BG0204", "BG0205", "BG0206", "BG0207", "BG0208", "BG0301",
        "BG0302", "BG0303", "BG0304", "BG0305", "BG0306", "BG0307", "BG0308", "BG0309", "BG0310",
        "BG0311", "BG0312", "BG0313", "BG0314", "BG0401", "BG0402", "BG0403",
    ];
    assert_eq!(checked, expected);
}
