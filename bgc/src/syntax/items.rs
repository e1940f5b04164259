//! Files: imports, models and components, and the blocks that hold their statements.

use super::ast::{self, Ident, Item};
use super::lexer::{Tok, Token};
use super::parser::{Fail, Parser};
use crate::diagnostic::Diagnostic;
use crate::span::Span;

/// The syntax errors after which a file is no longer read: a file of garbage would otherwise make one per statement
/// (the 64 MiB a file may have, gigabytes of diagnostics); the text rendering shows 100.
pub(super) const MAX_SYNTAX_ERRORS: usize = 1000;

impl Parser<'_> {
    /// The items of the file up to its end; junk between items is reported and skipped.
    pub(super) fn items(&mut self) -> Vec<Item> {
        let mut items = Vec::new();
        loop {
            let t = self.peek();
            match t.kind {
                Tok::Eof => break,
                Tok::Semi => {
                    // An empty statement has no meaning.
                    self.bump();
                }
                Tok::Ident if matches!(self.tok_text(t), "model" | "component") => {
                    let docs = self.take_docs();
                    items.push(Item::Model(self.model(docs)));
                }
                Tok::Ident if self.tok_text(t) == "import" => {
                    let docs = self.take_docs();
                    self.reject_docs(docs, "an import");
                    if let Some(import) = self.import() {
                        items.push(Item::Import(import));
                    }
                }
                Tok::RBrace | Tok::RParen | Tok::RBracket => {
                    self.bump();
                    self.diags.push(
                        Diagnostic::error("BG0111", format!("unmatched {}", t.kind.describe()))
                            .with_primary(self.tok_span(t), "this closes nothing")
                            .with_help(
                                "remove it, or add the opening bracket it was meant to close",
                            ),
                    );
                }
                _ => {
                    let help = if self.is_statement_keyword(t) || t.kind == Tok::Number {
                        "statements belong inside a `model NAME { ... }` or `component NAME { ... }`"
                    } else {
                        "a file holds `import \"FILE\";` lines and `model` and `component` declarations"
                    };
                    let _ = self.expected("`model`, `component` or `import`", help);
                    self.skip_to_item();
                }
            }
        }
        items
    }

    /// Skips junk at the top level up to the next `model`, `component` or `import` outside braces.
    fn skip_to_item(&mut self) {
        let mut depth = 0usize;
        self.bump();
        loop {
            let t = self.peek();
            match t.kind {
                Tok::Eof => return,
                Tok::LBrace => depth += 1,
                Tok::RBrace => depth = depth.saturating_sub(1),
                Tok::Ident
                    if depth == 0
                        && matches!(self.tok_text(t), "model" | "component" | "import") =>
                {
                    return;
                }
                _ => {}
            }
            self.bump();
        }
    }

    fn import(&mut self) -> Option<ast::Import> {
        let kw = self.bump();
        let result = (|| {
            let t = self.peek();
            let path = match t.kind {
                Tok::Str => {
                    let t = self.bump();
                    self.string_value(t)
                }
                _ => {
                    return Err(self.expected(
                        "the path of the imported file as a string",
                        "write `import \"std.bg\";` or a path relative to this file",
                    ));
                }
            };
            self.expect_semi("the import")?;
            Ok(path)
        })();
        match result {
            Ok(path) => Some(ast::Import {
                path,
                span: self.span_from(kw.start),
            }),
            Err(Fail) => {
                self.recover();
                None
            }
        }
    }

    fn model(&mut self, docs: Vec<(String, Span, bool)>) -> ast::ModelDecl {
        let kw = self.bump();
        let kind = if self.tok_text(kw) == "model" {
            ast::ModelKind::Model
        } else {
            ast::ModelKind::Component
        };
        let word = self.tok_text(kw);
        let name = match self.expect_name(&format!("the name of the {word}")) {
            Ok(n) => n,
            Err(Fail) => {
                // `model 3 { ... }`: step over the bad name so the body is still read.
                if !self.at(Tok::LBrace) && self.nth(1).kind == Tok::LBrace {
                    self.bump();
                }
                Ident {
                    name: String::new(),
                    span: self.span(kw.end, kw.end),
                }
            }
        };
        let body = match self.eat(Tok::LBrace) {
            Some(open) => self.block_body(open, word),
            None => {
                let _ = self.expected(
                    &format!("`{{` to open the body of the {word}"),
                    &format!(
                        "write `{word} {} {{ ... }}`",
                        if name.name.is_empty() {
                            "NAME"
                        } else {
                            &name.name
                        }
                    ),
                );
                self.recover();
                Vec::new()
            }
        };
        ast::ModelDecl {
            kind,
            doc: docs.into_iter().map(|(t, _, _)| t).collect(),
            name,
            body,
            unparsed: std::mem::take(&mut self.unparsed),
            span: self.span_from(kw.start),
        }
    }

    /// The statements of a model or component body, up to and including its `}`.
    fn block_body(&mut self, open: Token, word: &str) -> Vec<ast::Stmt> {
        let mut body = Vec::new();
        loop {
            let t = self.peek();
            match t.kind {
                Tok::RBrace => {
                    self.bump();
                    break;
                }
                Tok::Eof => {
                    self.unclosed(open, t, word);
                    break;
                }
                Tok::Ident if matches!(self.tok_text(t), "model" | "component" | "import") => {
                    self.unclosed(open, t, word);
                    break;
                }
                Tok::Semi => {
                    // An empty statement has no meaning.
                    self.bump();
                }
                _ if self.diags.len() >= MAX_SYNTAX_ERRORS => {
                    self.give_up(t);
                    break;
                }
                _ => {
                    if let Some(s) = self.statement() {
                        body.push(s);
                    }
                }
            }
        }
        body
    }

    /// Stops reading the file after [`MAX_SYNTAX_ERRORS`]: the rest is skipped with one error that says so.
    fn give_up(&mut self, at: Token) {
        self.diags.push(
            Diagnostic::error(
                "BG0101",
                format!(
                    "more than {MAX_SYNTAX_ERRORS} syntax errors: the rest of the file is not read"
                ),
            )
            .with_primary(self.tok_span(at), "reading stopped here")
            .with_help("fix the errors above, or check that this is a `.bg` file"),
        );
        while self.peek().kind != Tok::Eof {
            self.bump();
        }
    }

    /// Reports a block whose `}` is missing when `found` (end of file or something that cannot be inside it) is met.
    pub(super) fn unclosed(&mut self, open: Token, found: Token, what: &str) {
        let found_desc = self.describe(found);
        let at = if found.kind == Tok::Eof {
            self.span(found.start, found.end)
        } else {
            self.tok_span(found)
        };
        self.diags.push(
            Diagnostic::error(
                "BG0106",
                format!("unclosed `{{` of the {what}: expected `}}`, found {found_desc}"),
            )
            .with_primary(at, "expected `}` before this")
            .with_secondary(self.tok_span(open), "this `{` is never closed")
            .with_help(format!("close the {what} with `}}`")),
        );
    }
}
