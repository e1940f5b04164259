//! Expressions, units, node references and small integers.
//!
//! Expressions are parsed by precedence climbing over the grammar
//!
//! ```text
//! expr    = term (("+" | "-") term)*
//! term    = unary (("*" | "/") unary)*
//! unary   = "-" unary | power
//! power   = primary ("^" unary)?            (right-associative: a^b^c = a^(b^c); -a^2 = -(a^2))
//! primary = NUMBER | NAME | NAME "[" INT "]" | NAME "(" args ")" | "(" expr ")"
//! ```
//!
//! Binary chains are loops; nesting (parentheses, call arguments, unary minus, exponents) recurses. Both deepen the
//! tree, and the depth of the tree is capped at [`MAX_DEPTH`] (`BG0105`), so neither the parser nor any later walk of
//! an expression can overflow the stack.

use super::ast::*;
use super::lexer::{Tok, Token};
use super::parser::{Fail, MAX_DEPTH, PResult, Parser};
use crate::diagnostic::Diagnostic;
use crate::span::Span;

/// The help for a name right after a number (`2 kg`, `2 k`).
const NAME_AFTER_NUMBER: &str = "to multiply, write `*`, as in `2*k`; a unit is not written in an expression: a \
     quantity with a unit is a parameter, as in `param m = 2 [kg];`";

/// The help for a unit written inside an expression (`1/k [m/N]`, `(1 [m^2])`).
pub(super) const UNITS_IN_EXPRESSIONS: &str = "units are not written in an expression: an element's value takes its \
     unit from its kind and domain, and a parameter's, input's or output's unit follows its name, as in \
     `param k = 800 [N/m];`";

const EXPR_HELP: &str = "an expression is built from numbers, names, calls such as `f(x)` or `sin(x)`, parentheses \
                         and the operators `+ - * / ^`";

impl<'a> Parser<'a> {
    /// An expression.
    pub(super) fn expr(&mut self) -> PResult<Expr> {
        self.expr_with(true)
    }

    /// An expression in which `name[...]` is not an index (a parameter's default, which its unit follows).
    pub(super) fn expr_no_index(&mut self) -> PResult<Expr> {
        self.expr_with(false)
    }

    fn enter(&mut self) -> PResult<()> {
        self.enter_level(
            "nesting limit reached here",
            "split the expression using parameters or outputs, or remove redundant parentheses",
        )
    }

    /// One more operator of a `+ -` or `* /` chain: a long flat sum reaches the limit too, and needs other advice
    /// than nesting does.
    fn enter_chain(&mut self) -> PResult<()> {
        self.enter_level(
            "the limit is reached at this operator: each operator of a chain counts one level",
            "group the terms in parentheses, as in `(a + b + c) + (d + e + f)`: the depth is then about the number \
             of groups plus the length of the longest group, not the number of terms",
        )
    }

    fn enter_level(&mut self, label: &str, help: &str) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let t = self.peek();
            self.diags.push(
                Diagnostic::error(
                    "BG0105",
                    format!("expression nested too deeply (more than {MAX_DEPTH} levels)"),
                )
                .with_primary(self.tok_span(t), label.to_string())
                .with_help(help.to_string()),
            );
            self.depth -= 1;
            return Err(Fail);
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth = self.depth.saturating_sub(1);
    }

    fn expr_with(&mut self, index: bool) -> PResult<Expr> {
        self.enter()?;
        let r = self.additive(index);
        self.leave();
        r
    }

    fn additive(&mut self, index: bool) -> PResult<Expr> {
        self.chain(index, Self::term, |t| match t {
            Tok::Plus => Some(BinOp::Add),
            Tok::Minus => Some(BinOp::Sub),
            _ => None,
        })
    }

    fn term(&mut self, index: bool) -> PResult<Expr> {
        self.chain(index, Self::unary, |t| match t {
            Tok::Star => Some(BinOp::Mul),
            Tok::Slash => Some(BinOp::Div),
            _ => None,
        })
    }

    /// A left-associative chain `x op x op x ...`. Each operator deepens the tree by one level, so each counts
    /// against the nesting limit: a chain of thousands of terms would otherwise build a tree too deep to walk.
    fn chain(
        &mut self,
        index: bool,
        operand: fn(&mut Self, bool) -> PResult<Expr>,
        operator: fn(Tok) -> Option<BinOp>,
    ) -> PResult<Expr> {
        let mut levels = 0;
        let result = (|| {
            let mut lhs = operand(self, index)?;
            while let Some(op) = operator(self.peek().kind) {
                self.enter_chain()?;
                levels += 1;
                self.bump();
                let rhs = operand(self, index)?;
                lhs = binary(op, lhs, rhs);
            }
            Ok(lhs)
        })();
        self.depth = self.depth.saturating_sub(levels);
        result
    }

    fn unary(&mut self, index: bool) -> PResult<Expr> {
        if let Some(minus) = self.eat(Tok::Minus) {
            self.enter()?;
            let operand = self.unary(index);
            self.leave();
            let operand = operand?;
            let span = self.tok_span(minus).to(operand.span);
            return Ok(Expr {
                kind: ExprKind::Neg(Box::new(operand)),
                span,
            });
        }
        if self.at(Tok::Plus) {
            return Err(self.expected(
                "an expression",
                "there is no unary `+`; write the operand alone",
            ));
        }
        self.power(index)
    }

    /// MATLAB's element-wise `.*`, `./` and `.^` (a dot right before the operator): one error whose fix removes
    /// the dot, and the operator is read, so that the expression is the one meant. Called after every operand
    /// ([`Self::power`]), so it sees the dot before any binary operator.
    fn elementwise_dot(&mut self) {
        let (dot, op) = (self.peek(), self.nth(1));
        if dot.kind == Tok::Dot
            && matches!(op.kind, Tok::Star | Tok::Slash | Tok::Caret)
            && op.start == dot.end
        {
            self.bump();
            let written = self.tok_text(op).to_string();
            self.diags.push(
                Diagnostic::error("BG0101", format!("`.{written}` is not an operator"))
                    .with_primary(self.tok_span(dot), "MATLAB's element-wise operator")
                    .with_help(format!("every quantity is a number: write `{written}`"))
                    .with_fix(""),
            );
        }
    }

    fn power(&mut self, index: bool) -> PResult<Expr> {
        let base = self.primary(index)?;
        self.elementwise_dot();
        if self.eat(Tok::Caret).is_none() {
            return Ok(base);
        }
        self.enter()?;
        let exponent = self.unary(index);
        self.leave();
        Ok(binary(BinOp::Pow, base, exponent?))
    }

    fn primary(&mut self, index: bool) -> PResult<Expr> {
        let t = self.peek();
        match t.kind {
            Tok::Number => {
                self.bump();
                Ok(Expr {
                    kind: ExprKind::Number(self.number_value(t)),
                    span: self.tok_span(t),
                })
            }
            Tok::LParen => {
                self.bump();
                let inner = self.expr()?;
                self.close(Tok::RParen, t, "the parenthesis")?;
                // The parentheses are not kept in the tree, but the span covers them.
                Ok(Expr {
                    kind: inner.kind,
                    span: self.span_from(t.start),
                })
            }
            Tok::Ident => {
                let name = self.expect_name("an expression")?;
                if let Some(open) = self.eat(Tok::LParen) {
                    return self.call(name, open);
                }
                if index && self.at(Tok::LBracket) {
                    let open = self.bump();
                    if self.at(Tok::Ident) {
                        // `C spring = 1/k [m/N];`: a unit after a value, not an index of a field's port.
                        return Err(self.expected("an index", UNITS_IN_EXPRESSIONS));
                    }
                    let (i, _) = self.positive_int("an index")?;
                    self.close(Tok::RBracket, open, "the index")?;
                    return Ok(Expr {
                        kind: ExprKind::Indexed(name.name, i),
                        span: self.span_from(t.start),
                    });
                }
                Ok(Expr {
                    kind: ExprKind::Name(name.name),
                    span: name.span,
                })
            }
            Tok::Star if self.previous().is_some_and(|p| p.kind == Tok::Star) => Err(self
                .expected(
                    "an expression",
                    "a power is written with `^`, as in `x^2` (not `x**2`)",
                )),
            _ => Err(self.expected("an expression", EXPR_HELP)),
        }
    }

    /// The arguments of a call, after its `(`. The single argument of `e`, `f`, `p` or `q` that is written as a node
    /// (`x`, `inst.x`, `field[2]`) becomes [`ExprKind::Node`].
    fn call(&mut self, callee: Ident, open: Token) -> PResult<Expr> {
        let start = callee.span.start;
        let mut args = Vec::new();
        if matches!(callee.name.as_str(), "e" | "f" | "p" | "q") && self.node_then_rparen() {
            let node = self.node_ref()?;
            let span = node.span;
            args.push(Expr {
                kind: ExprKind::Node(node),
                span,
            });
        } else if !self.at(Tok::RParen) {
            args.push(self.expr()?);
            while self.eat(Tok::Comma).is_some() {
                args.push(self.expr()?);
            }
        }
        self.close(Tok::RParen, open, "the call")?;
        if matches!(callee.name.as_str(), "e" | "f" | "p" | "q")
            && let [arg] = args.as_mut_slice()
        {
            // `f((x))` names the same node as `f(x)`.
            let node = match &arg.kind {
                ExprKind::Name(n) => Some((n.clone(), None)),
                ExprKind::Indexed(n, i) => Some((n.clone(), Some((*i, arg.span)))),
                _ => None,
            };
            if let Some((name, port)) = node {
                arg.kind = ExprKind::Node(NodeRef {
                    path: ShortList::one(Ident {
                        name,
                        span: arg.span,
                    }),
                    port,
                    span: arg.span,
                });
            }
        }
        Ok(Expr {
            kind: ExprKind::Call(callee, args),
            span: self.span_from(start),
        })
    }

    /// The tokens ahead are a node reference followed by `)`.
    fn node_then_rparen(&self) -> bool {
        let mut k = 0;
        if self.nth(k).kind != Tok::Ident {
            return false;
        }
        k += 1;
        while self.nth(k).kind == Tok::Dot && self.nth(k + 1).kind == Tok::Ident {
            k += 2;
        }
        if self.nth(k).kind == Tok::LBracket
            && self.nth(k + 1).kind == Tok::Number
            && self.nth(k + 2).kind == Tok::RBracket
        {
            k += 3;
        }
        self.nth(k).kind == Tok::RParen
    }

    /// `NAME(.NAME)*([INT])?`
    pub(super) fn node_ref(&mut self) -> PResult<NodeRef> {
        let start = self.peek().start;
        if !self.at(Tok::Ident) {
            return Err(self.expected(
                "a node",
                "a node is an element or a junction (`j1`), a component instance's port (`shaft.a`) or a field's \
                 port (`leg[2]`)",
            ));
        }
        let mut path = ShortList::one(
            self.expect_name("a node (an element, a junction, `inst.port` or `field[i]`)")?,
        );
        while self.eat(Tok::Dot).is_some() {
            path.push(self.expect_name("a port name after `.`")?);
        }
        let mut port = None;
        if let Some(open) = self.eat(Tok::LBracket) {
            port = Some(self.positive_int("a port number")?);
            self.close(Tok::RBracket, open, "the port number")?;
        }
        Ok(NodeRef {
            path,
            port,
            span: self.span_from(start),
        })
    }

    /// The help for a `[` right after a number, a name or a `)`, or a name right after a number, where the
    /// expression could not go on: a unit written after a value, as other tools and papers write them
    /// (`0.5 [m/N]`, `2 kg`), or, for a name, perhaps a product without its `*`.
    pub(super) fn unit_after_value(&self) -> Option<&'static str> {
        match self.previous().map(|p| p.kind) {
            Some(Tok::Number | Tok::Ident | Tok::RParen) if self.at(Tok::LBracket) => {
                Some(UNITS_IN_EXPRESSIONS)
            }
            Some(Tok::Number) if self.at(Tok::Ident) && !self.starts_line(self.peek()) => {
                Some(NAME_AFTER_NUMBER)
            }
            _ => None,
        }
    }

    /// A closing bracket matching `open`; when missing, the error shows where the bracket was opened. When the
    /// next token is on a later line, the bracket is missing at the end of the line, and the error points there.
    pub(super) fn close(&mut self, kind: Tok, open: Token, what: &str) -> PResult<Token> {
        if let Some(t) = self.eat(kind) {
            return Ok(t);
        }
        let t = self.peek();
        let found = self.describe(t);
        let want = kind.describe();
        let at = if self.starts_line(t) {
            let end = self.prev_end();
            self.span(end, end)
        } else {
            self.tok_span(t)
        };
        self.diags.push(
            Diagnostic::error(
                "BG0101",
                format!("expected {want} to close {what}, found {found}"),
            )
            .with_primary(at, format!("expected {want}"))
            .with_secondary(self.tok_span(open), "opened here")
            .with_help(
                match self.unit_after_value().filter(|_| kind == Tok::RParen) {
                    Some(help) => help.to_string(),
                    None => format!("add the missing {want}"),
                },
            ),
        );
        Err(Fail)
    }

    /// A positive integer written with digits only (a port count, an index, a port number).
    pub(super) fn positive_int(&mut self, what: &str) -> PResult<(u32, Span)> {
        let t = self.peek();
        if t.kind != Tok::Number {
            return Err(self.expected(what, "write a whole number such as `1` or `2`"));
        }
        self.bump();
        let span = self.tok_span(t);
        let text = self.tok_text(t);
        match text.parse::<u32>() {
            Ok(n) if n >= 1 && text.bytes().all(|b| b.is_ascii_digit()) => Ok((n, span)),
            _ => {
                self.diags.push(
                    Diagnostic::error(
                        "BG0115",
                        format!("{what} must be a positive whole number, found `{text}`"),
                    )
                    .with_primary(span, "not a positive whole number")
                    .with_help("ports and indices count from 1 and are written with digits only"),
                );
                Err(Fail)
            }
        }
    }

    /// `[N m/rad]`, `[kg m^2]`, `[1]`, `[1/s]`: factors with optional integer powers, one optional `/`, everything
    /// after which is the denominator.
    pub(super) fn unit(&mut self) -> PResult<UnitExpr> {
        if self.at(Tok::Ident) {
            // `param k = 2 N/m;`: the unit without its brackets, up to the end of the statement on this line.
            let first = self.peek();
            let mut last = first;
            let mut k = 1;
            while matches!(
                self.nth(k).kind,
                Tok::Ident | Tok::Slash | Tok::Caret | Tok::Minus | Tok::Number
            ) && !self.starts_line(self.nth(k))
            {
                last = self.nth(k);
                k += 1;
            }
            let unit = self
                .text
                .get(first.start as usize..last.end as usize)
                .unwrap_or("");
            return Err(self.expected(
                "a unit in brackets",
                &format!("a unit goes in brackets: `[{unit}]`"),
            ));
        }
        let open = self.expect(
            Tok::LBracket,
            "a unit in brackets",
            "every parameter, input and output has a unit in brackets, as in `[N m]`, `[m/s^2]` or `[1]` for \
             dimensionless",
        )?;
        let mut numerator = Vec::new();
        let mut denominator = Vec::new();
        let mut one = None;
        if self.at(Tok::Number) {
            let t = self.bump();
            if self.tok_text(t) != "1" {
                return Err(self.bad_unit(
                    self.tok_span(t),
                    "a number in a unit can only be `1`, as in `[1]` or `[1/s]`",
                ));
            }
            one = Some(t);
        } else if self.at(Tok::Minus) && self.nth(1).kind == Tok::RBracket {
            // `[-]`, the dimensionless unit of engineering tables.
            let t = self.bump();
            self.diags.push(
                malformed_unit(
                    self.tok_span(t),
                    "a dimensionless quantity has the unit `[1]`",
                )
                .with_fix("1"),
            );
            one = Some(t);
        }
        if one.is_none() {
            self.unit_factors(&mut numerator)?;
        }
        if self.eat(Tok::Slash).is_some() {
            self.unit_factors(&mut denominator)?;
            if denominator.is_empty() {
                return Err(
                    self.expected("a unit after `/`", "write the denominator, as in `[m/s]`")
                );
            }
        }
        if numerator.is_empty() && one.is_none() && self.at(Tok::RBracket) {
            let t = self.peek();
            let (from, to) = (open.end, t.start);
            let refused_inside = self.diags.iter().any(|d| {
                d.code.0 == "BG0104"
                    && d.primary_span()
                        .is_some_and(|s| s.start >= from && s.end <= to)
            });
            if refused_inside {
                // Not empty: characters the lexer refused (`[°]`), reported there with what to write instead.
                return Err(Fail);
            }
            return Err(self.bad_unit(
                self.tok_span(open).to(self.tok_span(t)),
                "an empty unit: write `[1]` for a dimensionless quantity",
            ));
        }
        if let Some(help) = unit_operator_help(self.peek().kind, !denominator.is_empty()) {
            let t = self.peek();
            return Err(self.bad_unit(self.tok_span(t), help));
        }
        self.close(Tok::RBracket, open, "the unit")?;
        Ok(UnitExpr {
            numerator,
            denominator,
            span: self.span_from(open.start),
        })
    }

    /// Unit symbols with their powers, on one line: a name on the next line begins the next statement, not a unit.
    fn unit_factors(&mut self, out: &mut Vec<(String, i32)>) -> PResult<()> {
        while self.at(Tok::Ident) && (out.is_empty() || !self.starts_line(self.peek())) {
            let t = self.bump();
            let symbol = self.tok_text(t).to_string();
            let mut power = 1;
            if self.eat(Tok::Caret).is_some() {
                let negative = self.eat(Tok::Minus).is_some();
                let p = self.peek();
                let text = self.tok_text(p);
                // Digits, or superscripts (`m²`, reported by the lexer and read as `m^2`).
                let whole = text.bytes().all(|b| b.is_ascii_digit()) || !text.is_ascii();
                let parsed = if p.kind == Tok::Number && whole {
                    let v = self.number_value(p);
                    (v != 0.0 && v.fract() == 0.0 && v.abs() <= f64::from(i32::MAX))
                        .then_some(v as i32)
                } else {
                    None
                };
                match parsed {
                    Some(v) => {
                        self.bump();
                        power = if negative { -v } else { v };
                    }
                    None => {
                        return Err(self.bad_unit(
                            self.tok_span(p),
                            "a unit's power is a non-zero whole number, as in `m^2` or `s^-1`",
                        ));
                    }
                }
            }
            if power == 1
                && let Some(p) = self.power_without_caret(t)
            {
                power = p;
            }
            out.push((symbol, power));
            self.multiplication_in_unit();
        }
        Ok(())
    }

    /// `*`, `.` or `-` between two factors (`[N*m]`, `[N.m]`, `[N-m]`, as other tools write units): one error with
    /// the space to write instead, and the factors read on, so that the unit is the one meant and later checks see
    /// it.
    fn multiplication_in_unit(&mut self) {
        let (op, next) = (self.peek(), self.nth(1));
        if matches!(op.kind, Tok::Star | Tok::Dot | Tok::Minus)
            && next.kind == Tok::Ident
            && !self.starts_line(next)
        {
            self.bump();
            self.diags
                .push(malformed_unit(self.tok_span(op), UNIT_PRODUCT_HELP).with_fix(" "));
        }
    }

    /// A negative power written right after its factor without `^` (`[s-1]`, `[m s-2]`): one error whose fix
    /// inserts the `^`, and the power.
    fn power_without_caret(&mut self, factor: Token) -> Option<i32> {
        let (minus, digits) = (self.peek(), self.nth(1));
        let adjacent = minus.start == factor.end && digits.start == minus.end;
        if !(adjacent && minus.kind == Tok::Minus && digits.kind == Tok::Number) {
            return None;
        }
        let text = self.tok_text(digits).to_string();
        let v: i32 = text.parse().ok().filter(|v| *v != 0)?;
        self.bump();
        self.bump();
        self.diags.push(
            malformed_unit(
                self.tok_span(minus),
                format!(
                    "a unit's power follows `^`: `{}^-{text}`",
                    self.tok_text(factor)
                ),
            )
            .with_fix("^-"),
        );
        Some(-v)
    }

    fn bad_unit(&mut self, span: Span, help: &str) -> Fail {
        self.diags.push(malformed_unit(span, help));
        Fail
    }
}

/// BG0116 at `span`, with `help`: the one form of every unit error of the parser.
fn malformed_unit(span: Span, help: impl Into<String>) -> Diagnostic {
    Diagnostic::error("BG0116", "malformed unit")
        .with_primary(span, "not a unit")
        .with_help(help)
}

const UNIT_PRODUCT_HELP: &str = "unit factors multiply by a space, as in `[N m]` or `[kg m^2]`";

/// What to write instead of an operator that other tools put in units (`[N*m]`, `[N.m]`, `[m/s/s]`), which the
/// unit grammar does not have.
fn unit_operator_help(tok: Tok, after_slash: bool) -> Option<&'static str> {
    match tok {
        Tok::Star | Tok::Dot => Some(UNIT_PRODUCT_HELP),
        Tok::Minus | Tok::Plus | Tok::Number | Tok::Caret => Some(
            "a unit is SI symbols separated by spaces, each with an optional non-zero whole power after `^`: \
             `[kg m^2/s^2]`, `[s^-1]`",
        ),
        Tok::Slash if after_slash => Some(
            "a unit has one `/`, and every factor after it is in the denominator: `[m/s^2]` or `[kg/m s]`",
        ),
        _ => None,
    }
}

fn binary(op: BinOp, lhs: Expr, rhs: Expr) -> Expr {
    let span = lhs.span.to(rhs.span);
    Expr {
        kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)),
        span,
    }
}
