//! Rust source printer for generated model code.
//!
//! The printed code needs only `core` and the [`libm`] crate, so that generated models build without `std`
//! (`f64::sin`, `powf`, `sqrt` and `powi` are `std` methods). Forms: `bgc_powi(x, 2)` for integer constant exponents,
//! `libm::sqrt(x)` for `x^0.5`, `libm::pow(x, e)` otherwise, `1.0 / x` for negative exponents, `libm::sin(x)` for
//! the functions of the language under their C names (`ln` is `libm::log`, `abs` is `libm::fabs`),
//! `libm::atan2(y, x)`. The evaluator (`eval.rs`) calls the same functions in the same order, so evaluation and
//! generated code agree to the last bit on every platform.
//!
//! `sign`, `min`, `max` and integer powers print as calls to helpers ([`RUST_SIGN_FN`], [`RUST_MIN_FN`],
//! [`RUST_MAX_FN`], [`RUST_POWI_FN`]): `f64::signum(0.0)` is 1 while bgc's `sign(0)` is 0, `f64::min`/`f64::max`
//! return the other argument for a NaN while bgc's propagate it, and `f64::powi` is not in `core` and leaves the
//! order of its multiplications to the compiler. Generated code defines the helpers it calls; [`RUST_HELPERS`] is
//! their source and [`rust_helpers_used`] picks those a piece of code calls.
//!
//! Constants print as Rust's shortest round-trip `f64` literals (`2.0`, `0.1`, `1e-7`), and `f64::INFINITY`,
//! `f64::NEG_INFINITY`, `f64::NAN` for non-finite values. Symbol names come from the caller's closure and must be
//! Rust expressions that bind at least as tightly as a field access (a path, a field access `p.J_m` or an index
//! `x[0]`).
//!
//! [`to_rust_code`] gives the printed expression as a [`RustCode`] tree (how Rust parses the text), which code
//! generation uses to break long expressions into `let` lines; [`to_rust`] is its text.

use super::super::eval::as_i32;
use super::super::expr::{Expr, Node, Symbol};
use super::plan::{Keep, Kept, plan};
use super::{ATOM, PRODUCT, SUM, UNARY, negated, reciprocal, split_fraction, sum_print_order};
use crate::ir::Func;
use std::fmt;

/// The name of the sign helper that printed code calls.
pub const RUST_SIGN_FN: &str = "bgc_sign";
/// The name of the NaN-propagating minimum that printed code calls.
pub const RUST_MIN_FN: &str = "bgc_min";
/// The name of the NaN-propagating maximum that printed code calls.
pub const RUST_MAX_FN: &str = "bgc_max";
/// The name of the integer power that printed code calls.
pub const RUST_POWI_FN: &str = "bgc_powi";

/// The source of the helpers printed code calls: [`RUST_SIGN_FN`] (`sign(±0) = 0`, `sign(NaN) = NaN`, else ±1),
/// [`RUST_MIN_FN`] and [`RUST_MAX_FN`] (NaN when either argument is NaN), [`RUST_POWI_FN`] (binary powering).
/// Items are separated by one blank line, each starting with its doc comment.
pub const RUST_HELPERS: &str = include_str!("rust_helpers.rs");

/// The names of the helpers generated code may call.
pub const RUST_HELPER_FNS: [&str; 4] = [RUST_SIGN_FN, RUST_MIN_FN, RUST_MAX_FN, RUST_POWI_FN];

/// The start of every name in [`RUST_HELPER_FNS`]: a line without it calls none (one search instead of four over
/// a large module's hundreds of megabytes).
pub const RUST_HELPER_PREFIX: &str = "bgc_";

/// The helpers of [`RUST_HELPERS`] that `code` calls, in their order there, each followed by a blank line.
pub fn rust_helpers_used(code: &str) -> String {
    let mut out = String::new();
    for item in RUST_HELPERS.split("\n\n") {
        let item = item.trim_end_matches('\n');
        let called = RUST_HELPER_FNS.into_iter().any(|name| {
            item.contains(&format!("fn {name}(")) && code.contains(&format!("{name}("))
        });
        if called {
            out.push_str(item);
            out.push_str("\n\n");
        }
    }
    out
}

/// A binary operator of printed code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RustOp {
    Add,
    Sub,
    Mul,
    Div,
}

impl RustOp {
    pub fn as_str(self) -> &'static str {
        match self {
            RustOp::Add => "+",
            RustOp::Sub => "-",
            RustOp::Mul => "*",
            RustOp::Div => "/",
        }
    }
}

/// Printed code as Rust parses it. Every node is an expression of its own in Rust's parse of the whole text, and so
/// is every prefix `first op a op b` of a chain: any of them can be bound to a `let` and replaced by its name
/// without changing what is computed.
#[derive(Clone, Debug, PartialEq)]
pub enum RustCode {
    /// A literal, a name or a path, printed as is.
    Atom(String),
    /// `-operand`, the operand binding at least as tightly as unary minus.
    Neg(Box<RustCode>),
    /// `first op operand op operand ...`: left-associative operators of one precedence level (`+ -` or `* /`),
    /// each operand binding more tightly.
    Chain(Box<RustCode>, Vec<(RustOp, RustCode)>),
    /// `(inner)`.
    Paren(Box<RustCode>),
    /// `callee(arguments)`.
    Call(String, Vec<RustCode>),
}

impl RustCode {
    /// Whether the code is a name or a literal.
    pub fn is_atom(&self) -> bool {
        matches!(self, RustCode::Atom(_))
    }
}

impl fmt::Display for RustCode {
    /// Writes the code with a work list rather than by recursion, so that deep code cannot overflow the stack.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        enum Item<'a> {
            Code(&'a RustCode),
            Text(&'a str),
        }
        let mut pending = vec![Item::Code(self)];
        while let Some(item) = pending.pop() {
            let code = match item {
                Item::Text(s) => {
                    f.write_str(s)?;
                    continue;
                }
                Item::Code(code) => code,
            };
            match code {
                RustCode::Atom(s) => f.write_str(s)?,
                RustCode::Neg(inner) => {
                    f.write_str("-")?;
                    pending.push(Item::Code(inner));
                }
                RustCode::Chain(first, rest) => {
                    for (op, operand) in rest.iter().rev() {
                        pending.push(Item::Code(operand));
                        pending.push(Item::Text(" "));
                        pending.push(Item::Text(op.as_str()));
                        pending.push(Item::Text(" "));
                    }
                    pending.push(Item::Code(first));
                }
                RustCode::Paren(inner) => {
                    f.write_str("(")?;
                    pending.push(Item::Text(")"));
                    pending.push(Item::Code(inner));
                }
                RustCode::Call(callee, args) => {
                    write!(f, "{callee}(")?;
                    pending.push(Item::Text(")"));
                    for (i, a) in args.iter().enumerate().rev() {
                        pending.push(Item::Code(a));
                        if i > 0 {
                            pending.push(Item::Text(", "));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Frees `code` with a work list: dropping a deep tree by recursion could overflow the stack.
fn dismantle(code: RustCode) {
    let mut pending = vec![code];
    while let Some(code) = pending.pop() {
        match code {
            RustCode::Atom(_) => {}
            RustCode::Neg(inner) | RustCode::Paren(inner) => pending.push(*inner),
            RustCode::Chain(first, rest) => {
                pending.push(*first);
                pending.extend(rest.into_iter().map(|(_, c)| c));
            }
            RustCode::Call(_, args) => pending.extend(args),
        }
    }
}

impl Keep for RustCode {
    type Stored = RustCode;
    fn store(self) -> RustCode {
        self
    }
    fn reuse(stored: &RustCode) -> RustCode {
        stored.clone()
    }
    fn take(stored: RustCode) -> RustCode {
        stored
    }
}

/// `e` as a Rust `f64` expression, each symbol printed as `names` says.
pub fn to_rust(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> String {
    let code = to_rust_code(e, names);
    let text = code.to_string();
    dismantle(code);
    text
}

/// `e` as a tree of Rust code (whose text is [`to_rust`]), each symbol printed as `names` says.
pub fn to_rust_code(e: &Expr, names: &dyn Fn(&Symbol) -> String) -> RustCode {
    let printer = RustPrinter {
        names,
        kept: Kept::new(),
    };
    for (node, reused) in plan(e) {
        let printed = printer.print_node(node);
        printer.kept.insert(node, printed, reused);
    }
    printer.print(e).0
}

fn rust_number(c: f64) -> String {
    if c.is_nan() {
        "f64::NAN".to_string()
    } else if c.is_infinite() {
        if c > 0.0 {
            "f64::INFINITY"
        } else {
            "f64::NEG_INFINITY"
        }
        .to_string()
    } else {
        format!("{c:?}")
    }
}

/// The `libm` function computing a one-argument function of the language.
fn libm_name(f: Func) -> &'static str {
    match f {
        Func::Sin => "sin",
        Func::Cos => "cos",
        Func::Tan => "tan",
        Func::Asin => "asin",
        Func::Acos => "acos",
        Func::Atan => "atan",
        Func::Atan2 => "atan2",
        Func::Exp => "exp",
        Func::Ln => "log",
        Func::Log10 => "log10",
        Func::Sqrt => "sqrt",
        Func::Abs => "fabs",
        Func::Tanh => "tanh",
        Func::Sinh => "sinh",
        Func::Cosh => "cosh",
        // Not libm functions: printed as helper calls before this is asked.
        Func::Sign => RUST_SIGN_FN,
        Func::Min => RUST_MIN_FN,
        Func::Max => RUST_MAX_FN,
    }
}

/// A chain of `operands` joined by `op`.
fn chain(mut operands: Vec<RustCode>, op: RustOp) -> RustCode {
    if operands.len() == 1 {
        return operands.remove(0);
    }
    let mut iter = operands.into_iter();
    let first = iter.next().unwrap_or(RustCode::Atom("0.0".into()));
    RustCode::Chain(Box::new(first), iter.map(|o| (op, o)).collect())
}

/// `-code`, the minus on the first operand when `code` is a chain (as `-a * b` parses).
fn negate(code: RustCode) -> RustCode {
    match code {
        RustCode::Chain(first, rest) => RustCode::Chain(Box::new(negate(*first)), rest),
        other => RustCode::Neg(Box::new(other)),
    }
}

struct RustPrinter<'a> {
    names: &'a dyn Fn(&Symbol) -> String,
    kept: Kept<RustCode>,
}

impl RustPrinter<'_> {
    fn print(&self, e: &Expr) -> (RustCode, u8) {
        match self.kept.fetch(e) {
            Some(kept) => kept,
            None => self.print_node(e),
        }
    }

    fn print_node(&self, e: &Expr) -> (RustCode, u8) {
        match e.node() {
            Node::Const(c) => (
                RustCode::Atom(rust_number(*c)),
                if *c < 0.0 { UNARY } else { ATOM },
            ),
            Node::Sym(s) => (RustCode::Atom((self.names)(s)), ATOM),
            Node::Add(terms) => (self.sum(terms), SUM),
            Node::Mul(_) => match negated(e) {
                Some(pos) => (negate(self.product(&pos)), PRODUCT),
                None => (self.product(e), PRODUCT),
            },
            Node::Pow(b, x) => match reciprocal(e) {
                Some(_) => (self.product(e), PRODUCT),
                None => (self.power(b, x), ATOM),
            },
            Node::Call(f, args) => (self.call(*f, args), ATOM),
        }
    }

    fn wrapped(&self, e: &Expr, need: u8) -> RustCode {
        let (code, p) = self.print(e);
        if p < need {
            RustCode::Paren(Box::new(code))
        } else {
            code
        }
    }

    fn sum(&self, terms: &[Expr]) -> RustCode {
        let mut first = None;
        let mut rest = Vec::new();
        for (i, t) in sum_print_order(terms).into_iter().enumerate() {
            match (i, negated(t)) {
                (0, _) => first = Some(self.print(t).0),
                (_, Some(pos)) => rest.push((RustOp::Sub, self.wrapped(&pos, PRODUCT))),
                (_, None) => rest.push((RustOp::Add, self.print(t).0)),
            }
        }
        let first = first.unwrap_or(RustCode::Atom("0.0".into()));
        if rest.is_empty() {
            first
        } else {
            RustCode::Chain(Box::new(first), rest)
        }
    }

    fn product(&self, e: &Expr) -> RustCode {
        let fr = split_fraction(e);
        let mut num: Vec<RustCode> = Vec::new();
        if fr.coeff != 1.0 {
            num.push(RustCode::Atom(rust_number(fr.coeff)));
        }
        num.extend(fr.num.iter().map(|f| self.wrapped(f, UNARY)));
        if num.is_empty() {
            num.push(RustCode::Atom("1.0".into()));
        }
        let den = match fr.den.as_slice() {
            [] => return chain(num, RustOp::Mul),
            [single] => self.wrapped(single, ATOM),
            many => RustCode::Paren(Box::new(chain(
                many.iter().map(|f| self.wrapped(f, UNARY)).collect(),
                RustOp::Mul,
            ))),
        };
        match chain(num, RustOp::Mul) {
            RustCode::Chain(first, mut rest) => {
                rest.push((RustOp::Div, den));
                RustCode::Chain(first, rest)
            }
            single => RustCode::Chain(Box::new(single), vec![(RustOp::Div, den)]),
        }
    }

    fn power(&self, base: &Expr, exp: &Expr) -> RustCode {
        let b = self.print(base).0;
        match exp.as_const() {
            Some(0.5) => RustCode::Call("libm::sqrt".into(), vec![b]),
            Some(c) => match as_i32(c) {
                Some(n) => {
                    RustCode::Call(RUST_POWI_FN.into(), vec![b, RustCode::Atom(n.to_string())])
                }
                None => RustCode::Call("libm::pow".into(), vec![b, RustCode::Atom(rust_number(c))]),
            },
            None => RustCode::Call("libm::pow".into(), vec![b, self.print(exp).0]),
        }
    }

    fn call(&self, f: Func, args: &[Expr]) -> RustCode {
        let printed: Vec<RustCode> = args.iter().map(|a| self.print(a).0).collect();
        let callee = match f {
            Func::Sign | Func::Min | Func::Max => libm_name(f).to_string(),
            _ => format!("libm::{}", libm_name(f)),
        };
        RustCode::Call(callee, printed)
    }
}
