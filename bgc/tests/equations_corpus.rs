//! The equations of models/back_support.bg and of every corpus model, from text: parse, lower, causality, derive.
//! Snapshots of the text and LaTeX forms keep the printed equations stable; the numeric checks of the
//! back-support model against the paper are in `equations_back_support.rs` (on a hand-built graph) and here (on the
//! model file).

use bgc::causality::analyse;
use bgc::diagnostic::Diagnostic;
use bgc::equations::{Equations, derive, to_latex, to_text};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use std::path::{Path, PathBuf};

/// The equations of the single model of a file, with the diagnostics of lowering, causality and derivation.
fn equations_of(path: &Path) -> (Equations, Vec<Diagnostic>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut sources = SourceMap::new();
    let root = sources.add(path.display().to_string(), text);
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{}: {diags:?}", path.display());
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    (eqs, diags)
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn back_support_file() {
    let (eqs, diags) = equations_of(&root().join("../models/back_support.bg"));
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    assert_eq!(eqs.energy_states, 6);
    insta::assert_snapshot!("file_back_support_text", to_text(&eqs));
    insta::assert_snapshot!("file_back_support_latex", to_latex(&eqs));
}

#[test]
fn corpus_models() {
    let dir = root().join("tests/corpus");
    let files = bg_files(&dir);
    assert!(files.len() >= 10, "corpus not found in {}", dir.display());
    for (name, path) in files {
        let (eqs, diags) = equations_of(&path);
        let errors = errors(&diags);
        let text = format!("{}\nerrors: {errors:#?}\n", to_text(&eqs));
        insta::assert_snapshot!(format!("corpus_{name}_text"), text);
        insta::assert_snapshot!(format!("corpus_{name}_latex"), to_latex(&eqs));
    }
}

/// Every other model of models/ (back_support has its own test above): text and LaTeX snapshots, no errors.
#[test]
fn model_files() {
    let dir = root().join("../models");
    let mut files = bg_files(&dir);
    files.retain(|(name, _)| name != "back_support");
    assert!(files.len() >= 3, "models not found in {}", dir.display());
    for (name, path) in files {
        let (eqs, diags) = equations_of(&path);
        let errors = errors(&diags);
        assert!(errors.is_empty(), "{name}: {errors:?}");
        insta::assert_snapshot!(format!("model_{name}_text"), to_text(&eqs));
        insta::assert_snapshot!(format!("model_{name}_latex"), to_latex(&eqs));
    }
}

/// The `.bg` files of a folder with their stems, sorted.
fn bg_files(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "bg"));
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("model");
            (stem.to_string(), p)
        })
        .collect()
}

fn errors(diags: &[Diagnostic]) -> Vec<String> {
    diags
        .iter()
        .filter(|d| d.is_error())
        .map(|d| format!("{}: {}", d.code.0, d.message))
        .collect()
}
