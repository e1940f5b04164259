//! The formatter: a tree printed back in the canonical layout.
//!
//! The layout: 4-space indentation, one statement per line, spaces around binary operators (`^` included) and after commas, the
//! fewest parentheses that keep the tree (so `parse(format(t))` is `t` up to spans), numbers in the shortest form that
//! reads back to the same `f64`, units as `[N m/rad]`, `[kg m^2]`, `[1]`, `[1/s]`. Doc comments are printed before
//! their declarations; ordinary comments keep their place relative to statements (a comment inside a statement moves
//! to the end of that statement's line or just after it); one blank line is kept where the source had one or more.
//! An element with one law and no comment inside is printed on one line, `R r { e = k*f; }`, otherwise its laws
//! go on their own lines. Formatting a formatted file changes nothing.

use super::ast::*;
use crate::diagnostic::{Diagnostic, has_errors};
use crate::span::FileId;

/// Prints a parsed file in the canonical layout. The tree should come from a parse without errors
/// (see [`format_source`]); comments and blank lines are taken from [`File::comments`] and [`File::blank_lines`].
pub fn format(file: &File) -> String {
    let mut p = Printer {
        out: String::new(),
        comments: &file.comments,
        next_comment: 0,
        blanks: &file.blank_lines,
        indent: 0,
        last_end: 0,
        block_start: true,
        pending: Vec::new(),
    };
    p.file(file);
    p.out
}

/// Parses `text` and formats it in its own line endings (CRLF when its first line break is CRLF) and with its
/// byte-order mark, if it has one; refuses (returning the diagnostics) when the text has syntax errors.
/// The formatted text is read back before it is returned: a layout that would not parse (a limit the layout
/// reaches where the file did not) is refused, with the reason, rather than written over a valid file.
pub fn format_source(file: FileId, text: &str) -> Result<String, Vec<Diagnostic>> {
    let (tree, diags) = super::parse(file, text);
    if has_errors(&diags) {
        return Err(diags);
    }
    let formatted = format(&tree);
    let (_, again) = super::parse(file, &formatted);
    if let Some(d) = again.iter().find(|d| d.is_error()) {
        return Err(vec![Diagnostic::error(
            d.code.0,
            format!(
                "the canonical layout of this file would not read back ({}); the file is left as it is",
                d.message
            ),
        )]);
    }
    Ok(in_style_of(text, formatted))
}

/// `formatted` (from [`format()`]: `\n` line breaks, no byte-order mark) with the conventions of the file it came
/// from: CRLF line breaks when the original's first line break is CRLF (a Windows checkout), and the byte-order
/// mark when the original starts with one. The layout is canonical; the encoding of line breaks is the file's,
/// as rustfmt's and ruff's default (`auto`) keeps it, so that formatting never rewrites every line of such a file.
fn in_style_of(original: &str, formatted: String) -> String {
    const BOM: char = '\u{feff}';
    let crlf = original
        .find('\n')
        .is_some_and(|i| original[..i].ends_with('\r'));
    let mut out = match crlf {
        true => formatted.replace("\r\n", "\n").replace('\n', "\r\n"),
        false => formatted,
    };
    if original.starts_with(BOM) && !out.starts_with(BOM) {
        out.insert(0, BOM);
    }
    out
}

struct Printer<'f> {
    out: String,
    comments: &'f [Comment],
    next_comment: usize,
    blanks: &'f [u32],
    indent: usize,
    /// Source offset of the end of what was printed last, to find blank lines between it and the next thing.
    last_end: u32,
    /// Nothing has been printed yet in the current block (no blank line goes there).
    block_start: bool,
    /// Comments moved out of a statement that did not fit at the end of its line; they go on their own lines
    /// before whatever comes next, exactly where a reformatting finds them.
    pending: Vec<&'f Comment>,
}

impl Printer<'_> {
    fn pad(&mut self) {
        for _ in 0..self.indent {
            self.out.push_str("    ");
        }
    }

    /// Starts a new unit (a comment or a statement) whose source starts at `start`: a blank line first if the source
    /// had one since the last unit.
    fn begin_unit(&mut self, start: u32) {
        if !self.block_start {
            let from = self.blanks.partition_point(|b| *b <= self.last_end);
            if self.blanks.get(from).is_some_and(|b| *b < start) {
                self.out.push('\n');
            }
        }
        self.block_start = false;
    }

    fn end_unit(&mut self, end: u32) {
        self.last_end = self.last_end.max(end);
    }

    /// Prints, on their own lines, the pending comments and the comments that start before `before`.
    fn leading(&mut self, before: u32) {
        for c in std::mem::take(&mut self.pending) {
            self.begin_unit(c.span.start);
            self.pad();
            self.out.push_str(&c.text);
            self.out.push('\n');
            self.end_unit(c.span.end);
        }
        while let Some(c) = self.comments.get(self.next_comment) {
            if c.span.start >= before {
                break;
            }
            self.next_comment += 1;
            self.begin_unit(c.span.start);
            self.pad();
            self.out.push_str(&c.text);
            self.out.push('\n');
            self.end_unit(c.span.end);
        }
    }

    /// Ends the line of a construct spanning to `end`, whose next sibling starts at `next`: of the comments inside the
    /// construct and the one trailing it on its line, the first goes at the end of the line and the others become
    /// pending (printed on their own lines before the next thing).
    fn finish_line(&mut self, end: u32, next: u32) {
        let comments = self.comments;
        let mut moved = Vec::new();
        while let Some(c) = comments.get(self.next_comment) {
            if c.span.start < end {
                moved.push(c);
                self.next_comment += 1;
            } else {
                break;
            }
        }
        if let Some(c) = comments.get(self.next_comment)
            && !c.own_line
            && c.span.start < next
        {
            moved.push(c);
            self.next_comment += 1;
        }
        let mut iter = moved.into_iter();
        if let Some(first) = iter.next() {
            self.out.push(' ');
            self.out.push_str(&first.text);
        }
        self.out.push('\n');
        self.end_unit(end);
        self.pending.extend(iter);
    }

    fn docs(&mut self, doc: &[String]) {
        for line in doc {
            self.pad();
            if line.is_empty() {
                self.out.push_str("///\n");
            } else {
                self.out.push_str("/// ");
                self.out.push_str(line);
                self.out.push('\n');
            }
        }
    }

    fn file(&mut self, file: &File) {
        let mut prev_was_model = false;
        for (i, item) in file.items.iter().enumerate() {
            let span = item.span();
            let is_model = matches!(item, Item::Model(_));
            if i > 0 && (is_model || prev_was_model) && !self.out.ends_with("\n\n") {
                // Models and components are always set apart by a blank line.
                self.out.push('\n');
                self.block_start = true;
            }
            self.leading(span.start);
            self.begin_unit(span.start);
            let next = file
                .items
                .get(i + 1)
                .map(|it| it.span().start)
                .unwrap_or(u32::MAX);
            match item {
                Item::Import(im) => {
                    self.out.push_str("import ");
                    self.out.push_str(&quote(&im.path));
                    self.out.push(';');
                    self.finish_line(im.span.end, next);
                }
                Item::Model(m) => self.model(m, next),
            }
            prev_was_model = is_model;
        }
        self.leading(u32::MAX);
    }

    fn model(&mut self, m: &ModelDecl, next: u32) {
        self.docs(&m.doc);
        let word = match m.kind {
            ModelKind::Model => "model",
            ModelKind::Component => "component",
        };
        self.out.push_str(word);
        self.out.push(' ');
        self.out.push_str(&m.name.name);
        let close = m.span.end.saturating_sub(1);
        let has_inner_comments = self
            .comments
            .get(self.next_comment)
            .is_some_and(|c| c.span.start < close);
        if m.body.is_empty() && !has_inner_comments {
            self.out.push_str(" {}");
            self.finish_line(m.span.end, next);
            return;
        }
        self.out.push_str(" {\n");
        self.indent += 1;
        self.block_start = true;
        for (i, s) in m.body.iter().enumerate() {
            let next_stmt = m.body.get(i + 1).map(|s| s.span().start).unwrap_or(close);
            self.statement(s, next_stmt);
        }
        self.leading(close);
        self.indent -= 1;
        self.out.push('}');
        self.finish_line(m.span.end, next);
    }

    fn statement(&mut self, s: &Stmt, next: u32) {
        let span = s.span();
        self.leading(span.start);
        self.begin_unit(span.start);
        let line = match s {
            Stmt::Domain(d) => format!("domain {};", d.domain.name),
            Stmt::Param(p) => {
                self.docs(&p.doc);
                // The unit follows the default, so an index at the default's top level (`(e[1])`) keeps its
                // parentheses; without them `e[1] [1]` would read as `e` with the unit `[1]`.
                let default = if has_bare_index(&p.default) {
                    format!("({})", expr(&p.default))
                } else {
                    expr(&p.default)
                };
                let mut line = format!("param {} = {default} {}", p.name.name, unit(&p.unit));
                description(&mut line, &p.description);
                line.push(';');
                line
            }
            Stmt::Input(i) => {
                self.docs(&i.doc);
                let mut line = format!("input {} {}", i.name.name, unit(&i.unit));
                description(&mut line, &i.description);
                line.push(';');
                line
            }
            Stmt::Output(o) => {
                self.docs(&o.doc);
                let mut line = format!(
                    "output {} {} = {}",
                    o.name.name,
                    unit(&o.unit),
                    expr(&o.value)
                );
                description(&mut line, &o.description);
                line.push(';');
                line
            }
            Stmt::Var(v) => {
                self.docs(&v.doc);
                format!(
                    "var {} {} = int({});",
                    v.name.name,
                    unit(&v.unit),
                    expr(&v.integrand)
                )
            }
            Stmt::Coords(c) => format!("coords [{}];", list(&c.coords)),
            Stmt::Element(e) => {
                self.docs(&e.doc);
                self.element(e, next);
                return;
            }
            Stmt::Instance(i) => {
                self.docs(&i.doc);
                let mut line = format!("{} {}", i.component.name, i.name.name);
                if !i.overrides.is_empty() {
                    let o: Vec<String> = i
                        .overrides
                        .iter()
                        .map(|(n, v)| format!("{} = {}", n.name, expr(v)))
                        .collect();
                    line.push_str(&format!("({})", o.join(", ")));
                }
                line.push(';');
                line
            }
            Stmt::Bond(b) => bond(b),
            Stmt::Port(p) => format!("port {} = {};", p.name.name, node(&p.target)),
            Stmt::Allow(a) => {
                let mut line = format!("allow {} {}", a.code.name, node(&a.target));
                description(&mut line, &a.reason);
                line.push(';');
                line
            }
        };
        self.pad();
        self.out.push_str(&line);
        self.finish_line(span.end, next);
    }

    fn element(&mut self, e: &ElementDecl, next: u32) {
        let mut head = format!("{} {}", e.kind.keyword(), e.name.name);
        if let Some((n, _)) = e.ports {
            head.push_str(&format!("({n})"));
        }
        if let Some(d) = &e.domain {
            head.push_str(": ");
            head.push_str(&d.name);
        }
        self.pad();
        self.out.push_str(&head);
        match &e.body {
            ElementBody::None => {
                self.out.push(';');
                self.finish_line(e.span.end, next);
            }
            ElementBody::Value(v) => {
                self.out.push_str(" = ");
                self.out.push_str(&expr(v));
                self.out.push(';');
                self.finish_line(e.span.end, next);
            }
            ElementBody::Laws(laws) => {
                let close = e.span.end.saturating_sub(1);
                let inner_comments = self
                    .comments
                    .get(self.next_comment)
                    .is_some_and(|c| c.span.start < e.span.end);
                match laws.as_slice() {
                    [] if !inner_comments => self.out.push_str(" {}"),
                    [law] if !inner_comments => {
                        self.out.push_str(" { ");
                        self.out.push_str(&law_text(law));
                        self.out.push_str(" }");
                    }
                    _ => {
                        self.out.push_str(" {\n");
                        self.indent += 1;
                        self.block_start = true;
                        for (i, law) in laws.iter().enumerate() {
                            let next_law = laws.get(i + 1).map(|l| l.span.start).unwrap_or(close);
                            self.leading(law.span.start);
                            self.begin_unit(law.span.start);
                            self.pad();
                            self.out.push_str(&law_text(law));
                            self.finish_line(law.span.end, next_law);
                        }
                        self.leading(close);
                        self.indent -= 1;
                        self.pad();
                        self.out.push('}');
                    }
                }
                self.finish_line(e.span.end, next);
            }
        }
    }
}

/// An `name[i]` outside any call or parentheses.
fn has_bare_index(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Indexed(..) => true,
        ExprKind::Neg(x) => has_bare_index(x),
        ExprKind::Binary(_, a, b) => has_bare_index(a) || has_bare_index(b),
        _ => false,
    }
}

fn law_text(l: &Law) -> String {
    let mut s = l.lhs.name.clone();
    if !l.indices.is_empty() {
        let idx: Vec<String> = l.indices.iter().map(|(i, _)| i.to_string()).collect();
        s.push_str(&format!("[{}]", idx.join(", ")));
    }
    s.push_str(" = ");
    s.push_str(&expr(&l.rhs));
    s.push(';');
    s
}

fn bond(b: &BondStmt) -> String {
    let mut s = String::from("bond ");
    if let Some(l) = &b.label {
        s.push_str(&l.name);
        s.push_str(": ");
    }
    let groups: Vec<String> = b
        .chain
        .iter()
        .map(|g| g.iter().map(node).collect::<Vec<_>>().join(", "))
        .collect();
    s.push_str(&groups.join(" -> "));
    if let Some(h) = &b.hint {
        s.push_str(if h.fixed { " stroke! " } else { " stroke " });
        s.push_str(&node(&h.at));
    }
    s.push(';');
    s
}

fn description(line: &mut String, d: &Option<String>) {
    if let Some(d) = d {
        line.push(' ');
        line.push_str(&quote(d));
    }
}

/// A string literal with `\` and `"` escaped.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        if c == '"' || c == '\\' {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

/// A node reference: `j`, `inst.port`, `field[2]`.
pub fn node(n: &NodeRef) -> String {
    let mut s = n
        .path
        .iter()
        .map(|i| i.name.as_str())
        .collect::<Vec<_>>()
        .join(".");
    if let Some((i, _)) = n.port {
        s.push_str(&format!("[{i}]"));
    }
    s
}

/// A unit in canonical form.
pub fn unit(u: &UnitExpr) -> String {
    fn factors(f: &[(String, i32)]) -> String {
        f.iter()
            .map(|(s, p)| {
                if *p == 1 {
                    s.clone()
                } else {
                    format!("{s}^{p}")
                }
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
    let num = if u.numerator.is_empty() {
        "1".to_string()
    } else {
        factors(&u.numerator)
    };
    if u.denominator.is_empty() {
        format!("[{num}]")
    } else {
        format!("[{num}/{}]", factors(&u.denominator))
    }
}

/// A number in a form that reads back as the same `f64`: decimal from 0.001 up to a million (`2`, `0.5`, `3000`,
/// `0.00119`), otherwise the shorter of decimal and scientific (`3.06e-4`, `1e-7`, `1e6`, `1.5e300`).
pub fn number(v: f64) -> String {
    // Both `Display` and `LowerExp` print the fewest significant digits that read back exactly.
    let decimal = format!("{v}");
    let magnitude = v.abs();
    if v == 0.0 || (1e-3..1e6).contains(&magnitude) {
        return decimal;
    }
    let scientific = format!("{v:e}");
    if scientific.len() < decimal.len() {
        scientific
    } else {
        decimal
    }
}

fn list(items: &[Expr]) -> String {
    items.iter().map(expr).collect::<Vec<_>>().join(", ")
}

/// Binding strength of an expression's top operator: sums 1, products 2, negation 3, powers 4, atoms 5.
fn strength(e: &Expr) -> u8 {
    match &e.kind {
        ExprKind::Binary(BinOp::Add | BinOp::Sub, ..) => 1,
        ExprKind::Binary(BinOp::Mul | BinOp::Div, ..) => 2,
        ExprKind::Neg(_) => 3,
        ExprKind::Number(v) if v.is_sign_negative() => 3,
        ExprKind::Binary(BinOp::Pow, ..) => 4,
        _ => 5,
    }
}

fn wrap(e: &Expr, parens: bool) -> String {
    if parens {
        format!("({})", expr(e))
    } else {
        expr(e)
    }
}

/// The operators of a `+ -` or `* /` chain printed without parentheses before its left operand is put in them.
/// The parser counts each operator of a chain as a level of nesting (at most 200, `BG0105`); a left operand that is a
/// chain of its own needs no parentheses to keep the tree, and without them the chains a file wrote in groups would
/// join into one too deep to read back. Groups of this many keep a chain of `n` operators about `n/50 + 50` deep.
const CHAIN_GROUP: usize = 50;

/// An expression with the fewest parentheses that keep its tree: left-associative `+ -` and `* /` parenthesise a
/// right operand of the same strength, the right-associative `^` a left one; a power's base is an atom. A chain's
/// left operands are grouped every 50 operators (`CHAIN_GROUP`), and a negation of a negation is `--x`, so that the
/// text nests no deeper than the parser accepts.
pub fn expr(e: &Expr) -> String {
    expr_in_chain(e, 0)
}

/// [`expr`] of `e`, under `above` operators of the same chain printed without parentheses.
fn expr_in_chain(e: &Expr, above: usize) -> String {
    match &e.kind {
        ExprKind::Number(v) => number(*v),
        ExprKind::Name(n) => n.clone(),
        ExprKind::Indexed(n, i) => format!("{n}[{i}]"),
        ExprKind::Call(f, args) => format!("{}({})", f.name, list(args)),
        ExprKind::Node(n) => node(n),
        ExprKind::Neg(x) if matches!(x.kind, ExprKind::Neg(_)) => format!("-{}", expr(x)),
        ExprKind::Neg(x) => format!("-{}", wrap(x, strength(x) <= 3)),
        ExprKind::Binary(op, a, b) => {
            let (sym, level) = match op {
                BinOp::Add => ("+", 1),
                BinOp::Sub => ("-", 1),
                BinOp::Mul => ("*", 2),
                BinOp::Div => ("/", 2),
                BinOp::Pow => ("^", 4),
            };
            if *op == BinOp::Pow {
                format!(
                    "{} ^ {}",
                    wrap(a, strength(a) < 5),
                    wrap(b, strength(b) < 3)
                )
            } else {
                let left = match strength(a).cmp(&level) {
                    std::cmp::Ordering::Less => wrap(a, true),
                    std::cmp::Ordering::Equal if above + 1 >= CHAIN_GROUP => wrap(a, true),
                    std::cmp::Ordering::Equal => expr_in_chain(a, above + 1),
                    std::cmp::Ordering::Greater => expr(a),
                };
                format!("{left} {sym} {}", wrap(b, strength(b) <= level))
            }
        }
    }
}
