//! Statements laid out as `rustfmt` lays them out, by construction.
//!
//! `rustfmt` leaves a statement on one line when the line fits in [`MAX_WIDTH`] columns and every call's argument
//! list fits in [`CALL_ARGS_WIDTH`] columns (its `fn_call_width`); binary operators, unary minus, parentheses,
//! field accesses and indexing have no other limit. [`Body`] keeps every statement within both limits: a
//! statement that does not fit gets parts of its expression bound to `let`s before it (`t1`, `t2`, ...):
//! - a call whose arguments are too wide gets its widest arguments bound first;
//! - a chain `a + b - c` (or `a * b / c`) has its operands wider than half a line bound, and when the rest still
//!   does not fit, its longest prefix that fits becomes a `let` and the chain continues from that name;
//! - a parenthesised group that does not fit is bound whole (the parentheses go).
//!
//! Every part bound is an expression of its own in Rust's parse of the statement (see
//! [`crate::symbolic::RustCode`]), so the statement computes the same value, with the same roundings, as the
//! expression on one line. Only a single name or literal wider than a line can make a line longer than
//! [`MAX_WIDTH`].

use super::layout_widths::{text_width, text_within, widest_call_args};
use super::names::Namer;
use crate::symbolic::RustCode;

/// `rustfmt`'s `max_width`: the columns of a line.
pub(super) const MAX_WIDTH: usize = 100;
/// `rustfmt`'s `fn_call_width`: the columns of a call's arguments (`a, b`) on one line.
pub(super) const CALL_ARGS_WIDTH: usize = 60;
/// Columns kept for the name of a temporary (`t123`, or `t123_2` when the model has a `t123`).
const TEMP_NAME_WIDTH: usize = 8;

/// The width of `s` in columns (its characters: generated code has no wide characters).
pub(super) fn width(s: &str) -> usize {
    s.chars().count()
}

/// The lines of a function body: statements with the `let`s they need before them, and lines given as they are.
pub(super) struct Body<'n> {
    namer: &'n mut Namer,
    indent: String,
    /// The columns of a line (less than [`MAX_WIDTH`] inside a module that the caller indents).
    width: usize,
    next_temp: usize,
    lines: Vec<String>,
}

impl<'n> Body<'n> {
    /// A body indented by `indent` spaces whose lines must fit in `width` columns; temporaries are named by
    /// `namer`, which must hold every name the function already uses.
    pub fn new(namer: &'n mut Namer, indent: usize, width: usize) -> Body<'n> {
        Body {
            namer,
            indent: " ".repeat(indent),
            width,
            next_temp: 1,
            lines: Vec::new(),
        }
    }

    /// Numbers the next temporary `t{first}` (a function whose body is laid out in parts continues its count).
    pub fn first_temp(mut self, first: usize) -> Body<'n> {
        self.next_temp = first;
        self
    }

    /// The number of the next temporary.
    pub fn next_temp(&self) -> usize {
        self.next_temp
    }

    /// A line as it is, indented.
    pub fn line(&mut self, text: &str) {
        self.lines.push(format!("{}{text}", self.indent));
    }

    /// Lines already indented (comments laid out by the caller).
    pub fn lines(&mut self, lines: impl IntoIterator<Item = String>) {
        self.lines.extend(lines);
    }

    /// `head code tail` on one line (`let y = ` and `;`, or `dx[0] = ` and `;`, or nothing around a tail
    /// expression), after the `let`s it needs.
    pub fn statement(&mut self, head: &str, code: &RustCode, tail: &str) {
        let budget = self
            .width
            .saturating_sub(self.indent.len() + width(head) + width(tail));
        let text = self.fit(code, budget);
        self.lines
            .push(format!("{}{head}{text}{tail}", self.indent));
    }

    /// The lines, each ending in a newline.
    pub fn finish(self) -> String {
        let mut out = String::new();
        for l in self.lines {
            out.push_str(&l);
            out.push('\n');
        }
        out
    }

    /// The columns a temporary's value may take: `let tN = value;`.
    fn temp_budget(&self) -> usize {
        self.width
            .saturating_sub(self.indent.len() + "let  = ;".len() + TEMP_NAME_WIDTH)
    }

    fn temp_name(&mut self) -> String {
        let name = self.namer.ident(&format!("t{}", self.next_temp));
        self.next_temp += 1;
        name
    }

    /// Binds `text` (an expression laid out already) to a new temporary; returns its name.
    fn bind(&mut self, text: &str) -> String {
        let name = self.temp_name();
        self.lines
            .push(format!("{}let {name} = {text};", self.indent));
        name
    }

    /// `code` bound to a temporary (its own statement), or the code itself when it is a name or a literal.
    fn hoist(&mut self, code: &RustCode) -> String {
        match code {
            RustCode::Atom(s) => s.clone(),
            RustCode::Paren(inner) => self.hoist(inner),
            _ => {
                let text = self.fit(code, self.temp_budget());
                self.bind(&text)
            }
        }
    }

    /// The text of `code` in at most `budget` columns, with every call's arguments within [`CALL_ARGS_WIDTH`],
    /// binding parts to temporaries as needed.
    fn fit(&mut self, code: &RustCode, budget: usize) -> String {
        if let Some(flat) = text_within(code, budget)
            && widest_call_args(code) <= CALL_ARGS_WIDTH
        {
            return flat;
        }
        match code {
            RustCode::Atom(s) => s.clone(),
            RustCode::Neg(inner) => format!("-{}", self.fit(inner, budget.saturating_sub(1))),
            RustCode::Paren(inner) => self.hoist(inner),
            RustCode::Call(callee, args) => self.fit_call(callee, args, budget),
            RustCode::Chain(first, rest) => self.fit_chain(first, rest, budget),
        }
    }

    fn fit_call(&mut self, callee: &str, args: &[RustCode], budget: usize) -> String {
        let room = CALL_ARGS_WIDTH.min(budget.saturating_sub(width(callee) + 2));
        let mut texts: Vec<Option<String>> = args.iter().map(|a| text_within(a, room)).collect();
        // The widths decide which argument is bound first. One too wide for the room alone is bound in any case;
        // its exact width (a walk of it) is needed only to order it among others like it.
        let too_wide = (0..args.len())
            .filter(|&i| texts[i].is_none() && !args[i].is_atom())
            .count();
        let mut columns: Vec<usize> = args
            .iter()
            .zip(&texts)
            .map(|(a, t)| match t {
                Some(t) => width(t),
                None if too_wide > 1 || a.is_atom() => text_width(a),
                None => room + 1,
            })
            .collect();
        let mut bound = vec![false; args.len()];
        loop {
            let used = columns.iter().sum::<usize>() + 2 * columns.len().saturating_sub(1);
            if used <= room {
                break;
            }
            // The widest argument not bound yet that is more than a name.
            let widest = (0..args.len())
                .filter(|&i| !bound[i] && !args[i].is_atom())
                .max_by_key(|&i| (columns[i], std::cmp::Reverse(i)));
            let Some(i) = widest else { break };
            let name = self.hoist(&args[i]);
            columns[i] = width(&name);
            texts[i] = Some(name);
            bound[i] = true;
        }
        let texts: Vec<String> = args
            .iter()
            .zip(texts)
            .map(|(a, t)| t.unwrap_or_else(|| a.to_string()))
            .collect();
        format!("{callee}({})", texts.join(", "))
    }

    fn fit_chain(
        &mut self,
        first: &RustCode,
        rest: &[(crate::symbolic::RustOp, RustCode)],
        budget: usize,
    ) -> String {
        let limit = budget.min(self.temp_budget());
        let operands =
            std::iter::once((None, first)).chain(rest.iter().map(|(op, o)| (Some(*op), o)));
        let mut line = String::new();
        for (op, operand) in operands {
            // An operand wider than half a line, or with a call too wide, gets a line of its own.
            let flat = match operand {
                RustCode::Atom(s) => Some(s.clone()),
                _ => text_within(operand, limit / 2)
                    .filter(|_| widest_call_args(operand) <= CALL_ARGS_WIDTH),
            };
            let text = match (flat, operand) {
                (Some(flat), _) => flat,
                // `-x` keeps its minus here; `x` gets the line.
                (None, RustCode::Neg(inner)) => format!("-{}", self.hoist(inner)),
                (None, _) => self.hoist(operand),
            };
            line = match op {
                None => text,
                Some(op) => {
                    let joined = format!("{line} {} {text}", op.as_str());
                    if width(&joined) <= limit {
                        joined
                    } else {
                        let prefix = self.bind(&line);
                        format!("{prefix} {} {text}", op.as_str())
                    }
                }
            };
        }
        line
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codegen::test_support::{TestRng, assert_rustfmt_stable};
    use crate::symbolic::RustOp;

    fn atom(s: &str) -> RustCode {
        RustCode::Atom(s.into())
    }

    fn sum(names: &[String]) -> RustCode {
        let mut iter = names.iter();
        let first = atom(iter.next().map(String::as_str).unwrap_or("0.0"));
        RustCode::Chain(
            Box::new(first),
            iter.map(|n| (RustOp::Add, atom(n))).collect(),
        )
    }

    fn body_text(code: &RustCode) -> String {
        let mut namer = Namer::with_reserved();
        let mut body = Body::new(&mut namer, 4, MAX_WIDTH);
        body.statement("dx[0] = ", code, ";");
        body.finish()
    }

    #[test]
    fn a_statement_that_fits_stays_on_one_line() {
        let code = sum(&["a".into(), "b".into()]);
        assert_eq!(body_text(&code), "    dx[0] = a + b;\n");
    }

    #[test]
    fn a_long_sum_continues_from_its_bound_prefix() {
        let names: Vec<String> = (0..40).map(|i| format!("term_{i:02}")).collect();
        let text = body_text(&sum(&names));
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines.len() > 1, "{text}");
        for l in &lines {
            assert!(width(l) <= MAX_WIDTH, "{l}");
        }
        // The first temporary starts the sum; each later line continues from the previous name.
        assert!(
            lines[0].starts_with("    let t1 = term_00 + term_01 + "),
            "{text}"
        );
        assert!(lines[1].starts_with("    let t2 = t1 + "), "{text}");
        assert!(
            lines.last().is_some_and(|l| l.ends_with(" + term_39;")),
            "{text}"
        );
        // Every term appears once, in order.
        let all: Vec<&str> = text
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .filter(|w| w.starts_with("term_"))
            .collect();
        assert_eq!(all, names.iter().map(String::as_str).collect::<Vec<_>>());
    }

    #[test]
    fn wide_call_arguments_are_bound_first() {
        let long = sum(&(0..8).map(|i| format!("alpha_{i}")).collect::<Vec<_>>());
        let call = RustCode::Call("libm::atan2".into(), vec![long, atom("y")]);
        let text = body_text(&call);
        assert_eq!(
            text,
            "    let t1 = alpha_0 + alpha_1 + alpha_2 + alpha_3 + alpha_4 + alpha_5 + alpha_6 + alpha_7;\n    \
             dx[0] = libm::atan2(t1, y);\n"
        );
    }

    #[test]
    fn a_parenthesised_group_that_does_not_fit_is_bound_whole() {
        let group = RustCode::Paren(Box::new(sum(&(0..9)
            .map(|i| format!("beta_{i}"))
            .collect::<Vec<_>>())));
        let code = RustCode::Chain(
            Box::new(RustCode::Neg(Box::new(atom("k")))),
            vec![(RustOp::Mul, group), (RustOp::Div, atom("m"))],
        );
        let text = body_text(&code);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.last(), Some(&"    dx[0] = -k * t1 / m;"), "{text}");
        assert_eq!(lines.len(), 2, "{text}");
        assert!(lines[0].starts_with("    let t1 = beta_0 + "), "{text}");
    }

    #[test]
    fn temporaries_avoid_the_names_of_the_model() {
        let mut namer = Namer::with_reserved();
        assert_eq!(namer.ident("t1"), "t1");
        let mut body = Body::new(&mut namer, 4, MAX_WIDTH);
        let names: Vec<String> = (0..40).map(|i| format!("term_{i:02}")).collect();
        body.statement("dx[0] = ", &sum(&names), ";");
        let text = body.finish();
        assert!(text.starts_with("    let t1_2 = "), "{text}");
    }

    /// Random code as the printer builds it: sums of products, products of names, literals, calls and
    /// parenthesised sums, a minus on a product's first operand.
    fn random_code(rng: &mut TestRng, depth: usize) -> RustCode {
        if depth == 0 || rng.below(3) == 0 {
            return random_operand(rng, 0);
        }
        let n = 2 + rng.below(7);
        let terms: Vec<RustCode> = (0..n).map(|_| random_product(rng, depth - 1)).collect();
        let mut iter = terms.into_iter();
        let first = iter.next().unwrap_or(atom("0.0"));
        RustCode::Chain(
            Box::new(first),
            iter.map(|t| {
                (
                    if rng.below(2) == 0 {
                        RustOp::Add
                    } else {
                        RustOp::Sub
                    },
                    t,
                )
            })
            .collect(),
        )
    }

    fn random_product(rng: &mut TestRng, depth: usize) -> RustCode {
        let n = 1 + rng.below(5);
        let mut factors: Vec<RustCode> = (0..n).map(|_| random_operand(rng, depth)).collect();
        if rng.below(4) == 0 {
            factors[0] = RustCode::Neg(Box::new(factors[0].clone()));
        }
        let mut iter = factors.into_iter();
        let first = iter.next().unwrap_or(atom("1.0"));
        let rest: Vec<(RustOp, RustCode)> = iter
            .map(|f| {
                (
                    if rng.below(3) == 0 {
                        RustOp::Div
                    } else {
                        RustOp::Mul
                    },
                    f,
                )
            })
            .collect();
        if rest.is_empty() {
            first
        } else {
            RustCode::Chain(Box::new(first), rest)
        }
    }

    fn random_operand(rng: &mut TestRng, depth: usize) -> RustCode {
        match (depth, rng.below(6)) {
            (0, _) | (_, 0..=2) => {
                let names = [
                    "v0",
                    "v1",
                    "p.mass_of_the_trunk",
                    "theta_sint",
                    "v2",
                    "2.0",
                    "0.125",
                    "0.001",
                ];
                atom(names[rng.below(names.len())])
            }
            (_, 3) => RustCode::Paren(Box::new(random_code(rng, depth - 1))),
            (_, 4) => RustCode::Call("libm::sin".into(), vec![random_code(rng, depth - 1)]),
            _ => RustCode::Call(
                "libm::atan2".into(),
                vec![random_code(rng, depth - 1), random_code(rng, depth - 1)],
            ),
        }
    }

    /// The value of `code` as Rust computes it, with `v0 = 0.7`, `v1 = -1.3`, `v2 = 2.9`,
    /// `p.mass_of_the_trunk = 31.5`, `theta_sint = 0.05`, and the temporaries in `env`.
    fn eval(code: &RustCode, env: &std::collections::HashMap<String, f64>) -> f64 {
        match code {
            RustCode::Atom(s) => match s.as_str() {
                "v0" => 0.7,
                "v1" => -1.3,
                "v2" => 2.9,
                "p.mass_of_the_trunk" => 31.5,
                "theta_sint" => 0.05,
                other => env
                    .get(other)
                    .copied()
                    .unwrap_or_else(|| other.parse().unwrap_or(f64::NAN)),
            },
            RustCode::Neg(inner) => -eval(inner, env),
            RustCode::Paren(inner) => eval(inner, env),
            RustCode::Chain(first, rest) => rest.iter().fold(eval(first, env), |acc, (op, o)| {
                let v = eval(o, env);
                match op {
                    RustOp::Add => acc + v,
                    RustOp::Sub => acc - v,
                    RustOp::Mul => acc * v,
                    RustOp::Div => acc / v,
                }
            }),
            RustCode::Call(callee, args) => {
                let a: Vec<f64> = args.iter().map(|x| eval(x, env)).collect();
                match (callee.as_str(), a.as_slice()) {
                    ("libm::sin", [x]) => libm::sin(*x),
                    ("libm::atan2", [y, x]) => libm::atan2(*y, *x),
                    _ => f64::NAN,
                }
            }
        }
    }

    /// Parses one laid-out expression back into code, with Rust's precedence (the tokens the generator prints).
    fn parse(text: &str) -> RustCode {
        let tokens: Vec<String> = {
            let mut out = Vec::new();
            let mut cur = String::new();
            for c in text.chars() {
                if c.is_alphanumeric() || matches!(c, '_' | '.' | ':') {
                    cur.push(c);
                } else {
                    if !cur.is_empty() {
                        out.push(std::mem::take(&mut cur));
                    }
                    if c != ' ' {
                        out.push(c.to_string());
                    }
                }
            }
            if !cur.is_empty() {
                out.push(cur);
            }
            out
        };
        let mut pos = 0;
        let code = parse_sum(&tokens, &mut pos);
        assert_eq!(pos, tokens.len(), "trailing tokens in {text}");
        code
    }

    fn parse_chain(
        tokens: &[String],
        pos: &mut usize,
        ops: [(&str, RustOp); 2],
        operand: fn(&[String], &mut usize) -> RustCode,
    ) -> RustCode {
        let first = operand(tokens, pos);
        let mut rest = Vec::new();
        while let Some(op) = tokens
            .get(*pos)
            .and_then(|t| ops.iter().find(|(s, _)| s == t).map(|o| o.1))
        {
            *pos += 1;
            rest.push((op, operand(tokens, pos)));
        }
        if rest.is_empty() {
            first
        } else {
            RustCode::Chain(Box::new(first), rest)
        }
    }

    fn parse_sum(tokens: &[String], pos: &mut usize) -> RustCode {
        parse_chain(
            tokens,
            pos,
            [("+", RustOp::Add), ("-", RustOp::Sub)],
            parse_product,
        )
    }

    fn parse_product(tokens: &[String], pos: &mut usize) -> RustCode {
        parse_chain(
            tokens,
            pos,
            [("*", RustOp::Mul), ("/", RustOp::Div)],
            parse_unary,
        )
    }

    fn parse_unary(tokens: &[String], pos: &mut usize) -> RustCode {
        let t = tokens.get(*pos).cloned().unwrap_or_default();
        *pos += 1;
        match t.as_str() {
            "-" => RustCode::Neg(Box::new(parse_unary(tokens, pos))),
            "(" => {
                let inner = parse_sum(tokens, pos);
                assert_eq!(tokens.get(*pos).map(String::as_str), Some(")"));
                *pos += 1;
                RustCode::Paren(Box::new(inner))
            }
            name if tokens.get(*pos).map(String::as_str) == Some("(") => {
                *pos += 1;
                let mut args = vec![parse_sum(tokens, pos)];
                while tokens.get(*pos).map(String::as_str) == Some(",") {
                    *pos += 1;
                    args.push(parse_sum(tokens, pos));
                }
                assert_eq!(tokens.get(*pos).map(String::as_str), Some(")"));
                *pos += 1;
                RustCode::Call(name.to_string(), args)
            }
            name => atom(name),
        }
    }

    /// Random expressions laid out in a function at the top level and inside a module: rustfmt changes nothing,
    /// every line fits, and the lines compute the expression's value to the bit.
    #[test]
    fn random_statements_are_rustfmt_stable_and_keep_their_value() {
        let mut rng = TestRng(11);
        for base in [0, 4] {
            let mut namer = Namer::with_reserved();
            let mut body = Body::new(&mut namer, base + 4, MAX_WIDTH - base);
            let mut codes = Vec::new();
            for k in 0..150 {
                let code = random_code(&mut rng, 3);
                body.statement(&format!("let value_{k} = "), &code, ";");
                codes.push(code);
            }
            let lines = body.finish();
            // Not vacuous: many statements needed temporaries.
            let temps = lines
                .lines()
                .filter(|l| l.trim_start().starts_with("let t"))
                .count();
            assert!(temps > 100, "only {temps} temporaries");
            let pad = " ".repeat(base);
            let mut text = String::new();
            if base > 0 {
                text.push_str("mod m {\n");
            }
            text.push_str(&format!("{pad}fn f() {{\n{lines}{pad}}}\n"));
            if base > 0 {
                text.push_str("}\n");
            }
            assert_rustfmt_stable(&text);
            // Run the lines: each `let` binds its value; each `value_k` must be the expression's value.
            let mut env = std::collections::HashMap::new();
            for line in lines.lines() {
                let stmt = line.trim().trim_end_matches(';');
                let (name, value) = stmt
                    .strip_prefix("let ")
                    .and_then(|s| s.split_once(" = "))
                    .unwrap_or_else(|| panic!("not a let: {line}"));
                assert!(width(line) + base <= MAX_WIDTH, "{line}");
                let v = eval(&parse(value), &env);
                env.insert(name.to_string(), v);
            }
            for (k, code) in codes.iter().enumerate() {
                let want = eval(code, &std::collections::HashMap::new());
                let got = env.get(&format!("value_{k}")).copied().unwrap_or(f64::NAN);
                assert_eq!(got.to_bits(), want.to_bits(), "value_{k}: {code}");
            }
        }
    }
}
