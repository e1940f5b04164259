//! How wide a part of a statement's code prints, found without printing more of it than a line holds.
//!
//! Laying a statement out asks, part by part, whether a part fits in what is left of a line. Printing each part
//! whole to find out cost its size every time it was asked, once for each part it sits in: the square of the depth
//! on nested code (a Horner chain of 200 levels, in a chain of modulated transformers, spent two thirds of
//! `bgc rust` printing). [`text_within`] stops at the limit, so each question costs at most a line.

use super::layout::width;
use crate::symbolic::RustCode;
use std::fmt::{self, Write};

/// A writer that refuses text beyond a number of columns.
struct Bounded {
    text: String,
    left: usize,
}

impl Write for Bounded {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let w = width(s);
        if w > self.left {
            return Err(fmt::Error);
        }
        self.left -= w;
        self.text.push_str(s);
        Ok(())
    }
}

/// The text of `code` when it takes at most `limit` columns on one line.
pub(super) fn text_within(code: &RustCode, limit: usize) -> Option<String> {
    let mut out = Bounded {
        text: String::new(),
        left: limit,
    };
    write!(out, "{code}").ok().map(|()| out.text)
}

/// The columns `code` takes on one line, counted without printing it.
pub(super) fn text_width(code: &RustCode) -> usize {
    let mut total = 0;
    let mut stack = vec![code];
    while let Some(code) = stack.pop() {
        total += match code {
            RustCode::Atom(s) => width(s),
            RustCode::Neg(inner) => {
                stack.push(inner);
                1
            }
            RustCode::Paren(inner) => {
                stack.push(inner);
                2
            }
            RustCode::Chain(first, rest) => {
                stack.push(first);
                stack.extend(rest.iter().map(|(_, o)| o));
                rest.iter().map(|(op, _)| width(op.as_str()) + 2).sum()
            }
            RustCode::Call(callee, args) => {
                stack.extend(args);
                width(callee) + 2 + 2 * args.len().saturating_sub(1)
            }
        };
    }
    total
}

/// The widest argument list of any call in `code`. It recurses: for code that fits on a line.
pub(super) fn widest_call_args(code: &RustCode) -> usize {
    match code {
        RustCode::Atom(_) => 0,
        RustCode::Neg(inner) | RustCode::Paren(inner) => widest_call_args(inner),
        RustCode::Chain(first, rest) => rest
            .iter()
            .map(|(_, o)| widest_call_args(o))
            .fold(widest_call_args(first), usize::max),
        RustCode::Call(_, args) => {
            let own = args.iter().map(text_width).sum::<usize>() + 2 * args.len().saturating_sub(1);
            args.iter().map(widest_call_args).fold(own, usize::max)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::RustOp;

    fn atom(s: &str) -> RustCode {
        RustCode::Atom(s.into())
    }

    /// `bgc_powi(libm::atan2(-x[0], (p.a - 2.5 + y)), 3) / q`: every kind of node, nested.
    fn sample() -> RustCode {
        let call = RustCode::Call(
            "libm::atan2".into(),
            vec![
                RustCode::Neg(Box::new(atom("x[0]"))),
                RustCode::Paren(Box::new(RustCode::Chain(
                    Box::new(atom("p.a")),
                    vec![(RustOp::Sub, atom("2.5")), (RustOp::Add, atom("y"))],
                ))),
            ],
        );
        RustCode::Chain(
            Box::new(RustCode::Call("bgc_powi".into(), vec![call, atom("3")])),
            vec![(RustOp::Div, atom("q"))],
        )
    }

    #[test]
    fn the_width_is_that_of_the_printed_text_and_a_limit_stops_the_printing() {
        let code = sample();
        let text = "bgc_powi(libm::atan2(-x[0], (p.a - 2.5 + y)), 3) / q";
        assert_eq!(code.to_string(), text);
        assert_eq!(text_width(&code), 52);
        assert_eq!(text_within(&code, 52).as_deref(), Some(text));
        assert_eq!(text_within(&code, 51), None);
        assert_eq!(text_within(&code, 0), None);
        assert_eq!(text_width(&atom("μ")), 1);
        // The power's arguments, `libm::atan2(-x[0], (p.a - 2.5 + y)), 3`, are the widest list.
        assert_eq!(widest_call_args(&code), 38);
    }
}
