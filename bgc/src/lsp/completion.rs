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
use lsp_types::{CompletionItem, CompletionItemKind};

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

/// The completions at a byte offset of the root file.
pub fn complete(analysis: &Analysis, offset: usize) -> Vec<CompletionItem> {
    let text = analysis.root_text();
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = &text[line_start..offset];
    let word_start = line
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_ascii_alphanumeric() || *c == '_')
        .last()
        .map_or(line.len(), |(i, _)| i);
    let before = &line[..word_start];
    if before.rfind('[') > before.rfind(']') {
        return units();
    }
    if let Some(qualifier) = before.strip_suffix('.') {
        return members(analysis, qualifier, line_start + word_start);
    }
    if before.trim().is_empty() {
        return statement_start(analysis);
    }
    in_scope(analysis, analysis.root, offset)
}

fn units() -> Vec<CompletionItem> {
    crate::units::symbols()
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
