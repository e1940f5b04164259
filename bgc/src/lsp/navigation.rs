//! Go to definition, find references, rename and the document outline.
//!
//! References and rename look at every open document's analysis, so that a component's parameter renamed in its
//! library file is renamed in the models that import it too. A declaration is identified across analyses by its
//! file's name and the place of its name ([`SymbolKey`]).

use super::analysis::Analysis;
use super::diagnostics::Lines;
use super::files::source_uri;
use super::index::{Hit, SymbolKind};
use crate::lower::STD_DISPLAY_NAME;
use crate::span::{FileId, Span};
use crate::syntax::ast::Item;
use lsp_types::{DocumentSymbol, Location, TextEdit, Uri, WorkspaceEdit};
use std::collections::{HashMap, HashSet};

/// A declaration's identity in any analysis: the name of its file and the byte range of its name.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct SymbolKey {
    pub file: String,
    pub start: u32,
    pub end: u32,
}

/// The declaration named at an offset (by its declaration or a reference), with the span of the name there.
pub fn symbol_at(analysis: &Analysis, file: FileId, offset: usize) -> Option<(usize, Span)> {
    match analysis.index.at(file, offset)? {
        Hit::Symbol(id, span) => Some((id, span)),
        Hit::Unit(_) | Hit::Kind(..) => None,
    }
}

pub fn key(analysis: &Analysis, symbol: usize) -> Option<SymbolKey> {
    let s = analysis.index.symbols.get(symbol)?;
    let file = analysis.sources.get(s.name_span.file)?;
    Some(SymbolKey {
        file: file.name.clone(),
        start: s.name_span.start,
        end: s.name_span.end,
    })
}

/// The symbol of an analysis with this key.
fn find(analysis: &Analysis, key: &SymbolKey) -> Option<usize> {
    let file = analysis.file_named(&key.file)?;
    analysis.index.symbols.iter().position(|s| {
        s.name_span.file == file && s.name_span.start == key.start && s.name_span.end == key.end
    })
}

/// Where the name at an offset is declared; on an import, the start of the imported file.
pub fn definition(analysis: &Analysis, file: FileId, offset: usize) -> Option<Location> {
    if let Some(location) = imported_file(analysis, file, offset) {
        return Some(location);
    }
    let (id, _) = symbol_at(analysis, file, offset)?;
    let s = analysis.index.symbols.get(id)?;
    Lines::new(analysis).location(s.name_span)
}

/// The file an import at the offset loaded (the standard library for `"std.bg"`).
fn imported_file(analysis: &Analysis, file: FileId, offset: usize) -> Option<Location> {
    let (_, tree) = analysis.files.iter().find(|(id, _)| *id == file)?;
    let import = tree.items.iter().find_map(|item| match item {
        Item::Import(imp)
            if (imp.span.start as usize) <= offset && offset <= imp.span.end as usize =>
        {
            Some(imp)
        }
        _ => None,
    })?;
    let wanted = if import.path == crate::lower::STD_NAME {
        STD_DISPLAY_NAME.to_string()
    } else {
        let importer = analysis.sources.get(file)?.name.clone();
        let dir = std::path::Path::new(&importer).parent()?.to_path_buf();
        crate::lower::normalize(&dir.join(&import.path))
            .display()
            .to_string()
    };
    let target = analysis.sources.files().find(|(_, f)| f.name == wanted)?;
    Some(Location::new(
        source_uri(&target.1.name)?,
        lsp_types::Range::default(),
    ))
}

/// The spans naming the declaration in one analysis: its declaration (when asked for) and every reference.
fn spans_of(analysis: &Analysis, key: &SymbolKey, declaration: bool) -> Vec<Span> {
    let Some(id) = find(analysis, key) else {
        return Vec::new();
    };
    let mut spans: Vec<Span> = analysis.index.references_to(id).collect();
    if declaration && let Some(s) = analysis.index.symbols.get(id) {
        spans.push(s.name_span);
    }
    spans
}

/// Every place that names the declaration, over all analyses, each once, sorted by file and position.
pub fn references(analyses: &[&Analysis], key: &SymbolKey, declaration: bool) -> Vec<Location> {
    // A set, not a list: a parameter of a generated model has a reference per element (100,000 of them), and a
    // list's `contains` made that quadratic (10 s).
    let mut seen: HashSet<(&str, u32, u32)> = HashSet::new();
    let mut out = Vec::new();
    for &analysis in analyses {
        let lines = Lines::new(analysis);
        for span in spans_of(analysis, key, declaration) {
            let Some(name) = analysis.sources.get(span.file).map(|f| f.name.as_str()) else {
                continue;
            };
            if !seen.insert((name, span.start, span.end)) {
                continue;
            }
            if let Some(location) = lines.location(span) {
                out.push(location);
            }
        }
    }
    out.sort_by(|a, b| {
        (a.uri.as_str(), a.range.start.line, a.range.start.character).cmp(&(
            b.uri.as_str(),
            b.range.start.line,
            b.range.start.character,
        ))
    });
    out
}

/// Why a new name cannot be used, if it cannot.
pub fn check_new_name(name: &str) -> Result<(), String> {
    let mut chars = name.chars();
    let starts = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !starts || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        // `τ_m`: the spelling the compiler proposes for it.
        let ascii = crate::syntax::foreign::ascii_spelling(name)
            .filter(|a| a != name && check_new_name(a).is_ok())
            .map(|a| format!(" (write `{a}`)"))
            .unwrap_or_default();
        return Err(format!(
            "`{name}` is not a name: a name is an ASCII letter or `_` followed by ASCII letters, digits and `_`{ascii}"
        ));
    }
    if crate::syntax::KEYWORDS.contains(&name) || matches!(name, "t" | "pi") {
        return Err(format!("`{name}` is reserved by the language"));
    }
    // Ordinary names with a meaning of their own in some places: a parameter renamed `f` would read as the
    // element's own flow in a law block, `mass` as an inertia matrix entry in an I-field.
    if matches!(name, "e" | "f" | "p" | "q" | "int" | "mass") {
        return Err(format!(
            "`{name}` has a meaning of its own in some places (`e`, `f`, `p`, `q` in a law and as functions, `int` \
             in a `var`, `mass` in an I-field): renamed to it, a name could change what the model says"
        ));
    }
    Ok(())
}

/// The edits that rename the declaration and every reference to it, over all analyses.
// `WorkspaceEdit` keys its changes by `Uri`, whose parsed form caches offsets in cells; they are never changed
// after parsing, so the hash cannot change under the map.
#[allow(clippy::mutable_key_type)]
pub fn rename(
    analyses: &[&Analysis],
    key: &SymbolKey,
    new_name: &str,
) -> Result<WorkspaceEdit, String> {
    check_new_name(new_name)?;
    if key.file == STD_DISPLAY_NAME {
        return Err("names of the standard library cannot be renamed".to_string());
    }
    for analysis in analyses {
        if let Some(id) = find(analysis, key) {
            clash(analysis, id, new_name)?;
        }
    }
    let mut changes: HashMap<Uri, Vec<TextEdit>> = HashMap::new();
    for location in references(analyses, key, true) {
        changes
            .entry(location.uri)
            .or_default()
            .push(TextEdit::new(location.range, new_name.to_string()));
    }
    Ok(WorkspaceEdit::new(changes))
}

/// A declaration of the new name in the same scope would make the program mean something else.
fn clash(analysis: &Analysis, id: usize, new_name: &str) -> Result<(), String> {
    let index = &analysis.index;
    let Some(s) = index.symbols.get(id) else {
        return Ok(());
    };
    let taken = match s.parent {
        Some(parent) => index.members(parent).any(|(_, m)| m.name == new_name),
        None => index.global(new_name).is_some(),
    };
    if taken && s.name != new_name {
        return Err(format!(
            "`{new_name}` is already declared in the same scope"
        ));
    }
    Ok(())
}

/// The outline of the root file: its models and components with their declarations.
pub fn document_symbols(analysis: &Analysis) -> Vec<DocumentSymbol> {
    let lines = Lines::new(analysis);
    let index = &analysis.index;
    let symbol = |id: usize, children: Option<Vec<DocumentSymbol>>| {
        let s = &index.symbols[id];
        #[allow(deprecated)]
        DocumentSymbol {
            name: s.name.clone(),
            detail: Some(match s.kind {
                SymbolKind::Element => s.detail.clone(),
                SymbolKind::Instance => format!("{} instance", s.detail),
                k => k.noun().to_string(),
            }),
            kind: lsp_kind(s.kind),
            tags: None,
            deprecated: None,
            range: lines.range(s.decl_span),
            selection_range: lines.range(s.name_span),
            children,
        }
    };
    index
        .symbols
        .iter()
        .enumerate()
        .filter(|(_, s)| s.parent.is_none() && s.name_span.file == analysis.root)
        .map(|(id, _)| {
            let children = index.members(id).map(|(m, _)| symbol(m, None)).collect();
            symbol(id, Some(children))
        })
        .collect()
}

fn lsp_kind(kind: SymbolKind) -> lsp_types::SymbolKind {
    use lsp_types::SymbolKind as K;
    match kind {
        SymbolKind::Model => K::CLASS,
        SymbolKind::Component => K::STRUCT,
        SymbolKind::Param => K::CONSTANT,
        SymbolKind::Input => K::FIELD,
        SymbolKind::Output => K::PROPERTY,
        SymbolKind::Var => K::VARIABLE,
        SymbolKind::Element => K::OBJECT,
        SymbolKind::Instance => K::MODULE,
        SymbolKind::Port => K::INTERFACE,
    }
}

/// The URI of the file a span lies in.
pub fn span_uri(analysis: &Analysis, span: Span) -> Option<Uri> {
    source_uri(&analysis.sources.get(span.file)?.name)
}
