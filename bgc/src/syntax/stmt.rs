//! Statements of model and component bodies: declarations, elements, instances, bonds and ports.

use super::ast::*;
use super::lexer::Tok;
use super::parser::{Fail, PResult, Parser};
use crate::diagnostic::Diagnostic;
use crate::span::Span;

type Docs = Vec<(String, Span, bool)>;

impl<'a> Parser<'a> {
    /// Parses one statement; on a syntax error records it, skips the statement and returns `None`.
    pub(super) fn statement(&mut self) -> Option<Stmt> {
        let start_pos = self.pos;
        let docs = self.take_docs();
        let first = self.pos;
        match self.statement_inner(docs) {
            Ok(s) => Some(s),
            Err(Fail) => {
                self.recover();
                self.note_unparsed(first);
                if self.pos == start_pos {
                    self.bump();
                }
                None
            }
        }
    }

    /// Records what the failed statement from token `first` to the cursor declared: the name after its keyword or
    /// element kind (`param m`, `I mass`, `0 j`), or the instance name after a component's name (`Leg left`); for a
    /// `bond` statement, the names it bonds.
    fn note_unparsed(&mut self, first: usize) {
        let (Some(&lead), Some(&next)) = (self.toks.get(first), self.toks.get(first + 1)) else {
            return;
        };
        let word = self.tok_text(lead);
        if lead.kind == Tok::Ident && word == "domain" {
            self.unparsed.domain = true;
            return;
        }
        if lead.kind == Tok::Ident && word == "bond" {
            for k in first + 1..self.pos.min(self.toks.len()) {
                let t = self.toks[k];
                let name = self.tok_text(t);
                if t.kind == Tok::Ident && !super::parser::is_keyword(name) {
                    self.unparsed.bonded.push(Ident {
                        name: name.to_string(),
                        span: self.tok_span(t),
                    });
                }
            }
            return;
        }
        let declares = match lead.kind {
            Tok::Number => ElementKind::from_keyword(word).is_some(),
            Tok::Ident => {
                matches!(word, "param" | "input" | "output" | "var")
                    || ElementKind::from_keyword(word).is_some()
                    || !super::parser::is_keyword(word)
            }
            _ => false,
        };
        let name = self.tok_text(next);
        if declares && next.kind == Tok::Ident && !super::parser::is_keyword(name) {
            self.unparsed.names.push(Ident {
                name: name.to_string(),
                span: self.tok_span(next),
            });
        }
    }

    fn statement_inner(&mut self, docs: Docs) -> PResult<Stmt> {
        let t = self.peek();
        let start = t.start;
        if t.kind == Tok::Number {
            let text = self.tok_text(t);
            return match ElementKind::from_keyword(text) {
                Some(kind) => self.element(docs, kind).map(|e| Stmt::Element(Box::new(e))),
                None => Err(self.expected(
                    "a statement",
                    "a junction is `0 NAME;` or `1 NAME;`; other statements start with a keyword",
                )),
            };
        }
        if t.kind != Tok::Ident {
            return Err(self.expected(
                "a statement",
                "statements are declarations (`param`, `input`, `output`, `var`), elements, instances, `bond`, \
                 `port`, `domain` and `coords`",
            ));
        }
        let word = self.tok_text(t);
        if let Some(kind) = ElementKind::from_keyword(word) {
            return self.element(docs, kind).map(|e| Stmt::Element(Box::new(e)));
        }
        let docs = match word {
            "domain" | "coords" | "bond" | "port" | "allow" => {
                if !docs.is_empty() {
                    self.reject_docs(docs, &format!("a `{word}` statement"));
                }
                Vec::new()
            }
            _ => docs,
        };
        let stmt = match word {
            "domain" => {
                self.bump();
                let domain = self.expect_name("a domain name")?;
                self.expect_semi("the domain")?;
                Stmt::Domain(Box::new(DomainStmt {
                    domain,
                    span: self.span_from(start),
                }))
            }
            "param" => Stmt::Param(Box::new(self.param(docs)?)),
            "input" => {
                self.bump();
                let name = self.expect_name("the name of the input")?;
                let unit = self.unit()?;
                let description = self.description();
                if self.at(Tok::Eq) {
                    // `input u [N] = 0;`: an input's value comes from outside the model.
                    return Err(self.expected(
                        "`;` after the input",
                        "an input has no value in the file: it is given when the model runs (`bgc simulate \
                         --input NAME=EXPR`, or by the program that uses the generated code); a constant is a \
                         `param`",
                    ));
                }
                self.expect_semi("the input")?;
                Stmt::Input(Box::new(InputDecl {
                    doc: doc_text(docs),
                    name,
                    unit,
                    description,
                    span: self.span_from(start),
                }))
            }
            "output" => {
                self.bump();
                let name = self.expect_name("the name of the output")?;
                let unit = self.unit()?;
                self.expect(
                    Tok::Eq,
                    "`=` and the output's expression",
                    "write `output NAME [UNIT] = EXPR;`",
                )?;
                let value = self.expr()?;
                let description = self.description();
                self.expect_semi("the output")?;
                Stmt::Output(Box::new(OutputDecl {
                    doc: doc_text(docs),
                    name,
                    unit,
                    value,
                    description,
                    span: self.span_from(start),
                }))
            }
            "var" => Stmt::Var(Box::new(self.var(docs)?)),
            "coords" => {
                self.bump();
                let open = self.expect(
                    Tok::LBracket,
                    "`[` to open the list of coordinates",
                    "write `coords [x1, x2, ...];`",
                )?;
                let mut coords = vec![self.expr()?];
                while self.eat(Tok::Comma).is_some() {
                    coords.push(self.expr()?);
                }
                self.close(Tok::RBracket, open, "the list of coordinates")?;
                self.expect_semi("the coordinates")?;
                Stmt::Coords(Box::new(CoordsDecl {
                    coords,
                    span: self.span_from(start),
                }))
            }
            "bond" => Stmt::Bond(Box::new(self.bond()?)),
            "allow" => Stmt::Allow(Box::new(self.allow()?)),
            "port" => {
                self.bump();
                let name = self.expect_name("the name of the port")?;
                self.expect(
                    Tok::Eq,
                    "`=` and the node the port names",
                    "write `port NAME = NODE;`",
                )?;
                let target = self.node_ref()?;
                self.expect_semi("the port")?;
                Stmt::Port(Box::new(PortDecl {
                    name,
                    target,
                    span: self.span_from(start),
                }))
            }
            _ if super::parser::is_keyword(word) => {
                return Err(self.expected(
                    "a statement",
                    "`model`, `component` and `import` belong at the top level of a file",
                ));
            }
            _ => Stmt::Instance(Box::new(self.instance(docs)?)),
        };
        Ok(stmt)
    }

    /// `param NAME = EXPR [UNIT] ["description"];`
    fn param(&mut self, docs: Docs) -> PResult<ParamDecl> {
        let start = self.bump().start;
        let name = self.expect_name("the name of the parameter")?;
        self.expect(
            Tok::Eq,
            "`=` and the parameter's default value",
            "write `param NAME = VALUE [UNIT];`",
        )?;
        // The default is followed by its unit in brackets, so `n [1]` must not read as an index.
        let default = self.expr_no_index()?;
        let unit = self.unit()?;
        let description = self.description();
        self.expect_semi("the parameter")?;
        Ok(ParamDecl {
            doc: doc_text(docs),
            name,
            default,
            unit,
            description,
            span: self.span_from(start),
        })
    }

    /// `var NAME [UNIT] = int(FLOW);`
    fn var(&mut self, docs: Docs) -> PResult<VarDecl> {
        let start = self.bump().start;
        let name = self.expect_name("the name of the integrated flow")?;
        let unit = self.unit()?;
        self.expect(
            Tok::Eq,
            "`=` and `int(FLOW)`",
            "write `var NAME [UNIT] = int(f(x));`",
        )?;
        if !self.at_word("int") {
            return Err(self.expected(
                "`int(...)`",
                "a `var` is the integral of a flow: `var NAME [UNIT] = int(f(x));`",
            ));
        }
        self.bump();
        let open = self.expect(Tok::LParen, "`(` after `int`", "write `int(f(x))`")?;
        let integrand = self.expr()?;
        self.close(Tok::RParen, open, "the argument of `int`")?;
        self.expect_semi("the var")?;
        Ok(VarDecl {
            doc: doc_text(docs),
            name,
            unit,
            integrand,
            span: self.span_from(start),
        })
    }

    /// An optional description string.
    pub(super) fn description(&mut self) -> Option<String> {
        match self.peek().kind {
            Tok::Str => {
                let t = self.bump();
                Some(self.string_value(t))
            }
            _ => None,
        }
    }

    /// `KIND NAME[(n)] [: DOMAIN] [= EXPR | { LAW; ... }];`
    fn element(&mut self, docs: Docs, kind: ElementKind) -> PResult<ElementDecl> {
        let kw = self.bump();
        let kind_span = self.tok_span(kw);
        if self.at(Tok::Colon) {
            // `Se:source`, as 20-sim names elements.
            return Err(self.expected(
                &format!("the name of the `{}` element", kind.keyword()),
                &format!(
                    "write the kind, a space and the name: `{} source = ...;` (a domain follows the name: \
                     `{} source: electrical = ...;`)",
                    kind.keyword(),
                    kind.keyword()
                ),
            ));
        }
        let name =
            self.expect_name_for(|| format!("the name of the `{}` element", kind.keyword()))?;
        let mut ports = None;
        if let Some(open) = self.eat(Tok::LParen) {
            let n = self.positive_int("the number of ports")?;
            self.close(Tok::RParen, open, "the port count")?;
            if !kind.is_field() {
                self.diags.push(
                    Diagnostic::error(
                        "BG0117",
                        format!("{} element has no port count", kind.with_article()),
                    )
                    .with_primary(n.1, "only fields take a port count")
                    .with_help(
                        "only the multiport fields `CF`, `RF` and `IF` are written `KIND NAME(n)`",
                    ),
                );
            }
            ports = Some(n);
        } else if kind.is_field() {
            self.diags.push(
                Diagnostic::error(
                    "BG0117",
                    format!("the `{}` field needs its number of ports", kind.keyword()),
                )
                .with_primary(name.span, "the port count should follow this name")
                .with_help(format!(
                    "write `{} {}(2) {{ ... }}` for a two-port field",
                    kind.keyword(),
                    name.name
                )),
            );
        }
        let domain = if self.eat(Tok::Colon).is_some() {
            Some(self.expect_name("a domain name after `:`")?)
        } else {
            None
        };
        let body = if self.eat(Tok::Eq).is_some() {
            let value = self.expr()?;
            self.expect_semi("the element")?;
            ElementBody::Value(value)
        } else if let Some(open) = self.eat(Tok::LBrace) {
            let laws = self.laws(open);
            self.eat(Tok::Semi);
            ElementBody::Laws(laws)
        } else {
            if !self.at(Tok::Semi) {
                let t = self.peek();
                if !(self.starts_line(t) || t.kind == Tok::RBrace) {
                    return Err(self.expected(
                        "`=`, `{` or `;`",
                        "an element is `KIND NAME = VALUE;`, `KIND NAME { LAW; ... }` or, for a junction, `KIND NAME;`",
                    ));
                }
            }
            self.expect_semi("the element")?;
            ElementBody::None
        };
        Ok(ElementDecl {
            doc: doc_text(docs),
            kind,
            kind_span,
            name,
            ports,
            domain,
            body,
            span: self.span_from(kw.start),
        })
    }

    /// The laws of an element, after its `{`, up to and including the `}`.
    fn laws(&mut self, open: super::lexer::Token) -> Vec<Law> {
        let mut laws = Vec::new();
        loop {
            let t = self.peek();
            match t.kind {
                Tok::RBrace => {
                    self.bump();
                    break;
                }
                Tok::Semi => {
                    self.bump();
                }
                Tok::Eof => {
                    self.unclosed(open, t, "element's laws");
                    break;
                }
                Tok::Ident if self.is_statement_keyword(t) && self.starts_line(t) => {
                    self.unclosed(open, t, "element's laws");
                    break;
                }
                _ => {
                    let start_pos = self.pos;
                    let docs = self.take_docs();
                    self.reject_docs(docs, "a law");
                    match self.law() {
                        Ok(l) => laws.push(l),
                        Err(Fail) => {
                            self.recover();
                            if self.pos == start_pos {
                                self.bump();
                            }
                        }
                    }
                }
            }
        }
        laws
    }

    /// `LHS[i, j] = EXPR;`
    fn law(&mut self) -> PResult<Law> {
        let start = self.peek().start;
        let lhs = self.expect_name("a law such as `e = ...`")?;
        let mut indices = Vec::new();
        if let Some(open) = self.eat(Tok::LBracket) {
            indices.push(self.positive_int("an index")?);
            while self.eat(Tok::Comma).is_some() {
                indices.push(self.positive_int("an index")?);
            }
            self.close(Tok::RBracket, open, "the indices")?;
        }
        self.expect(
            Tok::Eq,
            "`=` in the law",
            "a law is `VARIABLE = EXPR;`, as in `e = k*q;`",
        )?;
        let rhs = self.expr()?;
        self.expect_semi("the law")?;
        Ok(Law {
            lhs,
            indices,
            rhs,
            span: self.span_from(start),
        })
    }

    /// `COMPONENT NAME(p = EXPR, ...);` (the parentheses may be left out when nothing is overridden).
    fn instance(&mut self, docs: Docs) -> PResult<InstanceDecl> {
        let start = self.peek().start;
        let component = self.expect_name("a statement")?;
        if self.peek().kind != Tok::Ident {
            let help = match super::suggest::keyword_like(&component.name) {
                Some(kw) => format!("did you mean the keyword `{kw}`?"),
                None => "an instance of a component is `COMPONENT NAME(PARAM = VALUE, ...);`"
                    .to_string(),
            };
            return Err(self.expected(
                &format!("an instance name after `{}`", component.name),
                &help,
            ));
        }
        let name = self.expect_name("the name of the instance")?;
        if !matches!(self.peek().kind, Tok::LParen | Tok::Semi)
            && let Some(kw) = super::suggest::keyword_like(&component.name)
        {
            // `parm k = 1 [kg];` reads as an instance `k` of a component `parm`; the misspelling is the error.
            self.diags.push(
                Diagnostic::error(
                    "BG0101",
                    format!("expected a statement, found `{}`", component.name),
                )
                .with_primary(component.span, "not a keyword")
                .with_help(format!("did you mean the keyword `{kw}`?")),
            );
            return Err(Fail);
        }
        let mut overrides = Vec::new();
        if let Some(open) = self.eat(Tok::LParen) {
            if !self.at(Tok::RParen) {
                loop {
                    let p = self.expect_name("a parameter name to override")?;
                    self.expect(
                        Tok::Eq,
                        "`=` after the parameter name",
                        "an override is `PARAM = VALUE`",
                    )?;
                    let v = self.expr()?;
                    overrides.push((p, v));
                    if self.eat(Tok::Comma).is_none() {
                        break;
                    }
                }
            }
            self.close(Tok::RParen, open, "the overrides")?;
        }
        self.expect_semi("the instance")?;
        Ok(InstanceDecl {
            doc: doc_text(docs),
            component,
            name,
            overrides,
            span: self.span_from(start),
        })
    }
}

fn doc_text(docs: Docs) -> Vec<String> {
    docs.into_iter().map(|(t, _, _)| t).collect()
}
