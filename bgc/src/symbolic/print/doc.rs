//! Printed text as a tree of pieces (a rope), so that putting a printed part inside a larger one costs a constant,
//! not the length of the part: printing a deep expression stays linear in the length of the text.

use std::borrow::Cow;
use std::rc::Rc;

/// Text under construction. Dropping and flattening walk it with a work list, so depth is no concern.
pub(in crate::symbolic) struct Doc {
    /// The first character of the text, kept so that asking for it costs nothing.
    first: Option<char>,
    piece: Piece,
}

enum Piece {
    /// Owned text, or a literal (a sign, a parenthesis, an operator) that needs no allocation.
    Text(Cow<'static, str>),
    Cat(Vec<Doc>),
    /// The printed form of a subexpression used in several places, printed once.
    Shared(Rc<Doc>),
}

impl Doc {
    pub fn text(s: impl Into<Cow<'static, str>>) -> Doc {
        let s = s.into();
        Doc {
            first: s.chars().next(),
            piece: Piece::Text(s),
        }
    }

    pub fn cat(parts: Vec<Doc>) -> Doc {
        Doc {
            first: parts.iter().find_map(|p| p.first),
            piece: Piece::Cat(parts),
        }
    }

    pub fn shared(doc: &Rc<Doc>) -> Doc {
        Doc {
            first: doc.first,
            piece: Piece::Shared(Rc::clone(doc)),
        }
    }

    pub fn starts_with_digit(&self) -> bool {
        self.first.is_some_and(|c| c.is_ascii_digit())
    }

    /// `(self)` with the given parentheses.
    pub fn wrap(self, open: impl Into<Cow<'static, str>>, close: &'static str) -> Doc {
        Doc::cat(vec![Doc::text(open), self, Doc::text(close)])
    }

    /// The parts joined by `sep`.
    pub fn join(parts: Vec<Doc>, sep: &'static str) -> Doc {
        let mut out = Vec::with_capacity(2 * parts.len());
        for (i, p) in parts.into_iter().enumerate() {
            if i > 0 {
                out.push(Doc::text(sep));
            }
            out.push(p);
        }
        Doc::cat(out)
    }

    /// The whole text.
    pub fn into_string(mut self) -> String {
        if let Piece::Text(s) = &mut self.piece {
            return std::mem::take(s).into_owned();
        }
        // The length first, so that the text is written into one allocation of the right size.
        let mut len = 0;
        let mut pending: Vec<&Doc> = Vec::with_capacity(16);
        pending.push(&self);
        while let Some(d) = pending.pop() {
            match &d.piece {
                Piece::Text(s) => len += s.len(),
                Piece::Cat(parts) => pending.extend(parts.iter()),
                Piece::Shared(rc) => pending.push(rc),
            }
        }
        let mut out = String::with_capacity(len);
        pending.push(&self);
        while let Some(d) = pending.pop() {
            match &d.piece {
                Piece::Text(s) => out.push_str(s),
                Piece::Cat(parts) => pending.extend(parts.iter().rev()),
                Piece::Shared(rc) => pending.push(rc),
            }
        }
        out
    }
}

impl Drop for Doc {
    fn drop(&mut self) {
        // Text needs no work list (most pieces are text, and so is every piece the loop below empties).
        if matches!(self.piece, Piece::Text(_)) {
            return;
        }
        let mut pending: Vec<Piece> = vec![self.take_piece()];
        while let Some(piece) = pending.pop() {
            match piece {
                Piece::Text(_) => {}
                Piece::Cat(parts) => pending.extend(parts.into_iter().map(|mut p| p.take_piece())),
                Piece::Shared(rc) => {
                    if let Ok(mut doc) = Rc::try_unwrap(rc) {
                        pending.push(doc.take_piece());
                    }
                }
            }
        }
    }
}

impl Doc {
    /// The piece, leaving empty text in its place (which drops without a work list).
    fn take_piece(&mut self) -> Piece {
        std::mem::replace(&mut self.piece, Piece::Text(Cow::Borrowed("")))
    }
}
