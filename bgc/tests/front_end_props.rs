//! Property tests of the whole front end (decode → parse → lower → causality) on mutated models: nothing panics,
//! every diagnostic is located inside the file it names, and a model that fails always says where.

use bgc::diagnostic::{Diagnostic, has_errors};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::{FileId, SourceMap};
use proptest::prelude::*;
use std::path::Path;

/// Complete models to mutate: the exoskeleton models, the corpus and the valid fixtures.
pub(crate) fn seeds() -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for dir in ["../models", "tests/corpus", "tests/fixtures/valid"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut paths: Vec<_> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "bg"))
            .collect();
        paths.sort();
        for p in paths {
            if let Ok(b) = std::fs::read(&p) {
                out.push(b);
            }
        }
    }
    out
}

/// Runs the front end; returns the diagnostics and the source map they point into.
fn front_end(bytes: &[u8]) -> (SourceMap, Vec<Diagnostic>) {
    let mut sources = SourceMap::new();
    let text = match bgc::syntax::decode(FileId(0), bytes) {
        Ok(t) => t.to_string(),
        Err(d) => {
            sources.add("mutated.bg", String::from_utf8_lossy(bytes).into_owned());
            return (sources, vec![d]);
        }
    };
    let id = sources.add("mutated.bg", text);
    let (models, mut diags) = lower(&mut sources, id, &mut MemoryLoader::new());
    if !has_errors(&diags) {
        for m in &models {
            diags.extend(bgc::causality::analyse(m).1);
        }
    }
    (sources, diags)
}

fn check(bytes: &[u8]) -> Result<(), TestCaseError> {
    let (sources, diags) = front_end(bytes);
    for d in &diags {
        for label in &d.labels {
            let file = sources.get(label.span.file);
            prop_assert!(file.is_some(), "label in an unknown file: {d:?}");
            let len = file.map_or(0, |f| f.text.len());
            prop_assert!(
                label.span.start <= label.span.end && label.span.end as usize <= len,
                "label outside its file: {d:?}"
            );
        }
    }
    if has_errors(&diags) {
        prop_assert!(
            diags
                .iter()
                .any(|d| d.is_error() && d.primary_span().is_some()),
            "errors without a location: {diags:?}"
        );
    }
    Ok(())
}

#[derive(Clone, Debug)]
pub(crate) enum Mutation {
    Delete { at: usize, len: usize },
    Insert { at: usize, text: &'static str },
    Duplicate { at: usize, len: usize },
}

/// Pieces that make plausible mistakes: stray tokens, wrong units, dangling bonds, bad numbers.
const INSERTS: &[&str] = &[
    ";",
    "}",
    "{",
    "->",
    " bond x -> y;",
    "[N/m]",
    "[kg",
    "1e999",
    "-",
    "(",
    ")",
    " 0 j;",
    " I ",
    "\"",
    "/// doc\n",
    " stroke ",
    "sin(",
    "q(",
    ",",
    ".",
    "[1]",
    " param z = -1 [kg];",
];

pub(crate) fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), prop::sample::select(INSERTS))
            .prop_map(|(at, text)| Mutation::Insert { at, text }),
        (any::<usize>(), 1usize..80).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
    ]
}

pub(crate) fn apply(mut bytes: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let n = bytes.len().max(1);
        match *m {
            Mutation::Delete { at, len } => {
                let at = at % n;
                let end = (at + len).min(bytes.len());
                if at < end {
                    bytes.drain(at..end);
                }
            }
            Mutation::Insert { at, text } => {
                let at = at % (bytes.len() + 1);
                bytes.splice(at..at, text.bytes());
            }
            Mutation::Duplicate { at, len } => {
                let at = at % n;
                let end = (at + len).min(bytes.len());
                if at < end {
                    let piece: Vec<u8> = bytes[at..end].to_vec();
                    bytes.splice(end..end, piece);
                }
            }
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn mutated_models_never_crash_and_errors_are_located(
        seed in any::<prop::sample::Index>(),
        muts in prop::collection::vec(mutation(), 1..5),
    ) {
        let seeds = seeds();
        prop_assume!(!seeds.is_empty());
        let base = seeds[seed.index(seeds.len())].clone();
        check(&apply(base, &muts))?;
    }
}

#[test]
fn the_seeds_themselves_have_no_errors() {
    let seeds = seeds();
    assert!(seeds.len() >= 15, "only {} seed models", seeds.len());
    for s in &seeds {
        let (_, diags) = front_end(s);
        assert!(
            !has_errors(&diags),
            "{:?}\n{}",
            diags.first(),
            String::from_utf8_lossy(s)
        );
    }
}

/// `bgc fmt` on every .bg file of the repository that parses: idempotent, and the formatted file means the same
/// (the same error codes from the whole front end; the formatter may settle a warning, as it turns a doc comment
/// that documents nothing into a plain comment).
#[test]
fn formatting_is_idempotent_and_keeps_meaning_on_every_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut count = 0;
    for dir in [
        "../models",
        "tests/corpus",
        "tests/fixtures/valid",
        "tests/fixtures/invalid",
        "tests/fixtures/causality",
        "std",
    ] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            if path.extension().is_none_or(|x| x != "bg") {
                continue;
            }
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let Ok(once) = bgc::syntax::format_source(FileId(0), &text) else {
                continue;
            };
            let twice = bgc::syntax::format_source(FileId(0), &once).unwrap_or_else(|d| {
                panic!("{}: formatted text does not parse: {d:?}", path.display())
            });
            assert_eq!(once, twice, "{}: fmt is not idempotent", path.display());
            let codes = |t: &str| -> Vec<&'static str> {
                front_end(t.as_bytes())
                    .1
                    .iter()
                    .filter(|d| d.is_error())
                    .map(|d| d.code.0)
                    .collect()
            };
            assert_eq!(
                codes(&text),
                codes(&once),
                "{}: formatting changed the errors",
                path.display()
            );
            count += 1;
        }
    }
    assert!(count >= 60, "only {count} files formatted");
}

/// The shipped models are kept in the canonical layout, so `bgc fmt --check models/*.bg` stays clean.
#[test]
fn shipped_models_are_in_canonical_layout() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    let mut count = 0;
    for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let path = e.path();
        if path.extension().is_none_or(|x| x != "bg") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let formatted = bgc::syntax::format_source(FileId(0), &text)
            .unwrap_or_else(|d| panic!("{}: {d:?}", path.display()));
        assert_eq!(
            formatted,
            text,
            "{} is not in the canonical layout",
            path.display()
        );
        count += 1;
    }
    assert!(count >= 3, "only {count} models");
}
