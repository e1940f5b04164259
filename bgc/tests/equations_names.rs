//! Every name the equations stage prints or generates identifies one quantity: element `s_spring` and instance
//! element `s.spring` both sanitize to `s_spring`, and a `var` may be named like a derived state (`p_mass`). The
//! fixture `fixtures/names/colliding_names.bg` has both; its states, intermediates and outputs must have distinct
//! names, the user's own names (`var`s, top-level elements) keep theirs, and the generated code's `STATE_NAMES`
//! follows.

use bgc::causality::analyse;
use bgc::equations::{Equations, derive};
use bgc::ir::Model;
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use std::collections::HashSet;
use std::path::Path;

fn equations() -> (Model, Equations) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/names/colliding_names.bg");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut sources = SourceMap::new();
    let root = sources.add("colliding_names.bg", text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(!bgc::diagnostic::has_errors(&diags), "{diags:?}");
    let (causality, _) = analyse(&models[0]);
    let (eqs, diags) = derive(&models[0], &causality);
    assert!(!bgc::diagnostic::has_errors(&diags), "{diags:?}");
    (models[0].clone(), eqs)
}

#[test]
fn states_of_colliding_elements_get_distinct_names() {
    let (model, eqs) = equations();
    let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
    let unique: HashSet<&str> = names.iter().copied().collect();
    assert_eq!(unique.len(), names.len(), "state names {names:?}");
    // The user's names keep theirs: the var `p_mass`, the model's own element `s_spring` (declared after the
    // instance `s`, whose element `s.spring` takes the suffix).
    let var = eqs
        .states
        .iter()
        .find(|s| s.var.is_some())
        .map(|s| s.name.as_str());
    assert_eq!(var, Some("p_mass"));
    let mut storage: Vec<&str> = eqs
        .states
        .iter()
        .filter(|s| s.var.is_none())
        .map(|s| s.name.as_str())
        .collect();
    storage.sort();
    assert_eq!(storage, ["p_mass_2", "q_s_spring", "q_s_spring_2"]);
    let element_of = |state: &str| {
        let s = eqs.states.iter().find(|s| s.name == state);
        s.and_then(|s| s.node).map(|n| model.graph[n].name.clone())
    };
    assert_eq!(element_of("q_s_spring").as_deref(), Some("s_spring"));
    assert_eq!(element_of("q_s_spring_2").as_deref(), Some("s.spring"));
}

#[test]
fn intermediates_do_not_reuse_a_printed_name() {
    let (_, eqs) = equations();
    let mut seen = HashSet::new();
    let printed = eqs
        .params
        .iter()
        .map(|p| p.0.clone())
        .chain(eqs.inputs.iter().cloned())
        .chain(eqs.states.iter().map(|s| s.name.clone()))
        .chain(eqs.intermediates.iter().map(|i| i.name.clone()))
        .chain(eqs.outputs.iter().map(|o| o.name.clone()));
    for name in printed {
        assert!(seen.insert(name.clone()), "`{name}` names two quantities");
    }
}

#[test]
fn generated_state_names_are_distinct() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/names/colliding_names.bg");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut sources = SourceMap::new();
    let root = sources.add("colliding_names.bg", text);
    let file = bgc::codegen::compile(&mut sources, root, &mut MemoryLoader::new())
        .unwrap_or_else(|d| panic!("{d:?}"));
    let code = bgc::codegen::rust::generate(&file, "colliding_names.bg");
    let names = code
        .lines()
        .find(|l| l.starts_with("pub const STATE_NAMES"))
        .unwrap_or_default();
    for name in [
        "\"q_s_spring\"",
        "\"q_s_spring_2\"",
        "\"p_mass\"",
        "\"p_mass_2\"",
    ] {
        assert!(names.contains(name), "{name} missing from {names}");
    }
}
