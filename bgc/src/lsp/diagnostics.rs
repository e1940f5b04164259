//! bgc's diagnostics as the protocol's: ranges in UTF-16 positions, the stable code, the notes and the help in
//! the message, secondary labels as related locations.
//!
//! A document's diagnostics are those of its own analysis. A finding located in a file it imports (an error in a
//! component it instantiates, say) is shown at the first import of the document, with its own place as related
//! information, so that nothing the compiler found is hidden.

use super::analysis::Analysis;
use super::files::source_uri;
use super::lines::LineIndex;
use crate::diagnostic::{Diagnostic, Severity};
use crate::span::Span;
use crate::syntax::ast::Item;
use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString, Range,
};

/// Line indexes of the files of an analysis, built once.
pub struct Lines<'a> {
    analysis: &'a Analysis,
    indexes: Vec<LineIndex>,
}

impl<'a> Lines<'a> {
    pub fn new(analysis: &'a Analysis) -> Lines<'a> {
        let indexes = analysis
            .sources
            .files()
            .map(|(_, f)| LineIndex::new(&f.text))
            .collect();
        Lines { analysis, indexes }
    }

    /// The range of a span in its file.
    pub fn range(&self, span: Span) -> Range {
        let text = self
            .analysis
            .sources
            .get(span.file)
            .map(|f| f.text.as_str())
            .unwrap_or("");
        match self.indexes.get(span.file.0 as usize) {
            Some(index) => index.range(text, span.range()),
            None => Range::default(),
        }
    }

    /// The location of a span (its file's URI and range).
    pub fn location(&self, span: Span) -> Option<Location> {
        let file = self.analysis.sources.get(span.file)?;
        Some(Location::new(source_uri(&file.name)?, self.range(span)))
    }
}

/// The protocol's diagnostics of the analysis's root document.
pub fn document_diagnostics(analysis: &Analysis) -> Vec<lsp_types::Diagnostic> {
    let lines = Lines::new(analysis);
    analysis
        .diagnostics
        .iter()
        .map(|d| convert(analysis, &lines, d))
        .collect()
}

fn convert(analysis: &Analysis, lines: &Lines, d: &Diagnostic) -> lsp_types::Diagnostic {
    let primary = d.primary_span();
    let mut related: Vec<DiagnosticRelatedInformation> = Vec::new();
    let mut message = d.message.clone();
    let range = match primary {
        Some(span) if span.file == analysis.root => lines.range(span),
        Some(span) => {
            // Elsewhere: at the first import, with the real place as related information.
            if let Some(location) = lines.location(span) {
                let label = d
                    .labels
                    .iter()
                    .find(|l| l.primary)
                    .map(|l| l.message.clone());
                related.push(DiagnosticRelatedInformation {
                    location,
                    message: label.unwrap_or_else(|| d.message.clone()),
                });
            }
            let name = analysis
                .sources
                .get(span.file)
                .map(|f| f.name.as_str())
                .unwrap_or("?");
            message = format!("in `{name}`: {message}");
            first_import(analysis)
                .map(|s| lines.range(s))
                .unwrap_or_default()
        }
        None => Range::default(),
    };
    for label in d.labels.iter().filter(|l| !l.primary) {
        if let Some(location) = lines.location(label.span) {
            related.push(DiagnosticRelatedInformation {
                location,
                message: label.message.clone(),
            });
        }
    }
    for note in &d.notes {
        message.push_str(&format!("\nnote: {note}"));
    }
    if let Some(help) = &d.help {
        message.push_str(&format!("\nhelp: {help}"));
    }
    lsp_types::Diagnostic {
        range,
        severity: Some(severity(d.severity)),
        code: Some(NumberOrString::String(d.code.0.to_string())),
        code_description: None,
        source: Some("bgc".to_string()),
        message,
        related_information: (!related.is_empty()).then_some(related),
        tags: None,
        data: None,
    }
}

pub fn severity(s: Severity) -> DiagnosticSeverity {
    match s {
        Severity::Error => DiagnosticSeverity::ERROR,
        Severity::Warning => DiagnosticSeverity::WARNING,
        Severity::Note => DiagnosticSeverity::INFORMATION,
    }
}

fn first_import(analysis: &Analysis) -> Option<Span> {
    let (_, root) = analysis.files.iter().find(|(id, _)| *id == analysis.root)?;
    root.items.iter().find_map(|i| match i {
        Item::Import(imp) => Some(imp.span),
        Item::Model(_) => None,
    })
}

/// The files of the analysis other than the root (for the documents whose analyses depend on a file).
pub fn imported_names(analysis: &Analysis) -> impl Iterator<Item = &str> {
    analysis
        .sources
        .files()
        .filter(move |(id, _)| *id != analysis.root)
        .map(|(_, f)| f.name.as_str())
}
