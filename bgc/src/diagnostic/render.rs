//! Rendering diagnostics: rustc-like text and JSON.

use super::excerpt::Excerpts;
use super::unprintable::{same_length, shown};
use super::{Diagnostic, Severity};
use crate::span::SourceMap;
use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term;
use serde::Serialize;

/// At most this many diagnostics are rendered; the rest are counted in one closing line. A hostile or badly broken
/// file can give tens of thousands of errors, of which only the first few say anything new.
pub const MAX_SHOWN: usize = 100;

/// Renders diagnostics as text like rustc's: `error[BG0201]: ...` then `--> FILE:LINE:COL` and the source excerpt.
/// `color` adds ANSI colours (for terminals). Only the first [`MAX_SHOWN`] are rendered, and a label on a line longer
/// than 240 bytes shows a window of the line around it.
pub fn to_text(sources: &SourceMap, diags: &[Diagnostic], color: bool) -> String {
    if diags.is_empty() {
        // Nothing to show: no need for a copy of every file.
        return String::new();
    }
    // codespan prints the lines between labels from these copies, in which no control character is left (at the
    // same byte offsets); the labels' own lines are windows of the real text with visible stand-ins.
    let mut files = SimpleFiles::new();
    let mut originals = Vec::new();
    for (_, f) in sources.files() {
        files.add(shown(&f.name), same_length(&f.text).into_owned());
        originals.push(f.text.as_str());
    }
    let config = term::Config::default();
    let mut out = String::new();
    let (shown_diags, rest) = most_severe(diags);
    for d in shown_diags {
        let mut excerpts = Excerpts::new(&files, &originals);
        let cs_diag = to_codespan(d, &mut excerpts);
        let mut buf: Vec<u8> = Vec::new();
        let ok = if color {
            let mut w = term::termcolor::Ansi::new(&mut buf);
            term::emit_to_write_style(&mut w, &config, &excerpts, &cs_diag).is_ok()
        } else {
            let mut w = term::termcolor::NoColor::new(&mut buf);
            term::emit_to_write_style(&mut w, &config, &excerpts, &cs_diag).is_ok()
        };
        if ok {
            out.push_str(&String::from_utf8_lossy(&buf));
        } else {
            // A label out of range of its file: fall back to the message alone rather than losing it.
            out.push_str(&format!(
                "{}[{}]: {}\n",
                severity_word(d.severity),
                d.code.0,
                shown(&d.message)
            ));
        }
    }
    if !rest.is_empty() {
        out.push_str(&omitted_line(&rest));
    }
    out
}

/// The diagnostics to render and those left out: all of them when there are at most [`MAX_SHOWN`], otherwise the
/// [`MAX_SHOWN`] most severe (errors, then warnings, then notes, each in the order given), rendered in the order
/// given. An error after a hundred notes (a long ladder's arbitrary causalities) is shown, not counted.
fn most_severe(diags: &[Diagnostic]) -> (Vec<&Diagnostic>, Vec<&Diagnostic>) {
    if diags.len() <= MAX_SHOWN {
        return (diags.iter().collect(), Vec::new());
    }
    let rank = |s: Severity| match s {
        Severity::Error => 0,
        Severity::Warning => 1,
        Severity::Note => 2,
    };
    let mut by_severity: Vec<usize> = (0..diags.len()).collect();
    by_severity.sort_by_key(|&i| (rank(diags[i].severity), i));
    let mut chosen = vec![false; diags.len()];
    for &i in by_severity.iter().take(MAX_SHOWN) {
        chosen[i] = true;
    }
    let (shown, rest): (Vec<_>, Vec<_>) = diags.iter().zip(chosen).partition(|(_, c)| *c);
    (
        shown.into_iter().map(|(d, _)| d).collect(),
        rest.into_iter().map(|(d, _)| d).collect(),
    )
}

/// The closing line for the diagnostics not rendered.
fn omitted_line(rest: &[&Diagnostic]) -> String {
    let count = |s: Severity| rest.iter().filter(|d| d.severity == s).count();
    let (errors, warnings, notes) = (
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Note),
    );
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    format!(
        "note: only the {MAX_SHOWN} most severe diagnostics are shown; {} more not shown ({}, {}, {})\n",
        rest.len(),
        plural(errors, "error"),
        plural(warnings, "warning"),
        plural(notes, "note")
    )
}

fn severity_word(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    }
}

fn to_codespan(d: &Diagnostic, excerpts: &mut Excerpts<'_>) -> cs::Diagnostic<usize> {
    let severity = match d.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
        Severity::Note => cs::Severity::Note,
    };
    let labels = d
        .labels
        .iter()
        .map(|l| {
            let style = if l.primary {
                cs::LabelStyle::Primary
            } else {
                cs::LabelStyle::Secondary
            };
            let (file, range) = excerpts.place(l.span.file.0 as usize, l.span.range());
            cs::Label::new(style, file, range).with_message(shown(&l.message))
        })
        .collect();
    // Messages quote what the user wrote (a file name, a record's column): never a control character as it is.
    let mut notes: Vec<String> = d.notes.iter().map(|n| shown(n)).collect();
    if let Some(h) = &d.help {
        notes.push(format!("help: {}", shown(h)));
    }
    cs::Diagnostic::new(severity)
        .with_code(d.code.0)
        .with_message(shown(&d.message))
        .with_labels(labels)
        .with_notes(notes)
}

#[derive(Serialize)]
struct JsonLabel<'a> {
    file: &'a str,
    line: usize,
    column: usize,
    end_line: usize,
    end_column: usize,
    start: u32,
    end: u32,
    message: &'a str,
    primary: bool,
}

#[derive(Serialize)]
struct JsonDiagnostic<'a> {
    code: &'a str,
    severity: Severity,
    message: &'a str,
    labels: Vec<JsonLabel<'a>>,
    notes: &'a [String],
    help: Option<&'a str>,
    /// The replacement of the primary label's text that fixes it, when certain.
    #[serde(skip_serializing_if = "Option::is_none")]
    fix: Option<&'a str>,
}

/// Diagnostics as a JSON array, with line and column (1-based) for every label.
pub fn to_json_value(sources: &SourceMap, diags: &[Diagnostic]) -> serde_json::Value {
    let items: Vec<JsonDiagnostic> = diags
        .iter()
        .map(|d| JsonDiagnostic {
            code: d.code.0,
            severity: d.severity,
            message: &d.message,
            labels: d
                .labels
                .iter()
                .map(|l| {
                    let file = sources.get(l.span.file);
                    let (line, column) = file.map_or((0, 0), |f| f.line_col(l.span.start as usize));
                    let (end_line, end_column) =
                        file.map_or((0, 0), |f| f.line_col(l.span.end as usize));
                    JsonLabel {
                        file: file.map_or("", |f| f.name.as_str()),
                        line,
                        column,
                        end_line,
                        end_column,
                        start: l.span.start,
                        end: l.span.end,
                        message: &l.message,
                        primary: l.primary,
                    }
                })
                .collect(),
            notes: &d.notes,
            help: d.help.as_deref(),
            fix: d.fix(),
        })
        .collect();
    serde_json::to_value(items).unwrap_or(serde_json::Value::Null)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_after_more_notes_than_are_shown_is_shown() {
        let mut diags: Vec<Diagnostic> = (0..150)
            .map(|k| Diagnostic::note_diag("BG0530", format!("choice {k}")))
            .collect();
        diags.insert(120, Diagnostic::warning("BG0520", "a loop"));
        diags.push(Diagnostic::error("BG0701", "too many tears"));
        let text = to_text(&SourceMap::new(), &diags, false);
        assert!(text.contains("error[BG0701]: too many tears"), "{text}");
        assert!(text.contains("warning[BG0520]: a loop"), "{text}");
        // The notes kept are the first 98, in their order, before the warning and the error.
        assert!(
            text.contains("choice 97\n") && !text.contains("choice 98\n"),
            "{text}"
        );
        let (warning, error) = (text.find("a loop"), text.find("too many tears"));
        assert!(text.find("choice 97") < warning && warning < error);
        assert!(text.ends_with(
            "note: only the 100 most severe diagnostics are shown; 52 more not shown (0 errors, 0 warnings, 52 notes)\n"
        ));
    }
}
