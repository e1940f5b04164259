//! The parser's core: the token cursor, error reporting, recovery and doc comments.
//!
//! The parser reads the lexer's tokens by recursive descent. A parse function returns `Err(Fail)` after it has
//! recorded a diagnostic; the statement (or law, or item) that contains it then skips to a synchronisation point
//! (the next `;` or the `}` closing the enclosing block, at the same brace depth, or a statement keyword that starts a
//! line) and parsing continues, so one run reports many errors and the tree keeps every statement that parsed.
//! Expression nesting is counted and capped at [`MAX_DEPTH`], so no input can overflow the stack. Every loop
//! consumes at least one token per turn, so parsing is linear in the number of tokens.

use super::ast::{self, Comment, Ident};
use super::lexer::{self, RawComment, Tok, Token};
use crate::diagnostic::Diagnostic;
use crate::span::{FileId, Span};

/// The deepest nesting of expressions (parentheses, unary minus, powers, call arguments) the parser accepts.
pub const MAX_DEPTH: usize = 200;

/// The keywords, written once: [`KEYWORDS`] lists them, and [`is_keyword`] is a `match` over the same words (it
/// compiles to a switch on length and bytes; every name the parser reads is checked, so a scan of the list would
/// cost more).
macro_rules! keywords {
    ($($word:literal),* $(,)?) => {
        /// Words that cannot be used as names.
        pub const KEYWORDS: &[&str] = &[$($word),*];

        /// Whether `s` is one of [`KEYWORDS`].
        pub fn is_keyword(s: &str) -> bool {
            matches!(s, $($word)|*)
        }
    };
}

keywords! {
    "model",
    "component",
    "param",
    "input",
    "output",
    "var",
    "bond",
    "port",
    "import",
    "domain",
    "coords",
    "allow",
    "hint",
    "stroke",
    "Se",
    "Sf",
    "MSe",
    "MSf",
    "C",
    "I",
    "R",
    "TF",
    "GY",
    "MTF",
    "MGY",
    "CF",
    "RF",
    "IF",
}

/// The keywords that never begin a statement: `stroke` (a bond's causality hint, inside the bond statement) and the
/// reserved `hint`. Every other keyword begins a statement or an item, and recovery stops before one that starts a
/// line.
const CLAUSE_KEYWORDS: &[&str] = &["hint", "stroke"];

/// A diagnostic has been recorded; the caller recovers.
#[derive(Debug)]
pub struct Fail;

pub type PResult<T> = Result<T, Fail>;

pub struct Parser<'a> {
    pub(super) file: FileId,
    pub(super) text: &'a str,
    pub(super) toks: Vec<Token>,
    numbers: Vec<(u32, f64)>,
    strings: Vec<(u32, String)>,
    unterminated: Vec<u32>,
    pub(super) pos: usize,
    pub(super) diags: Vec<Diagnostic>,
    pub(super) depth: usize,
    docs: Vec<RawComment>,
    next_doc: usize,
    comments: Vec<Comment>,
    /// What the failed statements of the body being read declared; taken when the body ends.
    pub(super) unparsed: ast::Unparsed,
}

/// Parses a whole file. See [`crate::syntax::parse`].
pub fn parse_file(file: FileId, text: &str) -> (ast::File, Vec<Diagnostic>) {
    let lexed = lexer::lex(file, text);
    let (docs, plain): (Vec<RawComment>, Vec<RawComment>) =
        lexed.comments.into_iter().partition(|c| c.doc);
    let comments = plain
        .into_iter()
        .map(|c| Comment {
            text: c.text,
            span: Span::new(file, c.start as usize, c.end as usize),
            own_line: c.own_line,
        })
        .collect();
    let mut p = Parser {
        file,
        text,
        toks: lexed.tokens,
        numbers: lexed.numbers,
        strings: lexed.strings,
        unterminated: lexed.unterminated,
        pos: 0,
        diags: lexed.diagnostics,
        depth: 0,
        docs,
        next_doc: 0,
        comments,
        unparsed: ast::Unparsed::default(),
    };
    let items = p.items();
    p.stray_docs_before(u32::MAX);
    let mut comments = std::mem::take(&mut p.comments);
    comments.sort_by_key(|c| c.span.start);
    let mut diags = p.diags;
    diags.sort_by_key(|d| d.primary_span().map(|s| s.start).unwrap_or(0));
    (
        ast::File {
            items,
            comments,
            blank_lines: lexed.blank_lines,
        },
        diags,
    )
}

impl<'a> Parser<'a> {
    // ----- the cursor -----

    pub(super) fn peek(&self) -> Token {
        self.nth(0)
    }

    /// The token `k` places ahead (the end-of-file token beyond the end).
    pub(super) fn nth(&self, k: usize) -> Token {
        let last = self.toks.len().saturating_sub(1);
        self.toks
            .get((self.pos + k).min(last))
            .copied()
            .unwrap_or(Token {
                kind: Tok::Eof,
                start: self.text.len() as u32,
                end: self.text.len() as u32,
            })
    }

    pub(super) fn bump(&mut self) -> Token {
        let t = self.peek();
        if t.kind != Tok::Eof {
            self.pos += 1;
        }
        t
    }

    pub(super) fn at(&self, kind: Tok) -> bool {
        self.peek().kind == kind
    }

    pub(super) fn eat(&mut self, kind: Tok) -> Option<Token> {
        if self.at(kind) {
            Some(self.bump())
        } else {
            None
        }
    }

    /// The value of a number token (0 for a malformed one, already reported).
    pub(super) fn number_value(&self, t: Token) -> f64 {
        match self
            .numbers
            .binary_search_by_key(&t.start, |&(start, _)| start)
        {
            Ok(i) => self.numbers.get(i).map_or(0.0, |&(_, v)| v),
            Err(_) => 0.0,
        }
    }

    /// The unescaped text of a string token.
    pub(super) fn string_value(&self, t: Token) -> String {
        match self
            .strings
            .binary_search_by_key(&t.start, |(start, _)| *start)
        {
            Ok(i) => self
                .strings
                .get(i)
                .map(|(_, s)| s.clone())
                .unwrap_or_default(),
            Err(_) => String::new(),
        }
    }

    pub(super) fn tok_text(&self, t: Token) -> &'a str {
        self.text
            .get(t.start as usize..t.end as usize)
            .unwrap_or("")
    }

    /// The current token is the name `word`.
    pub(super) fn at_word(&self, word: &str) -> bool {
        let t = self.peek();
        t.kind == Tok::Ident && self.tok_text(t) == word
    }

    pub(super) fn span(&self, start: u32, end: u32) -> Span {
        Span::new(self.file, start as usize, end as usize)
    }

    pub(super) fn tok_span(&self, t: Token) -> Span {
        self.span(t.start, t.end)
    }

    /// The last consumed token.
    pub(super) fn previous(&self) -> Option<Token> {
        self.pos
            .checked_sub(1)
            .and_then(|i| self.toks.get(i))
            .copied()
    }

    /// End of the last consumed token.
    pub(super) fn prev_end(&self) -> u32 {
        self.previous().map_or(0, |t| t.end)
    }

    /// From `start` to the end of the last consumed token.
    pub(super) fn span_from(&self, start: u32) -> Span {
        self.span(start, self.prev_end().max(start))
    }

    /// The token is the first on its line.
    pub(super) fn starts_line(&self, t: Token) -> bool {
        let before = self.pos_before(t);
        self.text
            .get(before as usize..t.start as usize)
            .is_some_and(|gap| gap.contains('\n'))
            || before == 0
    }

    /// End of the token before `t` (assumes `t` is the current token or later).
    fn pos_before(&self, t: Token) -> u32 {
        let idx = self.toks.partition_point(|x| x.start < t.start);
        if idx == 0 {
            0
        } else {
            self.toks.get(idx - 1).map(|x| x.end).unwrap_or(0)
        }
    }

    pub(super) fn is_statement_keyword(&self, t: Token) -> bool {
        if t.kind != Tok::Ident {
            return false;
        }
        let text = self.tok_text(t);
        is_keyword(text) && !CLAUSE_KEYWORDS.contains(&text)
    }

    // ----- diagnostics -----

    /// How a token is named in messages.
    pub(super) fn describe(&self, t: Token) -> String {
        let text = self.tok_text(t);
        match t.kind {
            Tok::Ident if is_keyword(text) => format!("keyword `{text}`"),
            Tok::Ident => format!("`{}`", shorten(text)),
            Tok::Number => format!("number `{}`", shorten(text)),
            Tok::Str => "a string".to_string(),
            other => other.describe().to_string(),
        }
    }

    /// Records "expected X, found Y" at the current token.
    pub(super) fn expected(&mut self, what: &str, help: &str) -> Fail {
        let t = self.peek();
        let found = self.describe(t);
        let d = Diagnostic::error("BG0101", format!("expected {what}, found {found}"))
            .with_primary(self.tok_span(t), format!("expected {what}"))
            .with_help(help.to_string());
        self.diags.push(d);
        Fail
    }

    pub(super) fn expect(&mut self, kind: Tok, what: &str, help: &str) -> PResult<Token> {
        match self.eat(kind) {
            Some(t) => Ok(t),
            None => Err(self.expected(what, help)),
        }
    }

    /// Expects the `;` that ends a statement. When the next token begins a new line or a statement, closes a block or
    /// ends the file, the statement is complete and only the `;` is missing: the error points just after the statement and parsing
    /// goes on as if the `;` were there.
    pub(super) fn expect_semi(&mut self, what: &str) -> PResult<()> {
        if self.eat(Tok::Semi).is_some() {
            return Ok(());
        }
        let t = self.peek();
        let after_unterminated = self.previous().is_some_and(|p| {
            p.kind == Tok::Str && self.unterminated.binary_search(&p.start).is_ok()
        });
        if after_unterminated && (self.starts_line(t) || matches!(t.kind, Tok::RBrace | Tok::Eof)) {
            // The unterminated string swallowed the rest of its line, `;` included; it is reported already.
            return Ok(());
        }
        if self.starts_line(t)
            || self.is_statement_keyword(t)
            || matches!(t.kind, Tok::RBrace | Tok::Eof)
        {
            let end = self.prev_end();
            let found = self.describe(t);
            let mut d = Diagnostic::error(
                "BG0101",
                format!("expected `;` after {what}, found {found}"),
            )
            .with_primary(self.span(end, end), "expected `;` here");
            if self.is_statement_keyword(t) || (self.starts_line(t) && t.kind == Tok::Ident) {
                d = d.with_secondary(self.tok_span(t), "the next statement starts here");
            }
            self.diags.push(d.with_help("end every statement with `;`"));
            return Ok(());
        }
        let help = self
            .unit_after_value()
            .unwrap_or("end every statement with `;`");
        Err(self.expected(&format!("`;` after {what}"), help))
    }

    /// Reads a name being declared or referred to. A keyword or a name with non-ASCII letters is reported but
    /// accepted, so that the rest of the statement is still checked.
    pub(super) fn expect_name(&mut self, what: &str) -> PResult<Ident> {
        self.expect_name_for(|| what.to_string())
    }

    /// [`Parser::expect_name`] with the description of what is expected built only when it is missing: a name is
    /// read for every element, and the description would otherwise be formatted each time.
    pub(super) fn expect_name_for(&mut self, what: impl FnOnce() -> String) -> PResult<Ident> {
        let t = self.peek();
        if t.kind != Tok::Ident {
            return Err(self.expected(
                &what(),
                "a name is a letter or `_` followed by letters, digits and `_`",
            ));
        }
        self.bump();
        let text = self.tok_text(t);
        let span = self.tok_span(t);
        if is_keyword(text) {
            self.diags.push(
                Diagnostic::error(
                    "BG0109",
                    format!("keyword `{text}` cannot be used as a name"),
                )
                .with_primary(span, "this is a keyword")
                .with_help(format!(
                    "choose another name, such as `{text}_1` or `my_{text}`"
                )),
            );
        } else if !text.is_ascii() && !super::foreign::reported_by_lexer(text) {
            self.diags.push(
                Diagnostic::error("BG0104", format!("name `{text}` has a non-ASCII character"))
                    .with_primary(span, "names are ASCII")
                    .with_help(
                        "names are ASCII letters, digits and `_` (`µ` is only a unit prefix)",
                    ),
            );
        }
        Ok(Ident {
            name: text.to_string(),
            span,
        })
    }

    /// Skips to the end of a failed statement: past the next `;`, or before the `}` that closes the enclosing block, a
    /// statement keyword that starts a line, or the end of the file. Braces opened while skipping are skipped whole.
    pub(super) fn recover(&mut self) {
        let mut depth = 0usize;
        loop {
            let t = self.peek();
            match t.kind {
                Tok::Eof => return,
                Tok::Semi if depth == 0 => {
                    self.bump();
                    return;
                }
                Tok::RBrace if depth == 0 => return,
                Tok::RBrace => depth -= 1,
                Tok::LBrace => depth += 1,
                Tok::Ident if depth == 0 && self.is_statement_keyword(t) && self.starts_line(t) => {
                    return;
                }
                _ => {}
            }
            self.bump();
        }
    }

    // ----- doc comments -----

    /// Takes the doc comments between the previous token and the current one. Earlier doc comments not taken by
    /// anything (inside a statement, say) are reported as documenting nothing.
    pub(super) fn take_docs(&mut self) -> Vec<(String, Span, bool)> {
        let start = self.peek().start;
        let prev = self.prev_end();
        self.stray_docs_before(prev);
        let mut out = Vec::new();
        while let Some(d) = self.docs.get(self.next_doc) {
            if d.start >= start {
                break;
            }
            let text = d.text.get(3..).unwrap_or("");
            let text = text.strip_prefix(' ').unwrap_or(text);
            out.push((text.to_string(), self.span(d.start, d.end), d.own_line));
            self.next_doc += 1;
        }
        out
    }

    /// Reports doc comments that precede something that takes no documentation, and keeps them as comments.
    pub(super) fn reject_docs(&mut self, docs: Vec<(String, Span, bool)>, what: &str) {
        for (text, span, own_line) in docs {
            self.stray_doc(text, span, own_line, what);
        }
    }

    fn stray_docs_before(&mut self, limit: u32) {
        while let Some(d) = self.docs.get(self.next_doc) {
            if d.start >= limit {
                break;
            }
            let text = d.text.get(3..).unwrap_or("");
            let text = text.strip_prefix(' ').unwrap_or(text).to_string();
            let span = self.span(d.start, d.end);
            let own_line = d.own_line;
            self.next_doc += 1;
            self.stray_doc(text, span, own_line, "nothing");
        }
    }

    fn stray_doc(&mut self, text: String, span: Span, own_line: bool, what: &str) {
        self.diags.push(
            Diagnostic::warning("BG0114", format!("doc comment documents {what}"))
                .with_primary(span, "this doc comment is not attached to a declaration")
                .with_help(
                    "put `///` comments right before a model, component, param, input, output, var, element or \
                     instance; use `//` for other comments",
                ),
        );
        let text = if text.is_empty() {
            "//".to_string()
        } else {
            format!("// {text}")
        };
        self.comments.push(Comment {
            text,
            span,
            own_line,
        });
    }
}

/// A token's text cut short for messages (a megabyte-long name should not fill the screen).
fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let cut: String = s.chars().take(MAX).collect();
        format!("{cut}...")
    }
}
