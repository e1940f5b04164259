//! Input signals: expressions of time `t` given on the command line, or a record's samples ([`Samples`]).
//!
//! Grammar (usual precedence, `^` right-associative and binding tighter than unary minus, as in `-t^2 = -(t^2)`):
//!
//! ```text
//! expr   = term (('+' | '-') term)*
//! term   = unary (('*' | '/') unary)*
//! unary  = '-' unary | '+' unary | power
//! power  = atom ('^' unary)?
//! atom   = NUMBER | 't' | 'pi' | NAME '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//!
//! Functions: `step(t0)` (0 for `t < t0`, 1 from `t0` on), `ramp(t0)` (`max(t - t0, 0)`), `sin`, `cos`, `tan`,
//! `exp`, `ln`, `sqrt`, `abs`, `sign`, `min(a, b)`, `max(a, b)`. The constant arguments of `step` and `ramp` are
//! the signal's breakpoints: the integrator restarts there, so a jump is resolved exactly instead of by step
//! rejection. A signal's time derivative is [`Signal::derivative`] (module [`super::input_rate`]).

use super::samples::Samples;
use std::fmt;

/// A parsed input signal.
#[derive(Clone, Debug, PartialEq)]
pub enum Signal {
    Num(f64),
    Time,
    Neg(Box<Signal>),
    Add(Box<Signal>, Box<Signal>),
    Sub(Box<Signal>, Box<Signal>),
    Mul(Box<Signal>, Box<Signal>),
    Div(Box<Signal>, Box<Signal>),
    Pow(Box<Signal>, Box<Signal>),
    Call(SignalFunc, Vec<Signal>),
    /// A recorded signal, replayed between its samples.
    Samples(Samples),
}

/// The functions a signal may call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignalFunc {
    Step,
    Ramp,
    Sin,
    Cos,
    Tan,
    Exp,
    Sqrt,
    Abs,
    Min,
    Max,
    Sign,
    Ln,
}

impl SignalFunc {
    const ALL: [(&'static str, SignalFunc, usize); 12] = [
        ("step", SignalFunc::Step, 1),
        ("ramp", SignalFunc::Ramp, 1),
        ("sin", SignalFunc::Sin, 1),
        ("cos", SignalFunc::Cos, 1),
        ("tan", SignalFunc::Tan, 1),
        ("exp", SignalFunc::Exp, 1),
        ("sqrt", SignalFunc::Sqrt, 1),
        ("abs", SignalFunc::Abs, 1),
        ("min", SignalFunc::Min, 2),
        ("max", SignalFunc::Max, 2),
        ("sign", SignalFunc::Sign, 1),
        ("ln", SignalFunc::Ln, 1),
    ];
}

/// Why a signal could not be parsed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message} at column {column}")]
pub struct SignalError {
    /// 1-based character column in the expression.
    pub column: usize,
    pub message: String,
}

impl Signal {
    /// Parses an expression of `t`.
    pub fn parse(text: &str) -> Result<Signal, SignalError> {
        let mut p = Parser {
            chars: text.chars().collect(),
            pos: 0,
            depth: 0,
        };
        let s = p.expr()?;
        p.skip_space();
        if let Some(c) = p.peek() {
            return Err(p.error(format!("unexpected `{c}`")));
        }
        Ok(s)
    }

    /// The value at time `t`.
    pub fn eval(&self, t: f64) -> f64 {
        match self {
            Signal::Num(v) => *v,
            Signal::Time => t,
            Signal::Samples(s) => s.eval(t),
            Signal::Neg(a) => -a.eval(t),
            Signal::Add(a, b) => a.eval(t) + b.eval(t),
            Signal::Sub(a, b) => a.eval(t) - b.eval(t),
            Signal::Mul(a, b) => a.eval(t) * b.eval(t),
            Signal::Div(a, b) => a.eval(t) / b.eval(t),
            Signal::Pow(a, b) => a.eval(t).powf(b.eval(t)),
            Signal::Call(f, args) => {
                let x = args.first().map_or(f64::NAN, |a| a.eval(t));
                let y = args.get(1).map_or(f64::NAN, |a| a.eval(t));
                match f {
                    SignalFunc::Step => {
                        if t >= x {
                            1.0
                        } else {
                            0.0
                        }
                    }
                    SignalFunc::Ramp => (t - x).max(0.0),
                    SignalFunc::Sin => x.sin(),
                    SignalFunc::Cos => x.cos(),
                    SignalFunc::Tan => x.tan(),
                    SignalFunc::Exp => x.exp(),
                    SignalFunc::Sqrt => x.sqrt(),
                    SignalFunc::Abs => x.abs(),
                    SignalFunc::Min => x.min(y),
                    SignalFunc::Max => x.max(y),
                    SignalFunc::Sign => {
                        if x > 0.0 {
                            1.0
                        } else if x < 0.0 {
                            -1.0
                        } else {
                            0.0
                        }
                    }
                    SignalFunc::Ln => x.ln(),
                }
            }
        }
    }

    /// The times at which the signal may jump or kink: the constant arguments of `step` and `ramp`.
    pub fn breakpoints(&self, out: &mut Vec<f64>) {
        match self {
            Signal::Num(_) | Signal::Time => {}
            Signal::Samples(s) => s.breakpoints(out),
            Signal::Neg(a) => a.breakpoints(out),
            Signal::Add(a, b)
            | Signal::Sub(a, b)
            | Signal::Mul(a, b)
            | Signal::Div(a, b)
            | Signal::Pow(a, b) => {
                a.breakpoints(out);
                b.breakpoints(out);
            }
            Signal::Call(f, args) => {
                if matches!(f, SignalFunc::Step | SignalFunc::Ramp)
                    && let Some(a) = args.first()
                    && !a.uses_time()
                {
                    out.push(a.eval(0.0));
                }
                args.iter().for_each(|a| a.breakpoints(out));
            }
        }
    }

    /// True when the value depends on `t`.
    pub fn uses_time(&self) -> bool {
        match self {
            Signal::Num(_) => false,
            Signal::Time | Signal::Samples(_) => true,
            Signal::Neg(a) => a.uses_time(),
            Signal::Add(a, b)
            | Signal::Sub(a, b)
            | Signal::Mul(a, b)
            | Signal::Div(a, b)
            | Signal::Pow(a, b) => a.uses_time() || b.uses_time(),
            // `step(a)` and `ramp(a)` compare `t` with their argument.
            Signal::Call(SignalFunc::Step | SignalFunc::Ramp, _) => true,
            Signal::Call(_, args) => args.iter().any(Signal::uses_time),
        }
    }
}

impl fmt::Display for SignalFunc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = SignalFunc::ALL
            .iter()
            .find(|(_, g, _)| g == self)
            .map_or("?", |(n, _, _)| n);
        f.write_str(name)
    }
}

/// Nesting deeper than this is refused rather than risking the stack.
const MAX_DEPTH: usize = 200;

struct Parser {
    chars: Vec<char>,
    pos: usize,
    depth: usize,
}

impl Parser {
    fn error(&self, message: String) -> SignalError {
        SignalError {
            column: self.pos + 1,
            message,
        }
    }

    /// "expected X", with what the character found probably meant.
    fn expected(&self, what: &str) -> SignalError {
        let hint = match self.peek() {
            Some('<' | '>') => {
                "; there are no comparisons: `step(t0)` is 0 before `t0` and 1 from `t0` on, as in \
                 `10*step(0.1)`"
            }
            Some('[') => "; a unit goes after the whole expression, as in `30*sin(t) [deg]`",
            _ => "",
        };
        self.error(format!("expected {what}{hint}"))
    }

    fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).copied()
    }

    fn skip_space(&mut self) {
        while self.peek().is_some_and(char::is_whitespace) {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: char) -> bool {
        self.skip_space();
        if self.peek() == Some(c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn enter(&mut self) -> Result<(), SignalError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error("expression nested too deeply".into()));
        }
        Ok(())
    }

    fn expr(&mut self) -> Result<Signal, SignalError> {
        self.enter()?;
        let mut lhs = self.term()?;
        loop {
            if self.eat('+') {
                lhs = Signal::Add(Box::new(lhs), Box::new(self.term()?));
            } else if self.eat('-') {
                lhs = Signal::Sub(Box::new(lhs), Box::new(self.term()?));
            } else {
                break;
            }
        }
        self.depth -= 1;
        Ok(lhs)
    }

    fn term(&mut self) -> Result<Signal, SignalError> {
        let mut lhs = self.unary()?;
        loop {
            if self.eat('*') {
                lhs = Signal::Mul(Box::new(lhs), Box::new(self.unary()?));
            } else if self.eat('/') {
                lhs = Signal::Div(Box::new(lhs), Box::new(self.unary()?));
            } else {
                break;
            }
        }
        Ok(lhs)
    }

    fn unary(&mut self) -> Result<Signal, SignalError> {
        self.enter()?;
        let s = if self.eat('-') {
            Signal::Neg(Box::new(self.unary()?))
        } else if self.eat('+') {
            self.unary()?
        } else {
            let base = self.atom()?;
            if self.eat('^') {
                Signal::Pow(Box::new(base), Box::new(self.unary()?))
            } else {
                base
            }
        };
        self.depth -= 1;
        Ok(s)
    }

    fn atom(&mut self) -> Result<Signal, SignalError> {
        self.skip_space();
        match self.peek() {
            Some('(') => {
                self.pos += 1;
                let e = self.expr()?;
                if !self.eat(')') {
                    return Err(self.expected("`)`"));
                }
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            Some(c) if c.is_alphabetic() || c == '_' => self.name(),
            Some(c) => Err(self.error(format!("unexpected `{c}`"))),
            None => Err(self.error("unexpected end of the expression".into())),
        }
    }

    fn number(&mut self) -> Result<Signal, SignalError> {
        let start = self.pos;
        while self.peek().is_some_and(|c| c.is_ascii_digit() || c == '.') {
            self.pos += 1;
        }
        if matches!(self.peek(), Some('e' | 'E')) {
            let mark = self.pos;
            self.pos += 1;
            if matches!(self.peek(), Some('+' | '-')) {
                self.pos += 1;
            }
            if self.peek().is_some_and(|c| c.is_ascii_digit()) {
                while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                    self.pos += 1;
                }
            } else {
                self.pos = mark;
            }
        }
        let text: String = self
            .chars
            .get(start..self.pos)
            .unwrap_or(&[])
            .iter()
            .collect();
        text.parse::<f64>()
            .map(Signal::Num)
            .map_err(|_| SignalError {
                column: start + 1,
                message: format!("`{text}` is not a number"),
            })
    }

    fn name(&mut self) -> Result<Signal, SignalError> {
        let start = self.pos;
        while self.peek().is_some_and(|c| c.is_alphanumeric() || c == '_') {
            self.pos += 1;
        }
        let name: String = self
            .chars
            .get(start..self.pos)
            .unwrap_or(&[])
            .iter()
            .collect();
        match name.as_str() {
            "t" => return Ok(Signal::Time),
            "pi" => return Ok(Signal::Num(std::f64::consts::PI)),
            _ => {}
        }
        let Some(&(_, func, arity)) = SignalFunc::ALL.iter().find(|(n, _, _)| *n == name) else {
            let message = match name.as_str() {
                "heaviside" | "Heaviside" | "unitstep" | "H" => format!(
                    "unknown name `{name}`: the unit step is `step(t0)`, 0 before `t0` and 1 from `t0` on"
                ),
                _ => format!(
                    "unknown name `{name}` (an input may use `t`, `pi`, numbers and step, ramp, sin, cos, tan, exp, ln, sqrt, abs, sign, min, max)"
                ),
            };
            return Err(SignalError {
                column: start + 1,
                message,
            });
        };
        if !self.eat('(') {
            return Err(self.error(format!("expected `(` after `{name}`")));
        }
        let mut args = vec![self.expr()?];
        while self.eat(',') {
            args.push(self.expr()?);
        }
        if !self.eat(')') {
            return Err(self.expected("`)` or `,`"));
        }
        if args.len() != arity {
            return Err(SignalError {
                column: start + 1,
                message: format!(
                    "`{name}` takes {arity} argument{}, got {}",
                    if arity == 1 { "" } else { "s" },
                    args.len()
                ),
            });
        }
        // A switching time that is not a number would switch never, silently (`t >= NaN` is false).
        if matches!(func, SignalFunc::Step | SignalFunc::Ramp)
            && let Some(a) = args.first()
            && !a.uses_time()
            && a.eval(0.0).is_nan()
        {
            return Err(SignalError {
                column: start + 1,
                message: format!("the time of `{name}` is not a number (NaN)"),
            });
        }
        Ok(Signal::Call(func, args))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str, t: f64) -> f64 {
        Signal::parse(text).unwrap().eval(t)
    }

    #[test]
    fn a_switching_time_that_is_not_a_number_is_refused() {
        let err = Signal::parse("2*step(0/0)").err();
        assert_eq!(
            err.map(|e| e.to_string()),
            Some("the time of `step` is not a number (NaN) at column 3".to_string())
        );
        assert!(Signal::parse("ramp(ln(-1))").is_err());
        // An infinite time is a switch that never comes (or always was): a number, accepted.
        assert_eq!(at("step(1/0)", 1e300), 0.0);
        assert_eq!(at("step(-1/0)", 0.0), 1.0);
    }

    #[test]
    fn evaluates_with_usual_precedence() {
        assert_eq!(at("1 + 2*3 - 4/2", 0.0), 5.0);
        assert_eq!(at("-t^2", 3.0), -9.0);
        assert_eq!(at("2^3^2", 0.0), 512.0);
        assert_eq!(at("(1+2)*t", 2.0), 6.0);
        assert_eq!(at("1.5e1 + 2E-1", 0.0), 15.2);
        assert!((at("sin(2*pi*t)", 0.25) - 1.0).abs() < 1e-15);
        assert!((at("cos(pi)", 0.0) + 1.0).abs() < 1e-15);
        assert_eq!(at("max(t, 2) + min(t, 2)", 5.0), 7.0);
    }

    #[test]
    fn step_and_ramp_switch_at_their_time() {
        assert_eq!(at("3*step(0.5)", 0.499), 0.0);
        assert_eq!(at("3*step(0.5)", 0.5), 3.0);
        assert_eq!(at("ramp(1)", 0.5), 0.0);
        assert_eq!(at("ramp(1)", 3.0), 2.0);
        let mut b = Vec::new();
        Signal::parse("step(0.5) - 2*step(1.5) + ramp(2) + step(t)")
            .unwrap()
            .breakpoints(&mut b);
        assert_eq!(b, vec![0.5, 1.5, 2.0]);
    }

    #[test]
    fn comparisons_steps_and_units_of_other_tools_say_what_to_write() {
        let said = |text: &str| Signal::parse(text).unwrap_err().message;
        assert!(
            said("10*(t>0.1)").contains("`step(t0)` is 0 before `t0`"),
            "{}",
            said("10*(t>0.1)")
        );
        assert!(said("heaviside(t-0.1)").contains("the unit step is `step(t0)`"));
        assert!(said("sin(2 [rad])").contains("a unit goes after the whole expression"));
        assert_eq!(said("(1"), "expected `)`");
    }

    #[test]
    fn errors_name_the_column() {
        let e = Signal::parse("1 + foo(t)").unwrap_err();
        assert_eq!(e.column, 5);
        assert!(e.message.contains("unknown name `foo`"));
        assert_eq!(Signal::parse("sin(t").unwrap_err().column, 6);
        assert!(
            Signal::parse("step(1, 2)")
                .unwrap_err()
                .message
                .contains("takes 1 argument")
        );
        assert!(Signal::parse("1 +").is_err());
        assert!(
            Signal::parse("2 3")
                .unwrap_err()
                .message
                .contains("unexpected `3`")
        );
        assert!(
            Signal::parse("1..2")
                .unwrap_err()
                .message
                .contains("not a number")
        );
        assert!(Signal::parse(&"(".repeat(10_000)).is_err());
    }
}
