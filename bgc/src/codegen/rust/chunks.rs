//! The text of a model's items while it is written, and the pass that marks each item `#[allow(dead_code)]` on
//! its way out.
//!
//! A large model's items are hundreds of megabytes (250 MB for the 100,000-stage chain). Held as one `String` it
//! grew by doubling (a moment with the old and the new buffer, 256 MB and 512 MB, both alive), and it was copied
//! once more into the finished module. [`Chunks`] holds the text in pieces of about [`CHUNK_BYTES`], each ending
//! a line, so that it grows without copying; [`write_lines`] hands the lines on one by one (to a file, to standard
//! output, or into a `String`), dropping each piece once its lines are written.

use super::ITEM_STARTS;
use std::fmt;

/// The size after which the next piece starts (at the end of a line).
const CHUNK_BYTES: usize = 1 << 20;

/// Text written in pieces; every piece but the last ends with `\n`, so the lines of the pieces, one after the
/// other, are the lines of the whole text.
#[derive(Default)]
pub(in crate::codegen) struct Chunks {
    pieces: Vec<String>,
}

impl Chunks {
    pub(in crate::codegen) fn push(&mut self, c: char) {
        let mut buf = [0u8; 4];
        self.push_str(c.encode_utf8(&mut buf));
    }

    pub(in crate::codegen) fn push_str(&mut self, s: &str) {
        match self.pieces.last_mut() {
            Some(last) if !(last.len() >= CHUNK_BYTES && last.ends_with('\n')) => last.push_str(s),
            _ => {
                let mut piece = String::with_capacity(CHUNK_BYTES.max(s.len()) + CHUNK_BYTES / 8);
                piece.push_str(s);
                self.pieces.push(piece);
            }
        }
    }

    /// Appends the text of `other`.
    pub(in crate::codegen) fn append(&mut self, other: Chunks) {
        for piece in other.pieces {
            self.push_str(&piece);
        }
    }

    pub(in crate::codegen) fn is_empty(&self) -> bool {
        self.pieces.iter().all(String::is_empty)
    }

    pub(in crate::codegen) fn ends_with(&self, c: char) -> bool {
        self.pieces
            .iter()
            .rev()
            .find(|p| !p.is_empty())
            .is_some_and(|p| p.ends_with(c))
    }

    /// The lines of the whole text.
    pub(in crate::codegen) fn lines(&self) -> impl Iterator<Item = &str> {
        self.pieces.iter().flat_map(|p| p.lines())
    }

    /// Each line, in order, handed to `line`; each piece is dropped once its lines are handed on.
    pub(in crate::codegen) fn into_lines(self, line: &mut dyn FnMut(&str)) {
        for piece in self.pieces {
            piece.lines().for_each(&mut *line);
        }
    }
}

impl fmt::Write for Chunks {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.push_str(s);
        Ok(())
    }
}

/// Passes lines on with `dead_code` allowed on each item, right above its keyword line (below its documentation
/// and other attributes; joined to an `#[allow(...)]` line already there), so that a crate that uses some of the
/// items builds without warnings. One line is held back until the next shows whether it is an item's.
pub(in crate::codegen) struct AllowDeadCode<'o> {
    out: &'o mut dyn FnMut(&str),
    held: String,
    holding: bool,
}

impl<'o> AllowDeadCode<'o> {
    pub(in crate::codegen) fn new(out: &'o mut dyn FnMut(&str)) -> Self {
        AllowDeadCode {
            out,
            held: String::new(),
            holding: false,
        }
    }

    pub(in crate::codegen) fn line(&mut self, line: &str) {
        if ITEM_STARTS.iter().any(|k| line.starts_with(k)) {
            if self.holding && self.held.starts_with("#[allow(") && self.held.ends_with(")]") {
                self.held.truncate(self.held.len() - 2);
                self.held.push_str(", dead_code)]");
            } else {
                self.hold("#[allow(dead_code)]");
            }
        }
        self.hold(line);
    }

    fn hold(&mut self, line: &str) {
        if self.holding {
            (self.out)(&self.held);
        }
        self.held.clear();
        self.held.push_str(line);
        self.holding = true;
    }

    /// Passes on the line held back.
    pub(in crate::codegen) fn finish(mut self) {
        if self.holding {
            (self.out)(&self.held);
            self.holding = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_end_lines_and_read_back_as_the_whole_text() {
        let mut c = Chunks::default();
        let mut whole = String::new();
        for k in 0..200_000 {
            let line = format!("let x{k} = {k};\n");
            // Written a character at a time, so that a piece would be cut inside a line if the cut did not wait
            // for `\n`.
            line.chars().for_each(|ch| c.push(ch));
            whole.push_str(&line);
        }
        assert!(c.pieces.len() > 2, "{} pieces", c.pieces.len());
        assert!(c.pieces.iter().rev().skip(1).all(|p| p.ends_with('\n')));
        assert!(c.lines().eq(whole.lines()));
        assert!(c.ends_with('\n') && !c.is_empty());
        let mut back = Vec::new();
        c.into_lines(&mut |l| back.push(l.to_string()));
        assert!(back.iter().map(String::as_str).eq(whole.lines()));
    }

    #[test]
    fn every_item_gets_dead_code_allowed_once() {
        let code = "/// Doc.\n#[inline]\npub fn f() {}\n#[allow(non_snake_case)]\nfn g() {}\nconst N: usize = 1;";
        let mut out = Vec::new();
        let mut push = |l: &str| out.push(l.to_string());
        let mut w = AllowDeadCode::new(&mut push);
        code.lines().for_each(|l| w.line(l));
        w.finish();
        assert_eq!(
            out,
            [
                "/// Doc.",
                "#[inline]",
                "#[allow(dead_code)]",
                "pub fn f() {}",
                "#[allow(non_snake_case, dead_code)]",
                "fn g() {}",
                "#[allow(dead_code)]",
                "const N: usize = 1;",
            ]
        );
    }
}
