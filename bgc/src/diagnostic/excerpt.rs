//! Source excerpts for the text renderer that stay short on any input.
//!
//! codespan-reporting prints every line a label touches in full. A minified or generated file can hold a whole
//! model on one line of megabytes, and echoing it for each of many diagnostics writes gigabytes. [`Excerpts`]
//! serves codespan the real files, except that a label on a line longer than [`MAX_LINE_BYTES`] is moved into a
//! one-line window of that line around the label, reported with its real line and column numbers. A line holding
//! a control character or a direction override is shown in such a window too, with each of them replaced by a
//! visible stand-in (`␛` for escape), so that echoing a hostile file cannot drive the terminal; the lines codespan
//! shows between labels come from copies with those characters replaced at the same offsets (`?`).

use super::unprintable;
use codespan_reporting::files::{self, Error, Files, SimpleFiles};
use std::ops::Range;

/// A line at most this long is shown whole.
pub const MAX_LINE_BYTES: usize = 240;
/// The bytes of context kept on each side of a label on a longer line.
const CONTEXT_BYTES: usize = 80;
/// The widest window, when the labels on one long line lie far apart.
const MAX_WINDOW_BYTES: usize = 2 * MAX_LINE_BYTES;
const ELLIPSIS: &str = "…";

/// A window of one long line of a real file.
struct Window {
    /// The real file.
    file: usize,
    /// The real line index (0-based) and the byte offset in the file where the window starts.
    line_index: usize,
    start: usize,
    end: usize,
    /// `…` + the window's text + `…` (the ellipses only where something was cut).
    text: String,
    /// The byte length of the leading ellipsis (0 or 3).
    lead: usize,
}

/// The files as codespan sees them for one diagnostic: the real ones (ids `0..n`) and the windows (`n..`).
pub struct Excerpts<'a> {
    real: &'a SimpleFiles<String, String>,
    /// The files' texts as they are (`real` may hold copies with control characters replaced, at the same
    /// offsets): windows are cut from these, with visible stand-ins.
    originals: &'a [&'a str],
    count: usize,
    windows: Vec<Window>,
}

impl<'a> Excerpts<'a> {
    pub fn new(real: &'a SimpleFiles<String, String>, originals: &'a [&'a str]) -> Self {
        Excerpts {
            real,
            originals,
            count: originals.len(),
            windows: Vec::new(),
        }
    }

    /// Where a label of `file` on `range` is shown: itself when its line is short, else in a window of its start
    /// line (a label running over several long lines is cut at the end of that line).
    pub fn place(&mut self, file: usize, range: Range<usize>) -> (usize, Range<usize>) {
        let Ok(f) = self.real.get(file) else {
            return (file, range);
        };
        let text = self
            .originals
            .get(file)
            .copied()
            .unwrap_or(f.source().as_str());
        let Ok(line_index) = f.line_index((), range.start) else {
            return (file, range);
        };
        let Ok(line) = f.line_range((), line_index) else {
            return (file, range);
        };
        let shown_from = text.get(line.start..range.end.max(line.end)).unwrap_or("");
        if line.len() <= MAX_LINE_BYTES && !needs_stand_ins(shown_from) {
            return (file, range);
        }
        let end = range.end.clamp(range.start, line.end);
        let covering = self.windows.iter().position(|w| {
            w.file == file && w.line_index == line_index && w.start <= range.start && end <= w.end
        });
        let w = match covering {
            Some(i) => i,
            None => {
                self.windows
                    .push(cut(text, file, line_index, line, range.start, end));
                self.windows.len() - 1
            }
        };
        let win = &self.windows[w];
        let shift = |at: usize| {
            let before = text.get(win.start..at.clamp(win.start, win.end));
            // The window's text is `shown` of the line: the offset is the length of what it shows before.
            win.lead + before.map_or(0, |b| unprintable::shown(b).len())
        };
        (self.count + w, shift(range.start)..shift(end))
    }

    fn window(&self, id: usize) -> Option<&Window> {
        id.checked_sub(self.count).and_then(|i| self.windows.get(i))
    }
}

/// The window of `line` around `start..end` (all of a short line), widened to char boundaries.
fn cut(
    text: &str,
    file: usize,
    line_index: usize,
    line: Range<usize>,
    start: usize,
    end: usize,
) -> Window {
    // A short line (here for its stand-ins) is shown whole.
    let short = line.len() <= MAX_LINE_BYTES;
    let mut from = if short {
        line.start
    } else {
        start.saturating_sub(CONTEXT_BYTES).max(line.start)
    };
    let mut to = if short {
        line.end
    } else {
        (end + CONTEXT_BYTES)
            .min(line.end)
            .min(from + MAX_WINDOW_BYTES)
    };
    while from > line.start && !text.is_char_boundary(from) {
        from -= 1;
    }
    while to < line.end && !text.is_char_boundary(to) {
        to += 1;
    }
    // The line range includes the line break; a window never shows it.
    let body = text
        .get(from..to)
        .unwrap_or("")
        .trim_end_matches(['\n', '\r']);
    let to = from + body.len();
    let lead = if from > line.start { ELLIPSIS } else { "" };
    let rest = text.get(to..line.end).unwrap_or("");
    let tail = if rest.trim_end_matches(['\n', '\r']).is_empty() {
        ""
    } else {
        ELLIPSIS
    };
    Window {
        file,
        line_index,
        start: from,
        end: to,
        text: format!("{lead}{}{tail}", unprintable::shown(body)),
        lead: lead.len(),
    }
}

/// Whether `text` holds a character that must be shown by a stand-in (line breaks aside).
fn needs_stand_ins(text: &str) -> bool {
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        let line_break = c == '\n' || (c == '\r' && chars.peek().is_none_or(|&n| n == '\n'));
        if unprintable::is_unprintable(c) && !line_break {
            return true;
        }
    }
    false
}

impl<'a> Files<'a> for Excerpts<'a> {
    type FileId = usize;
    type Name = String;
    type Source = &'a str;

    fn name(&'a self, id: usize) -> Result<String, Error> {
        match self.window(id) {
            Some(w) => self.real.name(w.file),
            None => self.real.name(id),
        }
    }

    fn source(&'a self, id: usize) -> Result<&'a str, Error> {
        match self.window(id) {
            Some(w) => Ok(&w.text),
            None => self.real.source(id),
        }
    }

    fn line_index(&'a self, id: usize, byte_index: usize) -> Result<usize, Error> {
        match self.window(id) {
            Some(_) => Ok(0),
            None => self.real.line_index(id, byte_index),
        }
    }

    fn line_number(&'a self, id: usize, line_index: usize) -> Result<usize, Error> {
        match self.window(id) {
            Some(w) => Ok(w.line_index + 1),
            None => self.real.line_number(id, line_index),
        }
    }

    fn column_number(
        &'a self,
        id: usize,
        line_index: usize,
        byte_index: usize,
    ) -> Result<usize, Error> {
        let Some(w) = self.window(id) else {
            return self.real.column_number(id, line_index, byte_index);
        };
        // The real column: the characters of the line before the window, then those of the window before the
        // byte (the leading ellipsis is not in the file).
        let real_line = self.real.line_range(w.file, w.line_index)?;
        let source = self.real.source(w.file)?;
        let before = files::column_index(source, real_line.start..w.start, w.start);
        let inside = w
            .text
            .get(w.lead..byte_index.clamp(w.lead, w.text.len()))
            .map_or(0, |s| s.chars().count());
        Ok(before + inside + 1)
    }

    fn line_range(&'a self, id: usize, line_index: usize) -> Result<Range<usize>, Error> {
        match self.window(id) {
            Some(w) if line_index == 0 => Ok(0..w.text.len()),
            Some(_) => Err(Error::LineTooLarge {
                given: line_index,
                max: 0,
            }),
            None => self.real.line_range(id, line_index),
        }
    }
}
