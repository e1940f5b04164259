//! The canonical order of expressions: the order of their keys ([`Ex::key`]) as strings, decided without
//! building the keys.
//!
//! Sums and products sort and collect their terms by this order, so it is asked for at every construction; a key
//! is as long as its expression, and building one per term re-read (and re-formatted the numbers of) whole
//! subexpressions each time a larger expression was built around them. Comparing the trees stops at the first
//! difference instead.
//!
//! A key is a sequence of tokens: `#<number>` (`{:e}` format), a symbol (`Param(3)`, `Time`), the heads `+(`,
//! `*(`, `^(` and `<function>(`, and the separators `,` and `)`:
//! `key(a + b) = +( key(a) , key(b) , )`, `key(b^x) = ^( key(b) , key(x) )`, `key(f(a)) = f( key(a) , )`.
//! Comparing two keys token by token gives the string order because two different tokens at one position already
//! decide it: no token is a proper prefix of another except a number of one of a longer number (`#1e1`, `#1e10`),
//! and what follows a number in a key (`,`, `)` or the end) sorts before the digit that continues the longer one,
//! as the shorter string does. So equal trees compare equal, and at the first pair of different subtrees (at the
//! same token position) the comparison of those subtrees is the answer.

use super::{Ex, Sym};
use std::cmp::Ordering;
use std::fmt::Write;

/// `a.key().cmp(&b.key())`, without the keys.
pub fn key_cmp(a: &Ex, b: &Ex) -> Ordering {
    match (a, b) {
        (Ex::Add(xs), Ex::Add(ys)) | (Ex::Mul(xs), Ex::Mul(ys)) => list_cmp(xs, ys),
        (Ex::Call(f, xs), Ex::Call(g, ys)) if f == g => list_cmp(xs, ys),
        (Ex::Pow(b1, x1), Ex::Pow(b2, x2)) => key_cmp(b1, b2).then_with(|| key_cmp(x1, x2)),
        (Ex::Num(x), Ex::Num(y)) if x.to_bits() == y.to_bits() => Ordering::Equal,
        (Ex::S(x), Ex::S(y)) if x == y => Ordering::Equal,
        _ => head_cmp(a, b),
    }
}

/// The items of two sums, products or argument lists, each followed by `,`, then `)`.
fn list_cmp(xs: &[Ex], ys: &[Ex]) -> Ordering {
    for (x, y) in xs.iter().zip(ys) {
        let c = key_cmp(x, y);
        if c != Ordering::Equal {
            return c;
        }
    }
    match (xs.get(ys.len()), ys.get(xs.len())) {
        // `xs` goes on where `ys` closes.
        (Some(x), _) => close_cmp(x).reverse(),
        (_, Some(y)) => close_cmp(y),
        _ => Ordering::Equal,
    }
}

/// `)` against the first token of `e`: only `#` (a number) sorts before `)`.
fn close_cmp(e: &Ex) -> Ordering {
    if matches!(e, Ex::Num(_)) {
        Ordering::Greater
    } else {
        Ordering::Less
    }
}

/// Two expressions whose first tokens differ (or are numbers, symbols or calls to compare).
fn head_cmp(a: &Ex, b: &Ex) -> Ordering {
    let (fa, fb) = (first_byte(a), first_byte(b));
    if fa != fb {
        return fa.cmp(&fb);
    }
    // The same first byte: two numbers, two symbols or two calls (the heads of the other kinds differ in it).
    let (mut ta, mut tb) = (Token::default(), Token::default());
    ta.head(a);
    tb.head(b);
    ta.bytes().cmp(tb.bytes())
}

/// The first byte of the key.
fn first_byte(e: &Ex) -> u8 {
    match e {
        Ex::Num(_) => b'#',
        Ex::Add(_) => b'+',
        Ex::Mul(_) => b'*',
        Ex::Pow(..) => b'^',
        Ex::S(s) => sym_name(*s).as_bytes()[0],
        Ex::Call(f, _) => f.name().as_bytes()[0],
    }
}

fn sym_name(s: Sym) -> &'static str {
    match s {
        Sym::Param(_) => "Param",
        Sym::Input(_) => "Input",
        Sym::InputDot(_) => "InputDot",
        Sym::State(_) => "State",
        Sym::StateDot(_) => "StateDot",
        Sym::Var(_) => "Var",
        Sym::Tear(_) => "Tear",
        Sym::Time => "Time",
        Sym::Output(_) => "Output",
    }
}

/// The first token of a key, written on the stack (the longest, a number, is `#` and 24 characters).
struct Token {
    bytes: [u8; 40],
    len: usize,
}

impl Default for Token {
    fn default() -> Self {
        Token {
            bytes: [0; 40],
            len: 0,
        }
    }
}

impl Token {
    fn head(&mut self, e: &Ex) {
        let _ = match e {
            Ex::Num(v) => write!(self, "#{v:e}"),
            Ex::S(s) => {
                s.write_key(self);
                Ok(())
            }
            Ex::Add(_) => self.write_str("+("),
            Ex::Mul(_) => self.write_str("*("),
            Ex::Pow(..) => self.write_str("^("),
            Ex::Call(f, _) => write!(self, "{}(", f.name()),
        };
    }

    fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

impl Write for Token {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let end = self.len + s.len();
        let slot = self.bytes.get_mut(self.len..end).ok_or(std::fmt::Error)?;
        slot.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}
