//! Characters that word processors, papers and PDFs put in formulas and units (`·`, `×`, `−`, `²`, `s⁻¹`, `→`,
//! `“mass”`, a no-break space): each is one error with what to write instead, and the lexer reads on as if the
//! ASCII form had been written, so that the rest of the statement gives no follow-up error ("expected `;`, found
//! `k`" after `m·k`, a unit read as `[kg m]` from `[kg·m²]`).

use super::lexer::Tok;

/// What a typographic character stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum StandIn {
    /// One token and its text (`−` → `-`, `÷` → `/`, `→` → `->`).
    Token(Tok, &'static str),
    /// A product: `*` in an expression, a space between the factors of a unit.
    Product,
    /// A power written in superscripts (`²`, `⁻¹`): `^` and the exponent.
    Power(i32),
    /// A space that is not ASCII (no-break, thin).
    Space,
}

impl StandIn {
    /// The ASCII text to write instead (`in_unit`: the character is between the factors of a unit).
    pub(super) fn ascii(self, in_unit: bool) -> String {
        match self {
            StandIn::Token(_, text) => text.to_string(),
            StandIn::Product if in_unit => " ".to_string(),
            StandIn::Product => "*".to_string(),
            StandIn::Power(p) => format!("^{p}"),
            StandIn::Space => " ".to_string(),
        }
    }
}

/// The typographic character or superscript run at the start of `rest`: its length in bytes, what it stands for
/// and the help to print.
pub(super) fn stand_in(rest: &str) -> Option<(usize, StandIn, &'static str)> {
    let c = rest.chars().next()?;
    let product = "multiply by `*` in an expression, and by a space in a unit, as in `[N m]`";
    Some(match c {
        '·' | '×' | '⋅' => (c.len_utf8(), StandIn::Product, product),
        '−' | '–' => (
            c.len_utf8(),
            StandIn::Token(Tok::Minus, "-"),
            "write the minus sign as the ASCII `-`",
        ),
        '÷' => (
            c.len_utf8(),
            StandIn::Token(Tok::Slash, "/"),
            "divide by `/`",
        ),
        '→' | '⟶' => (
            c.len_utf8(),
            StandIn::Token(Tok::Arrow, "->"),
            "a bond is written with `->`, as in `bond a -> b;`",
        ),
        '\u{a0}' | '\u{2009}' | '\u{202f}' | '\u{2007}' | '\u{200a}' => (
            c.len_utf8(),
            StandIn::Space,
            "a space that is not ASCII (pasted from a document): write a plain space",
        ),
        _ => {
            let (len, power) = superscript(rest)?;
            (
                len,
                StandIn::Power(power),
                "write a power with `^`, as in `x^2`, `[m^2]` or `[s^-1]`",
            )
        }
    })
}

/// A run of superscript digits, with an optional superscript minus before them (`²`, `⁻¹`): its length in bytes
/// and the exponent.
fn superscript(rest: &str) -> Option<(usize, i32)> {
    let mut chars = rest.char_indices().peekable();
    let negative = chars.next_if(|&(_, c)| c == '⁻').is_some();
    let mut value: i32 = 0;
    let mut digits = 0;
    let mut len = if negative { '⁻'.len_utf8() } else { 0 };
    while let Some(&(i, c)) = chars.peek() {
        let Some(d) = superscript_digit(c) else { break };
        value = value.saturating_mul(10).saturating_add(d);
        digits += 1;
        len = i + c.len_utf8();
        chars.next();
    }
    (digits > 0).then_some((len, if negative { -value } else { value }))
}

fn superscript_digit(c: char) -> Option<i32> {
    Some(match c {
        '⁰' => 0,
        '¹' => 1,
        '²' => 2,
        '³' => 3,
        '⁴' => 4,
        '⁵' => 5,
        '⁶' => 6,
        '⁷' => 7,
        '⁸' => 8,
        '⁹' => 9,
        _ => return None,
    })
}

/// A string between typographic quotes on one line (`“mass”`, `”mass”`, `“mass"`): its length in bytes and its
/// text, when it is closed on the line.
pub(super) fn quoted(rest: &str) -> Option<(usize, &str)> {
    let open = rest
        .chars()
        .next()
        .filter(|c| matches!(c, '“' | '”' | '„'))?;
    let body = &rest[open.len_utf8()..];
    let close = body.find(['”', '"', '“', '\n', '\r'])?;
    let closing = body[close..].chars().next()?;
    if matches!(closing, '\n' | '\r') {
        return None;
    }
    Some((open.len_utf8() + close + closing.len_utf8(), &body[..close]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn superscripts_read_as_powers() {
        assert_eq!(superscript("²]"), Some((2, 2)));
        assert_eq!(superscript("⁻¹ m"), Some((5, -1)));
        assert_eq!(superscript("¹⁰x"), Some(("¹⁰".len(), 10)));
        assert_eq!(superscript("⁻x"), None);
        assert_eq!(superscript("2"), None);
    }

    #[test]
    fn typographic_quotes_close_on_their_line() {
        assert_eq!(
            quoted("“moving mass”;"),
            Some(("“moving mass”".len(), "moving mass"))
        );
        assert_eq!(quoted("“mass\";"), Some(("“mass\"".len(), "mass")));
        assert_eq!(quoted("“mass\n”"), None);
        assert_eq!(quoted("mass"), None);
    }
}
