//! The lexer: text to tokens, comments and lexical diagnostics.
//!
//! Each token class is recognised by a small nom parser over `&str`; the driver loop turns what they recognise into
//! [`Token`]s with byte spans. Lexing never fails: a malformed literal becomes a token plus a diagnostic, and a
//! character that starts no token is reported (runs of them as one diagnostic) and skipped. Comments do not enter
//! the token stream; they are returned separately so that the parser can attach doc comments and the formatter can
//! print ordinary ones back. Lexing is a single left-to-right pass, so it takes time linear in the input.

use super::typographic::StandIn;
use crate::diagnostic::Diagnostic;
use crate::diagnostic::unprintable::{is_unprintable, stand_in};
use crate::span::{FileId, Span};
use nom::branch::alt;
use nom::bytes::complete::{tag, take_while, take_while1};
use nom::character::complete::{char, digit0, digit1, one_of};
use nom::combinator::{opt, recognize};
use nom::{IResult, Parser};

/// The class of a token. Literal values live beside the tokens (see [`Lexed`]), so that a token is three words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tok {
    Ident,
    /// A number literal; its value is in [`Lexed::numbers`].
    Number,
    /// A string literal; its unescaped text is in [`Lexed::strings`].
    Str,
    LBrace,
    RBrace,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Semi,
    Comma,
    Eq,
    Colon,
    Dot,
    Arrow,
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    Bang,
    Eof,
}

impl Tok {
    /// How the token class is named in "expected ..." messages.
    pub fn describe(self) -> &'static str {
        match self {
            Tok::Ident => "a name",
            Tok::Number => "a number",
            Tok::Str => "a string",
            Tok::LBrace => "`{`",
            Tok::RBrace => "`}`",
            Tok::LParen => "`(`",
            Tok::RParen => "`)`",
            Tok::LBracket => "`[`",
            Tok::RBracket => "`]`",
            Tok::Semi => "`;`",
            Tok::Comma => "`,`",
            Tok::Eq => "`=`",
            Tok::Colon => "`:`",
            Tok::Dot => "`.`",
            Tok::Arrow => "`->`",
            Tok::Plus => "`+`",
            Tok::Minus => "`-`",
            Tok::Star => "`*`",
            Tok::Slash => "`/`",
            Tok::Caret => "`^`",
            Tok::Bang => "`!`",
            Tok::Eof => "the end of the file",
        }
    }
}

/// A token: its class and its bytes. A large file has millions of them, so a token carries nothing else.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Token {
    pub kind: Tok,
    pub start: u32,
    pub end: u32,
}

/// A `//` or `///` comment.
#[derive(Clone, Debug, PartialEq)]
pub struct RawComment {
    /// The whole comment, from the slashes to the end of the line, trailing whitespace removed.
    pub text: String,
    pub start: u32,
    pub end: u32,
    /// `///` (but not `////`): documentation of the next declaration.
    pub doc: bool,
    /// Nothing but whitespace precedes the comment on its line.
    pub own_line: bool,
}

/// The lexer's output.
#[derive(Clone, Debug, Default)]
pub struct Lexed {
    /// The tokens, always ending with one [`Tok::Eof`].
    pub tokens: Vec<Token>,
    /// The value of each number token, by the token's start, in order (0 for a malformed number, which is already
    /// reported).
    pub numbers: Vec<(u32, f64)>,
    /// The unescaped text of each string token, by the token's start, in order.
    pub strings: Vec<(u32, String)>,
    /// The starts of the string tokens without a closing quote (already reported; each ran to the end of its line).
    pub unterminated: Vec<u32>,
    pub comments: Vec<RawComment>,
    /// Byte offsets of the starts of blank lines, so the formatter can keep paragraphs apart.
    pub blank_lines: Vec<u32>,
    pub diagnostics: Vec<Diagnostic>,
}

fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_' || is_micro(c)
}

fn is_ident_continue(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || is_micro(c)
}

/// The micro sign and the Greek small mu, both accepted as the SI prefix `µ` in units.
pub fn is_micro(c: char) -> bool {
    c == '\u{b5}' || c == '\u{3bc}'
}

fn ident(i: &str) -> IResult<&str, &str> {
    recognize((take_while1(is_ident_start), take_while(is_ident_continue))).parse(i)
}

/// `12`, `0.5`, `.5`, `12.`, with an optional exponent part; the exponent's digits are optional here so that `1e`
/// is recognised (and then reported) as one malformed number rather than a number and a name.
fn number(i: &str) -> IResult<&str, &str> {
    recognize((
        alt((
            recognize((digit1, opt((char('.'), digit0)))),
            recognize((char('.'), digit1)),
        )),
        opt((one_of("eE"), opt(one_of("+-")), digit0)),
    ))
    .parse(i)
}

fn line_comment(i: &str) -> IResult<&str, &str> {
    // A comment ends at any line break, a lone `\r` too (as a string does).
    recognize((tag("//"), take_while(|c| c != '\n' && c != '\r'))).parse(i)
}

fn whitespace(i: &str) -> IResult<&str, &str> {
    take_while1(|c: char| c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\u{c}').parse(i)
}

fn punct(i: &str) -> IResult<&str, Tok> {
    if let Ok((rest, _)) = tag::<&str, &str, nom::error::Error<&str>>("->").parse(i) {
        return Ok((rest, Tok::Arrow));
    }
    let (rest, c) = one_of("{}()[];,=:.+-*/^!").parse(i)?;
    let kind = u8::try_from(c)
        .ok()
        .and_then(one_char_punct)
        .unwrap_or(Tok::Bang);
    Ok((rest, kind))
}

/// The token of a one-character punctuation mark (`None` for any other byte).
fn one_char_punct(c: u8) -> Option<Tok> {
    Some(match c {
        b'{' => Tok::LBrace,
        b'}' => Tok::RBrace,
        b'(' => Tok::LParen,
        b')' => Tok::RParen,
        b'[' => Tok::LBracket,
        b']' => Tok::RBracket,
        b';' => Tok::Semi,
        b',' => Tok::Comma,
        b'=' => Tok::Eq,
        b':' => Tok::Colon,
        b'.' => Tok::Dot,
        b'+' => Tok::Plus,
        b'-' => Tok::Minus,
        b'*' => Tok::Star,
        b'/' => Tok::Slash,
        b'^' => Tok::Caret,
        b'!' => Tok::Bang,
        _ => return None,
    })
}

struct Lexer<'a> {
    file: FileId,
    text: &'a str,
    out: Lexed,
    /// Start of a run of invalid characters not yet reported.
    junk: Option<(usize, usize)>,
    /// Whether only whitespace has been seen since the last newline.
    at_line_start: bool,
    /// Diagnostics past [`MAX_LEXER_DIAGNOSTICS`]: counted, and summed up in one at the end.
    omitted: Option<(Span, usize)>,
}

/// The diagnostics the lexer records one by one. A file of invalid characters would otherwise make millions (the
/// 64 MiB a file may have, gigabytes of diagnostics); the text rendering shows 100.
const MAX_LEXER_DIAGNOSTICS: usize = 1000;

/// Splits `text` into tokens. See the module documentation.
pub fn lex(file: FileId, text: &str) -> Lexed {
    let mut out = Lexed::default();
    // From one token per six bytes in commented models to one per three in generated ones; reserving avoids
    // repeated growth of a large vector (pages reserved but never written cost nothing).
    out.tokens.reserve(text.len() / 3 + 1);
    let mut lx = Lexer {
        file,
        text,
        out,
        junk: None,
        at_line_start: true,
        omitted: None,
    };
    lx.run();
    if let Some((first, count)) = lx.omitted {
        lx.out.diagnostics.push(
            Diagnostic::error("BG0104", format!("{count} more lexical errors are not listed"))
                .with_primary(first, "the first of them")
                .with_help(format!(
                    "the first {MAX_LEXER_DIAGNOSTICS} are listed; fix those, or check that this is a `.bg` file"
                )),
        );
    }
    lx.out
}

impl<'a> Lexer<'a> {
    /// Records a diagnostic, or counts it past [`MAX_LEXER_DIAGNOSTICS`].
    fn report(&mut self, d: Diagnostic) {
        if self.out.diagnostics.len() < MAX_LEXER_DIAGNOSTICS {
            self.out.diagnostics.push(d);
            return;
        }
        let first = d.primary_span().unwrap_or(self.span(0, 0));
        let (_, count) = self.omitted.get_or_insert((first, 0));
        *count += 1;
    }

    fn span(&self, start: usize, end: usize) -> Span {
        Span::new(self.file, start, end)
    }

    fn push(&mut self, kind: Tok, start: usize, end: usize) {
        self.out.tokens.push(Token {
            kind,
            start: start as u32,
            end: end as u32,
        });
        self.at_line_start = false;
    }

    fn push_number(&mut self, start: usize, end: usize, value: f64) {
        self.out.numbers.push((start as u32, value));
        self.push(Tok::Number, start, end);
    }

    /// Reports the pending run of invalid characters, if any (before each token, so always inlined: the check is
    /// a compare, the call it would otherwise be costs more).
    #[inline(always)]
    fn flush_junk(&mut self) {
        if self.junk.is_some() {
            self.report_junk();
        }
    }

    fn report_junk(&mut self) {
        if let Some((start, end)) = self.junk.take() {
            let shown: String = self
                .text
                .get(start..end)
                .unwrap_or("")
                .chars()
                .take(1)
                .collect();
            let msg = if end - start == shown.len() {
                format!("invalid character {shown:?}")
            } else {
                "invalid characters".to_string()
            };
            let help = shown
                .chars()
                .next()
                .and_then(typographic_help)
                .unwrap_or(
                    "names are ASCII letters, digits and `_`; text belongs in a \"string\"; comments start with `//`",
                );
            self.report(
                Diagnostic::error("BG0104", msg)
                    .with_primary(self.span(start, end), "not part of the language")
                    .with_help(help),
            );
        }
    }

    fn run(&mut self) {
        let text = self.text;
        // A byte-order mark, which some editors write at the start of UTF-8 files, is not text.
        let mut rest = text.strip_prefix('\u{feff}').unwrap_or(text);
        while !rest.is_empty() {
            let start = text.len() - rest.len();
            if let Some(r) = self.common(start, rest) {
                rest = r;
                continue;
            }
            if let Ok((r, ws)) = whitespace(rest) {
                self.flush_junk();
                self.note_whitespace(start, ws);
                rest = r;
                continue;
            }
            if let Ok((r, c)) = line_comment(rest) {
                self.flush_junk();
                self.comment(start, c);
                rest = r;
                continue;
            }
            if let Ok((r, _)) = ident(rest) {
                self.flush_junk();
                self.push(Tok::Ident, start, text.len() - r.len());
                rest = r;
                continue;
            }
            if let Ok((r, n)) = number(rest) {
                self.flush_junk();
                rest = self.number(start, n, r);
                continue;
            }
            if rest.starts_with('"') {
                self.flush_junk();
                rest = self.string(start, rest);
                continue;
            }
            if let Ok((r, kind)) = punct(rest) {
                self.flush_junk();
                self.push(kind, start, text.len() - r.len());
                rest = r;
                continue;
            }
            if self.foreign_comment(rest) {
                self.flush_junk();
                let len = rest.find(['\n', '\r']).unwrap_or(rest.len());
                let marker = rest.get(..1).unwrap_or("#");
                self.report(
                    Diagnostic::error("BG0104", format!("invalid character {marker:?}"))
                        .with_primary(
                            self.span(start, start + len),
                            "a comment as other languages write it",
                        )
                        .with_help("comments start with `//`; the rest of this line is skipped"),
                );
                rest = rest.get(len..).unwrap_or("");
                continue;
            }
            if let Some((len, text)) = super::typographic::quoted(rest) {
                self.flush_junk();
                self.typographic_string(start, len, text);
                rest = rest.get(len..).unwrap_or("");
                continue;
            }
            if let Some((len, stand_in, help)) = super::typographic::stand_in(rest) {
                self.flush_junk();
                self.typographic(start, start + len, stand_in, help);
                rest = rest.get(len..).unwrap_or("");
                continue;
            }
            if let Some(len) = super::foreign::name_len(rest) {
                self.flush_junk();
                self.foreign_name(start, start + len);
                rest = rest.get(len..).unwrap_or("");
                continue;
            }
            // Nothing starts here: extend the current run of invalid characters by one character.
            let width = rest.chars().next().map(char::len_utf8).unwrap_or(1);
            let end = start + width;
            self.junk = Some(match self.junk {
                Some((s, _)) => (s, end),
                None => (start, end),
            });
            self.at_line_start = false;
            rest = rest.get(width..).unwrap_or("");
        }
        self.flush_junk();
        let end = text.len();
        self.out.tokens.push(Token {
            kind: Tok::Eof,
            start: end as u32,
            end: end as u32,
        });
    }

    /// A name with letters outside ASCII from `start` to `end` (joined to an ASCII name just before it, as in
    /// `masse_é`): one error with the ASCII spelling when there is one, and one name token, so that the statement
    /// parses on.
    fn foreign_name(&mut self, start: usize, end: usize) {
        let start = match self.out.tokens.last() {
            Some(t) if t.kind == Tok::Ident && t.end as usize == start => {
                let joined = t.start as usize;
                self.out.tokens.pop();
                joined
            }
            _ => start,
        };
        let name = self.text.get(start..end).unwrap_or("");
        let (what, help, fix) = match self.in_unit() {
            true => (
                "unit",
                super::foreign::unit_help(name),
                super::foreign::unit_spelling(name),
            ),
            false => (
                "name",
                super::foreign::name_help(name),
                super::foreign::ascii_spelling(name),
            ),
        };
        let mut d = Diagnostic::error(
            "BG0104",
            format!("the {what} `{name}` has letters outside ASCII"),
        )
        .with_primary(
            self.span(start, end),
            format!("not a {what} of the language"),
        )
        .with_help(help);
        if let Some(fix) = fix {
            d = d.with_fix(fix);
        }
        self.report(d);
        self.push(Tok::Ident, start, end);
    }

    /// Whether the tokens so far leave a `[` open: a unit is being written. Asked only for a name with letters
    /// outside ASCII or a typographic character, so the common tokens pay nothing for it; a unit is a few tokens
    /// long, so the look back is bounded.
    fn in_unit(&self) -> bool {
        for t in self.out.tokens.iter().rev().take(64) {
            match t.kind {
                Tok::LBracket => return true,
                Tok::RBracket | Tok::Semi | Tok::LBrace | Tok::RBrace => return false,
                _ => {}
            }
        }
        false
    }

    /// The common tokens, recognised from their first byte without trying each parser in turn: whitespace, ASCII
    /// names, numbers and the punctuation that begins nothing else. Returns the rest of the text, or `None` to leave
    /// the text to the general parsers (comments, `/`, `.`, `-`, strings, names with `µ`, invalid characters).
    fn common(&mut self, start: usize, rest: &'a str) -> Option<&'a str> {
        let bytes = rest.as_bytes();
        let first = *bytes.first()?;
        let run = |from: usize, pred: fn(u8) -> bool| {
            from + bytes
                .get(from..)
                .unwrap_or(&[])
                .iter()
                .take_while(|&&b| pred(b))
                .count()
        };
        match first {
            b' ' | b'\t' | b'\r' | b'\n' | 0x0c => {
                let len = run(0, |b| matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0c));
                let (ws, r) = rest.split_at_checked(len)?;
                self.flush_junk();
                self.note_whitespace(start, ws);
                Some(r)
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                let len = run(1, |b| b.is_ascii_alphanumeric() || b == b'_');
                // A non-ASCII character may continue the name (`µ`): the general parser decides.
                if bytes.get(len).is_some_and(|b| !b.is_ascii()) {
                    return None;
                }
                self.flush_junk();
                self.push(Tok::Ident, start, start + len);
                rest.get(len..)
            }
            b'0'..=b'9' => {
                let (r, n) = number(rest).ok()?;
                self.flush_junk();
                Some(self.number(start, n, r))
            }
            // `->` is most of the `-` in bond statements.
            b'-' if bytes.get(1) == Some(&b'>') => {
                self.flush_junk();
                self.push(Tok::Arrow, start, start + 2);
                rest.get(2..)
            }
            // `.`, `-` and `/` may begin a number or a comment: left to the general parsers.
            b'.' | b'-' | b'/' => None,
            _ => {
                let kind = one_char_punct(first)?;
                self.flush_junk();
                self.push(kind, start, start + 1);
                rest.get(1..)
            }
        }
    }

    /// Records blank lines: a newline followed by only whitespace and another newline.
    fn note_whitespace(&mut self, start: usize, ws: &str) {
        let mut newlines = 0;
        for (i, c) in ws.char_indices() {
            if c == '\n' {
                newlines += 1;
                self.at_line_start = true;
                if newlines == 2 {
                    self.out.blank_lines.push((start + i) as u32);
                }
            }
        }
    }

    fn comment(&mut self, start: usize, c: &str) {
        let doc = c.starts_with("///") && !c.starts_with("////");
        self.out.comments.push(RawComment {
            text: c.trim_end().to_string(),
            start: start as u32,
            end: (start + c.len()) as u32,
            doc,
            own_line: self.at_line_start,
        });
        self.at_line_start = false;
    }

    /// Checks a recognised number: malformed continuations (`1.2.3`, `1e`, `2x`) and non-finite values.
    fn number(&mut self, start: usize, n: &'a str, r: &'a str) -> &'a str {
        // A number glued to more digits, dots or letters is one malformed literal, not several tokens.
        let glued = r
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
            .unwrap_or(r.len());
        let (tail, rest) = r.split_at(glued);
        let end = start + n.len() + tail.len();
        let span = self.span(start, end);
        let literal = self.text.get(start..end).unwrap_or(n);
        let exponent_without_digits = n.ends_with(['e', 'E', '+', '-']);
        if !tail.is_empty() || exponent_without_digits {
            let (msg, help) = if tail.starts_with('.') || n.matches('.').count() > 1 {
                (
                    format!("malformed number `{literal}`: more than one decimal point"),
                    "a number has at most one `.`, as in `1.25`",
                )
            } else if exponent_without_digits {
                (
                    format!("malformed number `{literal}`: the exponent has no digits"),
                    "write the exponent's digits, as in `1e3` or `2.5E-4`",
                )
            } else {
                (
                    format!("malformed number `{literal}`"),
                    "separate a number from a name by a space or an operator, as in `2*x`; units go in brackets, as in `2 [kg]`",
                )
            };
            self.report(
                Diagnostic::error("BG0103", msg)
                    .with_primary(span, "not a valid number")
                    .with_help(help),
            );
            self.push_number(start, end, 0.0);
            return rest;
        }
        match n.parse::<f64>() {
            Ok(v) if v.is_finite() => self.push_number(start, end, v),
            _ => {
                self.report(
                    Diagnostic::error("BG0103", format!("number `{literal}` is not finite"))
                        .with_primary(span, "too large to be represented as a 64-bit float")
                        .with_help("numbers must be finite; the largest is about 1.8e308"),
                );
                self.push_number(start, end, 0.0);
            }
        }
        rest
    }

    /// Lexes a string starting at `rest` (which starts with `"`). A string ends at its closing quote; a line break
    /// or the end of the file before it makes it unterminated.
    fn string(&mut self, start: usize, rest: &'a str) -> &'a str {
        let mut value = String::new();
        let mut chars = rest.char_indices().skip(1);
        let mut end = None;
        while let Some((i, c)) = chars.next() {
            match c {
                '"' => {
                    end = Some(i + 1);
                    break;
                }
                '\n' | '\r' => break,
                '\\' => match chars.next() {
                    Some((_, '"')) => value.push('"'),
                    Some((_, '\\')) => value.push('\\'),
                    Some((j, other)) if other != '\n' && other != '\r' => {
                        let esc = self.span(start + i, start + j + other.len_utf8());
                        self.report(
                            Diagnostic::error(
                                "BG0112",
                                format!("unknown escape `\\{other}` in a string"),
                            )
                            .with_primary(esc, "not an escape")
                            .with_help("the escapes are `\\\"` (a quote) and `\\\\` (a backslash)"),
                        );
                        value.push(other);
                    }
                    _ => break,
                },
                c if is_unprintable(c) => {
                    self.unprintable_in_string(start + i, c);
                    value.push(stand_in(c));
                }
                c => value.push(c),
            }
        }
        self.out.strings.push((start as u32, value));
        match end {
            Some(len) => {
                self.push(Tok::Str, start, start + len);
                rest.get(len..).unwrap_or("")
            }
            None => {
                let len = rest.find(['\n', '\r']).unwrap_or(rest.len());
                self.report(
                    Diagnostic::error("BG0102", "unterminated string")
                        .with_primary(self.span(start, start + len), "this string has no closing `\"`")
                        .with_help("close the string with `\"` on the same line; write a quote inside it as `\\\"`"),
                );
                self.push(Tok::Str, start, start + len);
                self.out.unterminated.push(start as u32);
                rest.get(len..).unwrap_or("")
            }
        }
    }

    /// A control character or a direction override inside a string at `at`: an error whose fix removes it. The
    /// string keeps a visible stand-in, so that no message or generated file quoting it holds the character.
    fn unprintable_in_string(&mut self, at: usize, c: char) {
        let span = self.span(at, at + c.len_utf8());
        self.report(
            Diagnostic::error("BG0104", format!("invalid character {:?} in a string", c.to_string()))
                .with_primary(span, "not allowed in a string")
                .with_help("strings hold printable text: a control character or a direction override would show the text other than it is, in a terminal, an editor or an FMU's description; remove it")
                .with_fix(""),
        );
    }

    /// A typographic character (`·`, `²`, `→`, ...; see [`super::typographic`]): one error, and the tokens of what it
    /// stands for.
    fn typographic(&mut self, start: usize, end: usize, stand_in: StandIn, help: &'static str) {
        let shown = self.text.get(start..end).unwrap_or("");
        let msg = match shown.chars().count() {
            1 => format!("invalid character {shown:?}"),
            _ => format!("invalid characters {shown:?}"),
        };
        let in_unit = stand_in == StandIn::Product && self.in_unit();
        self.report(
            Diagnostic::error("BG0104", msg)
                .with_primary(self.span(start, end), "not part of the language")
                .with_help(help)
                .with_fix(stand_in.ascii(in_unit)),
        );
        match stand_in {
            StandIn::Token(kind, _) => self.push(kind, start, end),
            // Factors of a unit are separated by a space.
            StandIn::Product if in_unit => {}
            StandIn::Product => self.push(Tok::Star, start, end),
            StandIn::Power(p) => {
                self.push(Tok::Caret, start, start);
                if p < 0 {
                    self.push(Tok::Minus, start, start);
                }
                self.push_number(start, end, f64::from(p.unsigned_abs()));
            }
            StandIn::Space => {}
        }
    }

    /// A string between typographic quotes (`“moving mass”`): one error, and the string.
    fn typographic_string(&mut self, start: usize, len: usize, text: &str) {
        self.report(
            Diagnostic::error("BG0104", "a string between typographic quotes")
                .with_primary(self.span(start, start + len), "not part of the language")
                .with_help(format!("write it between ASCII quotes: \"{text}\""))
                .with_fix(format!("\"{}\"", text.replace('\\', "\\\\"))),
        );
        self.out.strings.push((start as u32, text.to_string()));
        self.push(Tok::Str, start, start + len);
    }

    /// A `#` (Python, shell) or `%` (MATLAB) that starts a line or follows the end of a statement: a comment in
    /// another language's syntax, whose words would otherwise each be an error. Inside a statement (`800 # [N/m]`,
    /// `[%]`) it is an invalid character like any other.
    fn foreign_comment(&self, rest: &str) -> bool {
        matches!(rest.chars().next(), Some('#' | '%'))
            && (self.at_line_start
                || self
                    .out
                    .tokens
                    .last()
                    .is_some_and(|t| matches!(t.kind, Tok::Semi | Tok::LBrace | Tok::RBrace)))
    }
}

/// What to write for a character that word processors, papers and other tools use in formulas and units.
fn typographic_help(c: char) -> Option<&'static str> {
    Some(match c {
        '°' => "write degrees as `deg`, as in `[deg]` or `[deg/s]`",
        '%' => {
            "there is no percent sign: write a fraction, dimensionless (`[1]`), as in `0.5` for 50 %"
        }
        '<' | '>' => {
            "a bond is written `bond a -> b;` (power from `a` to `b`); expressions have no comparisons, but \
             `min(a, b)`, `max(a, b)` and `sign(x)`"
        }
        _ => return None,
    })
}
