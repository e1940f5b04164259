//! The one diagnostic type of bgc, shared by every stage.
//!
//! A stage returns its findings as `Vec<Diagnostic>`; nothing here prints. Rendering to text (rustc-like, with
//! `FILE:LINE:COL` and the source excerpt) and to JSON lives in [`render`].

mod excerpt;
pub mod render;
pub mod suggest;
pub mod unprintable;

use crate::span::Span;
use serde::Serialize;

/// A number as a message shows it: as Rust writes it (`2`, `-0.5`, `1200`) where that is short, in exponent
/// form outside `[1e-5, 1e16)` (`1e-320`, which Rust writes as `0.000…01` with 320 digits).
pub fn number(v: f64) -> String {
    let magnitude = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-5..1e16).contains(&magnitude) {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Note,
    Warning,
    Error,
}

/// A stable diagnostic code such as `BG0201`. The list of codes is in docs/language.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct Code(pub &'static str);

#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Label {
    pub span: Span,
    pub message: String,
    /// The primary label marks the offending place; secondary labels explain it.
    pub primary: bool,
    /// The text that replaces the label's span to fix the diagnostic, when the fix is certain (a character pasted
    /// from a document and its ASCII form): editors offer it as a quick fix.
    pub replacement: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Diagnostic {
    pub code: Code,
    pub severity: Severity,
    /// One specific line: what is wrong.
    pub message: String,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    /// What to do about it.
    pub help: Option<String>,
}

impl Diagnostic {
    pub fn new(severity: Severity, code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic {
            code: Code(code),
            severity,
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
            help: None,
        }
    }

    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Error, code, message)
    }

    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Warning, code, message)
    }

    pub fn note_diag(code: &'static str, message: impl Into<String>) -> Self {
        Self::new(Severity::Note, code, message)
    }

    /// Adds the primary label.
    pub fn with_primary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: true,
            replacement: None,
        });
        self
    }

    /// Adds a secondary label.
    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: false,
            replacement: None,
        });
        self
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// The certain fix: `replacement` for the text of the primary label (added before).
    pub fn with_fix(mut self, replacement: impl Into<String>) -> Self {
        if let Some(label) = self.labels.iter_mut().find(|l| l.primary) {
            label.replacement = Some(replacement.into());
        }
        self
    }

    /// The certain fix of [`Diagnostic::with_fix`], if any.
    pub fn fix(&self) -> Option<&str> {
        self.labels
            .iter()
            .find(|l| l.primary)
            .and_then(|l| l.replacement.as_deref())
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// The primary span, if any.
    pub fn primary_span(&self) -> Option<Span> {
        self.labels.iter().find(|l| l.primary).map(|l| l.span)
    }
}

/// True when any diagnostic is an error.
pub fn has_errors(diags: &[Diagnostic]) -> bool {
    diags.iter().any(Diagnostic::is_error)
}
