//! Completion: what may be written at the cursor, from the text of its line and the index of names.
//!
//! - inside a unit's brackets: unit symbols;
//! - after `inst.`: what the instance's component declares (ports, elements, instances);
//! - at the start of a statement: keywords, element kinds and the components that can be instantiated;
//! - elsewhere: the names of the enclosing model (parameters, inputs, outputs, vars, elements, instances) and
//!   the functions, `t` and `pi`.

use super::analysis::Analysis;
use super::index::SymbolKind;
use crate::ir::Func;
use crate::span::FileId;
use crate::syntax::ast::ElementKind;
use lsp_types::{CompletionItem, CompletionItemKind, CompletionList, CompletionResponse};

const STATEMENT_KEYWORDS: [&str; 12] = [
    "model",
    "component",
    "import",
    "param",
    "input",
    "output",
    "var",
    "bond",
    "port",
    "domain",
    "coords",
    "allow",
];

const KINDS: [ElementKind; 16] = [
    ElementKind::Se,
    ElementKind::Sf,
    ElementKind::MSe,
    ElementKind::MSf,
    ElementKind::C,
    ElementKind::I,
    ElementKind::R,
    ElementKind::TF,
    ElementKind::GY,
    ElementKind::MTF,
    ElementKind::MGY,
    ElementKind::Zero,
    ElementKind::One,
    ElementKind::CF,
    ElementKind::RF,
    ElementKind::IF,
];

fn item(label: &str, kind: CompletionItemKind, detail: String) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail: Some(detail),
        ..CompletionItem::default()
    }
}

/// The most completions one answer holds. A generated model has hundreds of thousands of names in scope: all of
/// them made a 28 MB answer to every keystroke. Past this many, the answer holds those that start with the word
/// being typed (ignoring case), up to this many, and says it is incomplete, so the editor asks again as the word
/// grows; below it, the editor gets everything and filters as it likes (fuzzily).
pub const MAX_ITEMS: usize = 1000;

/// The answer to a completion request at a byte offset of the root file: [`complete`], cut to [`MAX_ITEMS`].
pub fn respond(analysis: &Analysis, offset: usize) -> CompletionResponse {
    let items = complete(analysis, offset);
    if items.len() <= MAX_ITEMS {
        return CompletionResponse::Array(items);
    }
    let text = analysis.root_text();
    let word = text[typed_word(text, offset)].to_ascii_lowercase();
    let items = items
        .into_iter()
        .filter(|i| i.label.to_ascii_lowercase().starts_with(&word))
        .take(MAX_ITEMS)
        .collect();
    CompletionResponse::List(CompletionList {
        is_incomplete: true,
        items,
    })
}

/// The name being typed at `offset` (moved back to a character boundary): the ASCII letters, digits and `_`
/// before it.
fn typed_word(text: &str, offset: usize) -> std::ops::Range<usize> {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let len = text[..end]
        .bytes()
        .rev()
        .take_while(|b| b.is_ascii_alphanumeric() || *b == b'_')
        .count();
    end - len..end
}

/// The completions at a byte offset of the root file.
pub fn complete(analysis: &Analysis, offset: usize) -> Vec<CompletionItem> {
    let text = analysis.root_text();
    let word = typed_word(text, offset);
    let line_start = text[..word.start].rfind('\n').map_or(0, |i| i + 1);
    let before = &text[line_start..word.start];
    if before.rfind('[') > before.rfind(']') {
        return units();
    }
    if let Some(qualifier) = before.strip_suffix('.') {
        return members(analysis, qualifier, word.start);
    }
    if before.trim().is_empty() {
        return statement_start(analysis);
    }
    in_scope(analysis, analysis.root, word.end)
}

/// The unit symbols a file may write: `Ω` is known (to say what to write instead) but is not ASCII (`BG0104`).
fn units() -> Vec<CompletionItem> {
    crate::units::symbols()
        .filter(|(s, _)| s.is_ascii())
        .map(|(s, u)| item(s, CompletionItemKind::UNIT, format!("{u} (SI)")))
        .collect()
}

fn statement_start(analysis: &Analysis) -> Vec<CompletionItem> {
    let mut out: Vec<CompletionItem> = STATEMENT_KEYWORDS
        .iter()
        .map(|k| item(k, CompletionItemKind::KEYWORD, "keyword".into()))
        .collect();
    out.extend(KINDS.iter().map(|k| {
        item(
            k.keyword(),
            CompletionItemKind::KEYWORD,
            super::hover::kind_meaning(*k).to_string(),
        )
    }));
    out.extend(
        analysis
            .index
            .symbols
            .iter()
            .filter(|s| s.kind == SymbolKind::Component)
            .map(|s| item(&s.name, CompletionItemKind::CLASS, "component".into())),
    );
    out
}

/// What `a.b.` opens: the members of the component of the last instance of the path.
fn members(analysis: &Analysis, qualifier: &str, at: usize) -> Vec<CompletionItem> {
    let path: String = qualifier
        .chars()
        .rev()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '.')
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    let index = &analysis.index;
    let Some(mut scope) = index.enclosing(analysis.root, at) else {
        return Vec::new();
    };
    for part in path.split('.') {
        let instance = index
            .members(scope)
            .find(|(_, s)| s.name == part && s.kind == SymbolKind::Instance);
        match instance.and_then(|(_, s)| index.global(&s.detail)) {
            Some(component) => scope = component,
            None => return Vec::new(),
        }
    }
    index
        .members(scope)
        .filter(|(_, s)| {
            matches!(
                s.kind,
                SymbolKind::Port | SymbolKind::Element | SymbolKind::Instance
            )
        })
        .map(|(_, s)| item(&s.name, completion_kind(s.kind), s.kind.noun().to_string()))
        .collect()
}

fn in_scope(analysis: &Analysis, file: FileId, offset: usize) -> Vec<CompletionItem> {
    let index = &analysis.index;
    let mut out: Vec<CompletionItem> = match index.enclosing(file, offset) {
        Some(model) => index
            .members(model)
            .map(|(_, s)| {
                let detail = match &s.description {
                    Some(d) => format!("{}: {d}", s.kind.noun()),
                    None => s.kind.noun().to_string(),
                };
                item(&s.name, completion_kind(s.kind), detail)
            })
            .collect(),
        None => Vec::new(),
    };
    out.extend(Func::ALL.iter().map(|f| {
        item(
            f.name(),
            CompletionItemKind::FUNCTION,
            format!("function of {} argument(s)", f.arity()),
        )
    }));
    for (name, what) in [
        ("t", "time [s]"),
        ("pi", "π"),
        ("e", "effort of a node: e(x)"),
        ("f", "flow of a node: f(x)"),
        ("p", "momentum of an inertia: p(x)"),
        ("q", "displacement of a compliance: q(x)"),
        ("int", "integral of a flow (in `var`)"),
    ] {
        out.push(item(name, CompletionItemKind::KEYWORD, what.to_string()));
    }
    out
}

fn completion_kind(kind: SymbolKind) -> CompletionItemKind {
    match kind {
        SymbolKind::Model | SymbolKind::Component => CompletionItemKind::CLASS,
        SymbolKind::Param => CompletionItemKind::CONSTANT,
        SymbolKind::Input | SymbolKind::Output | SymbolKind::Var => CompletionItemKind::VARIABLE,
        SymbolKind::Element | SymbolKind::Instance => CompletionItemKind::VALUE,
        SymbolKind::Port => CompletionItemKind::INTERFACE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(response: CompletionResponse) -> (bool, Vec<String>) {
        match response {
            CompletionResponse::Array(items) => {
                (false, items.into_iter().map(|i| i.label).collect())
            }
            CompletionResponse::List(list) => (
                list.is_incomplete,
                list.items.into_iter().map(|i| i.label).collect(),
            ),
        }
    }

    #[test]
    fn a_model_with_more_names_than_an_answer_holds_gets_those_of_the_typed_word() {
        let mut text = String::from(
            "model m {\n    domain electrical;\n    Se s = 1;\n    1 j;\n    bond s -> j;\n",
        );
        for k in 0..3 * MAX_ITEMS {
            text.push_str(&format!("    R r{k} = 1;\n    bond j -> r{k};\n"));
        }
        text.push_str("    output y [V] = e(R2);\n}\n");
        let analysis = crate::lsp::analysis::analyse_front(
            "m.bg",
            &text,
            &mut crate::lower::MemoryLoader::new(),
        );
        let at = |needle: &str| text.find(needle).map(|i| i + needle.len()).unwrap_or(0);
        // After `e(R2`: the names starting with `r2` (ignoring case), all 1,111 of them but cut to the limit.
        let (incomplete, found) = labels(respond(&analysis, at("e(R2")));
        assert!(incomplete);
        assert_eq!(found.len(), MAX_ITEMS);
        assert!(found.iter().all(|l| l.starts_with("r2")), "{found:?}");
        // After `e(R2`'s `e(`: nothing typed yet, the first MAX_ITEMS names.
        let (incomplete, found) = labels(respond(&analysis, at("e(")));
        assert!(incomplete && found.len() == MAX_ITEMS);
        // A small model gets its whole list, for the editor to filter.
        let small = "model m {\n    domain electrical;\n    Se s = 1;\n    R r = 2;\n    bond s -> r;\n    output y [V] = e(r);\n}\n";
        let analysis = crate::lsp::analysis::analyse_front(
            "s.bg",
            small,
            &mut crate::lower::MemoryLoader::new(),
        );
        let (incomplete, found) = labels(respond(&analysis, small.find("e(r").unwrap_or(0) + 2));
        assert!(
            !incomplete && found.iter().any(|l| l == "r") && found.iter().any(|l| l == "sin"),
            "{found:?}"
        );
    }
}
