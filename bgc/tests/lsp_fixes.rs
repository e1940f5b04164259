//! Quick fixes that are certain: characters pasted from a document (`·`, `²`, `→`, `“…”`, a no-break space), names
//! in Greek letters, and units and operators as other tools write them, each replaced by what bgc writes. Applied
//! together, they leave a model without errors.

use crate::lsp_support;

use lsp_support::{Client, apply, range, unsaved, uri};
use lsp_types::request::CodeActionRequest;
use lsp_types::{CodeActionOrCommand, TextDocumentIdentifier};

const PASTED: &str = "model a {\n    domain rotational;\n    param J = 2 × 1 [kg·m²] “inertia”;\n    \
                      param k = 3 [N·m·rad⁻¹];\n    param τ_m = 1 [N m];\n    Se s = −τ_m;\n    I i = J·k/k;\n    \
                      C c = 1/k;\n    1\u{a0}j;\n    bond s → j -> i, c;\n}\n";

/// Opens `text` as `name`, checks that it has `errors` diagnostics, asks for the code actions of the whole file,
/// applies every edit they carry, and checks that the result has no diagnostic. Returns the actions' titles and
/// the fixed text.
fn apply_every_fix(name: &str, text: &str, errors: usize) -> (Vec<String>, String) {
    let mut client = Client::start();
    let doc = uri(&unsaved(name));
    client.open(&doc, text);
    let found = client.diagnostics(&doc, 1);
    assert_eq!(found.len(), errors, "{found:#?}");
    let lines = text.lines().count() as u32;
    let actions = client
        .request::<CodeActionRequest>(lsp_types::CodeActionParams {
            text_document: TextDocumentIdentifier::new(doc.clone()),
            range: range(0, 0, lines, 0),
            context: Default::default(),
            work_done_progress_params: Default::default(),
            partial_result_params: Default::default(),
        })
        .expect("code actions answer")
        .unwrap_or_default();
    let mut edits = Vec::new();
    let mut titles = Vec::new();
    for action in &actions {
        let CodeActionOrCommand::CodeAction(fix) = action else {
            panic!("a code action")
        };
        titles.push(fix.title.clone());
        if let Some(changes) = fix.edit.as_ref().and_then(|e| e.changes.as_ref()) {
            edits.extend(changes[&doc].iter().cloned());
        }
    }
    let fixed = apply(text, &edits);
    client.change(
        &doc,
        2,
        vec![lsp_types::TextDocumentContentChangeEvent {
            range: None,
            range_length: None,
            text: fixed.clone(),
        }],
    );
    let left = client.diagnostics(&doc, 2);
    assert!(left.is_empty(), "{fixed}\n{left:#?}");
    assert_eq!(client.shutdown(), bgc::lsp::Ended::Shutdown);
    (titles, fixed)
}

#[test]
fn the_fixes_of_pasted_characters_and_greek_names_leave_no_error() {
    let (titles, fixed) = apply_every_fix("pasted.bg", PASTED, 13);
    assert_eq!(titles.len(), 13, "{titles:#?}");
    assert!(titles.contains(&"Replace `τ_m` with `tau_m`".to_string()));
    assert!(titles.contains(&"Replace `⁻¹` with `^-1`".to_string()));
    assert_eq!(
        fixed,
        "model a {\n    domain rotational;\n    param J = 2 * 1 [kg m^2] \"inertia\";\n    \
         param k = 3 [N m rad^-1];\n    param tau_m = 1 [N m];\n    Se s = -tau_m;\n    I i = J*k/k;\n    \
         C c = 1/k;\n    1 j;\n    bond s -> j -> i, c;\n}\n"
    );
}

/// Units and operators as other tools write them (`[N*m]`, `[N-m]`, `[s-1]`, `[-]`, `.^`, `PI`): each error's fix is
/// certain, and applied together they leave a model without errors.
#[test]
fn the_fixes_of_other_tools_spellings_leave_no_error() {
    const WRITTEN: &str = "model b {\n    domain rotational;\n    param J = 2 [kg*m^2];\n    \
                           param k = 3 [N-m/rad];\n    param w = 2*PI [s-1];\n    param r = 0.5 [-];\n    \
                           Se s = 1;\n    I i = J.*r.^2;\n    C c = 1/k;\n    output y [1] = w/w;\n    \
                           1 j;\n    bond s -> j -> i, c;\n}\n";
    let (titles, fixed) = apply_every_fix("other_tools.bg", WRITTEN, 7);
    assert!(titles.contains(&"Remove `.`".to_string()), "{titles:#?}");
    assert_eq!(
        fixed,
        "model b {\n    domain rotational;\n    param J = 2 [kg m^2];\n    param k = 3 [N m/rad];\n    \
         param w = 2*pi [s^-1];\n    param r = 0.5 [1];\n    Se s = 1;\n    I i = J*r^2;\n    C c = 1/k;\n    \
         output y [1] = w/w;\n    1 j;\n    bond s -> j -> i, c;\n}\n"
    );
}
