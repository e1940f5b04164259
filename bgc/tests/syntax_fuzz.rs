//! Property tests of the front end on hostile input: random bytes, and valid files mutated by deletions, insertions
//! and truncations. Decoding and parsing must never panic, every diagnostic must carry a primary label inside the
//! text, and whenever a mutated file still parses without errors the formatter must keep its meaning and be
//! idempotent.

use bgc::span::FileId;
use bgc::syntax::{decode, format, parse};
use proptest::prelude::*;
use serde_json::Value;
use std::path::Path;

/// The valid fixtures and the examples of the language reference, as seeds for mutation.
fn seeds() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    if let Ok(dir) = std::fs::read_dir(root.join("tests/fixtures/valid")) {
        for e in dir.flatten() {
            if let Ok(s) = std::fs::read_to_string(e.path()) {
                out.push(s);
            }
        }
    }
    let doc = std::fs::read_to_string(root.join("../docs/language.md")).unwrap_or_default();
    for block in doc.split("```bg\n").skip(1) {
        if let Some((code, _)) = block.split_once("```") {
            out.push(format!("model example {{\n{code}}}\n"));
        }
    }
    out.sort();
    out
}

/// The tree with spans and layout removed.
fn meaning(file: &bgc::syntax::ast::File) -> Value {
    fn strip(v: Value) -> Value {
        match v {
            Value::Object(map) => {
                if map.len() == 3 && map.contains_key("file") && map.contains_key("start") {
                    return Value::Null;
                }
                Value::Object(
                    map.into_iter()
                        .filter(|(k, _)| k != "blank_lines" && k != "own_line")
                        .map(|(k, v)| (k, strip(v)))
                        .collect(),
                )
            }
            Value::Array(items) => Value::Array(items.into_iter().map(strip).collect()),
            other => other,
        }
    }
    strip(serde_json::to_value(file).unwrap_or(Value::Null))
}

/// Decodes and parses; checks the diagnostics' labels; checks the formatter when the parse is clean.
fn check_bytes(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = match decode(FileId(0), bytes) {
        Ok(t) => t,
        Err(d) => {
            let s = d.primary_span();
            prop_assert!(
                s.is_some_and(|s| s.start <= s.end && (s.end as usize) <= bytes.len()),
                "{d:?}"
            );
            return Ok(());
        }
    };
    let (tree, diags) = parse(FileId(0), text);
    for d in &diags {
        let s = d.primary_span();
        prop_assert!(s.is_some(), "no primary label: {d:?}");
        for l in &d.labels {
            prop_assert!(
                l.span.start <= l.span.end && (l.span.end as usize) <= text.len(),
                "label out of bounds: {d:?}"
            );
            prop_assert!(
                text.is_char_boundary(l.span.start as usize)
                    && text.is_char_boundary(l.span.end as usize)
            );
        }
        prop_assert!(d.help.is_some(), "no help: {d:?}");
    }
    if !bgc::diagnostic::has_errors(&diags) {
        let once = format(&tree);
        let (tree2, diags2) = parse(FileId(0), &once);
        prop_assert!(
            !bgc::diagnostic::has_errors(&diags2),
            "formatted text has errors:\n{once}\n{diags2:?}"
        );
        prop_assert_eq!(
            meaning(&tree),
            meaning(&tree2),
            "meaning changed:\n{}\n---\n{}",
            text,
            once
        );
        prop_assert_eq!(format(&tree2), once);
    }
    Ok(())
}

#[derive(Clone, Debug)]
enum Mutation {
    Delete { at: usize, len: usize },
    Insert { at: usize, bytes: Vec<u8> },
    Truncate { at: usize },
}

/// Pieces that make plausible (and implausible) source text when inserted.
const PIECES: &[&str] = &[
    "(", ")", "{", "}", "[", "]", ";", ",", "->", "=", ":", ".", "-", "^", "!", "\"", "//", "///",
    "\n", " ", "model", "param", "bond", "stroke", "1e999", "1.2.3", "0", "1", "x", "e", "f(", "C",
    "µ", "#", "\r\n", "\u{0}",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1..20usize).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), prop::sample::select(PIECES)).prop_map(|(at, p)| Mutation::Insert {
            at,
            bytes: p.as_bytes().to_vec()
        }),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
    ]
}

fn apply(mut bytes: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let n = bytes.len();
        match m {
            Mutation::Delete { at, len } if n > 0 => {
                let a = at % n;
                let b = (a + len).min(n);
                bytes.drain(a..b);
            }
            Mutation::Insert { at, bytes: ins } => {
                let a = at % (n + 1);
                bytes.splice(a..a, ins.iter().copied());
            }
            Mutation::Truncate { at } => bytes.truncate(at % (n + 1)),
            _ => {}
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1024, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_crash(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        check_bytes(&bytes)?;
    }

    #[test]
    fn random_ascii_never_crashes(text in "[ -~\n]{0,512}") {
        check_bytes(text.as_bytes())?;
    }

    #[test]
    fn mutated_valid_files_never_crash(seed in any::<prop::sample::Index>(), muts in prop::collection::vec(mutation(), 1..6)) {
        let seeds = seeds();
        prop_assume!(!seeds.is_empty());
        let src = seeds[seed.index(seeds.len())].clone().into_bytes();
        check_bytes(&apply(src, &muts))?;
    }
}

#[test]
fn every_truncation_of_every_seed_is_handled() {
    for s in seeds() {
        for cut in 0..=s.len() {
            if s.is_char_boundary(cut)
                && let Err(e) = check_bytes(&s.as_bytes()[..cut])
            {
                panic!("truncation at {cut}: {e}");
            }
        }
    }
}

/// A comment inserted at any space or line break of a valid file keeps it valid, survives formatting (the formatter
/// may move it to the end of its statement's line, never drop it) and the formatted file is stable.
#[test]
fn a_comment_anywhere_is_kept_and_formatting_is_stable() {
    for s in seeds() {
        for (i, c) in s.char_indices() {
            if c != ' ' && c != '\n' {
                continue;
            }
            for comment in [" // note\n", "\n// note\n", " /// doc\n"] {
                let mut text = s.clone();
                text.insert_str(i, comment);
                if let Err(e) = check_bytes(text.as_bytes()) {
                    panic!("comment {comment:?} at {i}: {e}");
                }
                let (tree, diags) = parse(FileId(0), &text);
                if !bgc::diagnostic::has_errors(&diags) {
                    let out = format(&tree);
                    let want = s.matches("note").count() + 1;
                    let ordinary = comment.contains("note");
                    if ordinary {
                        assert_eq!(
                            out.matches("note").count(),
                            want,
                            "comment lost:\n{text}\n---\n{out}"
                        );
                    }
                }
            }
        }
    }
}
