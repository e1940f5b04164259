//! Edits the server proposes: formatting (`bgc fmt`'s canonical layout) and quick fixes for the diagnostics
//! whose help names the replacement ("did you mean `R_a`?").

use super::analysis::Analysis;
use super::diagnostics::{Lines, severity};
use super::lines::LineIndex;
use crate::diagnostic::unprintable::shown;
use lsp_types::{
    CodeAction, CodeActionKind, CodeActionOrCommand, NumberOrString, Range, TextEdit, Uri,
    WorkspaceEdit,
};
use std::collections::HashMap;

/// The edit that puts the text in the canonical layout: one replacement of the part between the longest common
/// prefix and suffix of the old and new text, so that the editor keeps the cursor and folds of untouched lines.
/// `None` when the text has syntax errors (it cannot be formatted) and an empty list when it is already formatted.
pub fn format(text: &str) -> Option<Vec<TextEdit>> {
    let formatted = crate::syntax::format_source(crate::span::FileId(0), text).ok()?;
    if formatted == text {
        return Some(Vec::new());
    }
    let prefix = common_prefix(text, &formatted);
    let suffix = common_suffix(&text[prefix..], &formatted[prefix..]);
    let lines = LineIndex::new(text);
    let range = lines.range(text, prefix..text.len() - suffix);
    let new_text = formatted[prefix..formatted.len() - suffix].to_string();
    Some(vec![TextEdit::new(range, new_text)])
}

/// The edits of [`format()`] that touch the lines of `range`: the canonical layout's line changes, each hunk of a
/// line diff of the old and the formatted text kept when it overlaps (or, for an insertion, borders) those lines.
/// A hunk that replaces as many lines as it writes pairs them line by line, and only the selected ones change; one
/// that joins or splits lines is formatted whole. The rest of the file stays as written. `None` when the text has
/// syntax errors.
pub fn format_range(text: &str, range: Range) -> Option<Vec<TextEdit>> {
    let formatted = crate::syntax::format_source(crate::span::FileId(0), text).ok()?;
    let starts = line_starts(text);
    let old_lines = super::line_diff::lines(text);
    let new_lines = super::line_diff::lines(&formatted);
    let (first, last) = (range.start.line as usize, range.end.line as usize);
    let lines = LineIndex::new(text);
    let mut edits = Vec::new();
    for op in super::line_diff::ops(&old_lines, &new_lines) {
        let (tag, old, new) = op.as_tag_tuple();
        if tag == similar::DiffTag::Equal {
            continue;
        }
        let touches = if old.is_empty() {
            (first..=last + 1).contains(&old.start)
        } else {
            old.start <= last && first < old.end
        };
        if !touches {
            continue;
        }
        if old.len() == new.len()
            && old
                .clone()
                .zip(new.clone())
                .all(|(o, n)| same_statement(old_lines[o], new_lines[n]))
        {
            for (o, n) in old.zip(new).filter(|(o, _)| (first..=last).contains(o)) {
                edits.push(TextEdit::new(
                    lines.range(text, starts[o]..starts[o + 1]),
                    new_lines[n].to_string(),
                ));
            }
        } else {
            let bytes = starts[old.start]..starts[old.end];
            edits.push(TextEdit::new(
                lines.range(text, bytes),
                new_lines[new].concat(),
            ));
        }
    }
    Some(edits)
}

/// Whether a line and its counterpart in the canonical layout start alike (the same first word, or both a
/// comment): then the layout changed the line in place, and it can be formatted alone. Where lines shifted (a
/// comment moved to the next line), the hunk is formatted whole.
fn same_statement(old: &str, new: &str) -> bool {
    let first_word = |line: &str| -> String {
        let line = line.trim_start();
        match line.starts_with("//") {
            true => "//".to_string(),
            false => line
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect(),
        }
    };
    let word = first_word(old);
    !word.is_empty() && word == first_word(new)
}

/// The byte offset of the start of each line of `text`, and its length last (`starts[k]..starts[k + 1]` is line
/// `k` with its line break).
fn line_starts(text: &str) -> Vec<usize> {
    let mut starts = vec![0];
    starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
    if starts.last() != Some(&text.len()) {
        starts.push(text.len());
    }
    starts
}

fn common_prefix(a: &str, b: &str) -> usize {
    let mut n = a.bytes().zip(b.bytes()).take_while(|(x, y)| x == y).count();
    while !a.is_char_boundary(n) || !b.is_char_boundary(n) {
        n -= 1;
    }
    n
}

fn common_suffix(a: &str, b: &str) -> usize {
    let mut n = a
        .bytes()
        .rev()
        .zip(b.bytes().rev())
        .take_while(|(x, y)| x == y)
        .count();
    while !a.is_char_boundary(a.len() - n) || !b.is_char_boundary(b.len() - n) {
        n -= 1;
    }
    n
}

/// The name a help line proposes: the text between the backticks of "did you mean `NAME`?" or "did you mean the
/// keyword `NAME`?".
pub fn suggestion(help: &str) -> Option<&str> {
    let rest = help.split("did you mean ").nth(1)?;
    let rest = rest.strip_prefix("the keyword ").unwrap_or(rest);
    let rest = rest.strip_prefix('`')?;
    let end = rest.find('`')?;
    Some(&rest[..end])
}

/// The quick fixes for the diagnostics of the root file that overlap `range`.
pub fn code_actions(analysis: &Analysis, uri: &Uri, range: Range) -> Vec<CodeActionOrCommand> {
    let lines = Lines::new(analysis);
    let text = analysis.root_text();
    let mut out = Vec::new();
    for d in &analysis.diagnostics {
        let Some(span) = d.primary_span().filter(|s| s.file == analysis.root) else {
            continue;
        };
        let place = lines.range(span);
        if place.end < range.start || range.end < place.start {
            continue;
        }
        let written = text.get(span.range()).unwrap_or("");
        // A certain fix (a character pasted from a document), else the name a "did you mean" help proposes.
        let replacement = match (d.fix(), d.help.as_deref().and_then(suggestion)) {
            (Some(fix), _) => fix,
            (None, Some(name)) if plausible(written, name) => name,
            _ => continue,
        };
        let edit = TextEdit::new(place, replacement.to_string());
        let diagnostic = lsp_types::Diagnostic {
            range: place,
            severity: Some(severity(d.severity)),
            code: Some(NumberOrString::String(d.code.0.to_string())),
            source: Some("bgc".to_string()),
            message: d.message.clone(),
            ..lsp_types::Diagnostic::default()
        };
        out.push(CodeActionOrCommand::CodeAction(CodeAction {
            // A control character is named by its stand-in: the title is shown as it is.
            title: match (replacement.is_empty(), written.trim().is_empty()) {
                (true, _) => format!("Remove `{}`", shown(written)),
                (false, true) => "Replace the space that is not ASCII with a space".to_string(),
                (false, false) => format!("Replace `{}` with `{replacement}`", shown(written)),
            },
            kind: Some(CodeActionKind::QUICKFIX),
            diagnostics: Some(vec![diagnostic]),
            edit: Some(WorkspaceEdit::new(HashMap::from([(
                uri.clone(),
                vec![edit],
            )]))),
            is_preferred: Some(true),
            ..CodeAction::default()
        }));
    }
    out
}

/// The label covers just a misspelt name (a few edits away from the suggestion), so replacing it is the fix.
fn plausible(written: &str, replacement: &str) -> bool {
    let is_name = |s: &str| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_alphanumeric() || c == '_' || c == '.')
    };
    is_name(written) && written != replacement && distance(written, replacement) <= 3
}

fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            let best = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
            cur.push(best);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_are_read_from_helps() {
        assert_eq!(suggestion("did you mean `R_a`?"), Some("R_a"));
        assert_eq!(
            suggestion("did you mean the keyword `param`?"),
            Some("param")
        );
        assert_eq!(suggestion("declare it as a `param`"), None);
        assert!(plausible("R_b", "R_a"));
        assert!(!plausible("k", "param"));
        assert!(!plausible("j1 -> j2", "j1"));
    }

    #[test]
    fn formatting_replaces_only_what_changes() {
        let text = "model m {\n    domain rotational;\n  param   k = 1 [N m/rad];\n}\n";
        let edits = format(text).unwrap_or_default();
        assert_eq!(edits.len(), 1);
        // Only `param   ` of line 2 changes: `  param   k` becomes `    param k`.
        let range = edits[0].range;
        assert_eq!(
            (range.start, range.end),
            (
                lsp_types::Position::new(2, 2),
                lsp_types::Position::new(2, 9)
            )
        );
        assert_eq!(edits[0].new_text, "  param");
        let mut applied = text.to_string();
        applied.replace_range(
            text.find("param").unwrap_or(0)..text.find(" k =").unwrap_or(0),
            "  param",
        );
        assert_eq!(
            Ok(applied),
            crate::syntax::format_source(crate::span::FileId(0), text)
        );
        assert_eq!(
            format(&crate::syntax::format_source(crate::span::FileId(0), text).unwrap_or_default()),
            Some(Vec::new())
        );
        assert_eq!(format("model m {\n"), None);
    }
}
