//! A small symbolic expression type for the equations stage.
//!
//! Expressions are built through constructors that keep them in a light canonical form, so that equal expressions
//! compare equal often enough for cancellation (`x - x = 0`, `J * J^-1 = 1`) and printing is deterministic:
//! - sums are flat, numbers are folded, like terms (same non-numeric part) are collected, terms are sorted;
//! - products are flat, numbers are folded, equal bases are collected by adding exponents, factors are sorted;
//! - `a - b` is `a + (-1)·b`, `a / b` is `a · b^-1`; a numeric power of a product is distributed.
//!
//! Nothing here knows about bond graphs: leaves are [`Sym`] symbols that the stage names.

mod expand;
mod order;

use crate::ir::Func;
pub use expand::Expander;
pub use order::key_cmp;
use std::fmt::Write;

/// A leaf symbol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Sym {
    /// A model parameter.
    Param(usize),
    /// A model input.
    Input(usize),
    /// The time derivative of an input. Kept only in the power of an element next to a storage in derivative
    /// causality (energy terms); a rate or output that keeps one is refused.
    InputDot(usize),
    /// A state (index into the equations' state list).
    State(usize),
    /// The time derivative of a state (an unknown while derivative causality is resolved).
    StateDot(usize),
    /// An intermediate bond variable (index into the equations' variable table).
    Var(usize),
    /// A tear variable of an algebraic loop (the variable index it stands for).
    Tear(usize),
    /// Time.
    Time,
    /// The value of an earlier output (index into the equations' outputs): an output defined through earlier
    /// outputs refers to them instead of copying their expressions, and consumers evaluate outputs in order.
    Output(usize),
}

impl Sym {
    /// Writes the symbol as its `Debug` form (`Param(3)`, `Time`), which keys and so the order of terms are made
    /// of, without the formatter's machinery.
    fn write_key(self, s: &mut impl Write) {
        let (name, index) = match self {
            Sym::Param(i) => ("Param", i),
            Sym::Input(i) => ("Input", i),
            Sym::InputDot(i) => ("InputDot", i),
            Sym::State(i) => ("State", i),
            Sym::StateDot(i) => ("StateDot", i),
            Sym::Var(i) => ("Var", i),
            Sym::Tear(i) => ("Tear", i),
            Sym::Output(i) => ("Output", i),
            Sym::Time => {
                let _ = s.write_str("Time");
                return;
            }
        };
        let _ = write!(s, "{name}({index})");
    }
}

/// A symbolic expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Ex {
    Num(f64),
    S(Sym),
    Add(Vec<Ex>),
    Mul(Vec<Ex>),
    Pow(Box<Ex>, Box<Ex>),
    Call(Func, Vec<Ex>),
}

impl Ex {
    pub fn zero() -> Ex {
        Ex::Num(0.0)
    }

    pub fn one() -> Ex {
        Ex::Num(1.0)
    }

    pub fn sym(s: Sym) -> Ex {
        Ex::S(s)
    }

    pub fn num(&self) -> Option<f64> {
        match self {
            Ex::Num(v) => Some(*v),
            _ => None,
        }
    }

    pub fn is_zero(&self) -> bool {
        self.num() == Some(0.0)
    }

    /// A structural key: equal keys mean equal expressions. Used for sorting and collecting.
    pub fn key(&self) -> String {
        let mut s = String::new();
        self.write_key(&mut s);
        s
    }

    /// The length of [`Ex::key`], without building it.
    pub fn key_len(&self) -> usize {
        let mut counter = KeyLength(0);
        self.write_key(&mut counter);
        counter.0
    }

    fn write_key(&self, s: &mut impl Write) {
        match self {
            // Numbers sort first; their bit pattern makes the key exact.
            // Written in place: a key is built for every term of every sum and product, so no temporary strings.
            Ex::Num(v) => {
                let _ = write!(s, "#{v:e}");
            }
            Ex::S(sym) => sym.write_key(s),
            Ex::Add(ts) => {
                let _ = s.write_str("+(");
                for t in ts {
                    t.write_key(s);
                    let _ = s.write_char(',');
                }
                let _ = s.write_char(')');
            }
            Ex::Mul(fs) => {
                let _ = s.write_str("*(");
                for f in fs {
                    f.write_key(s);
                    let _ = s.write_char(',');
                }
                let _ = s.write_char(')');
            }
            Ex::Pow(b, e) => {
                let _ = s.write_str("^(");
                b.write_key(s);
                let _ = s.write_char(',');
                e.write_key(s);
                let _ = s.write_char(')');
            }
            Ex::Call(f, args) => {
                let _ = s.write_str(f.name());
                let _ = s.write_char('(');
                for a in args {
                    a.write_key(s);
                    let _ = s.write_char(',');
                }
                let _ = s.write_char(')');
            }
        }
    }

    /// Visits every symbol.
    pub fn for_each_sym(&self, f: &mut dyn FnMut(Sym)) {
        match self {
            Ex::Num(_) => {}
            Ex::S(s) => f(*s),
            Ex::Add(v) | Ex::Mul(v) | Ex::Call(_, v) => v.iter().for_each(|e| e.for_each_sym(f)),
            Ex::Pow(b, e) => {
                b.for_each_sym(f);
                e.for_each_sym(f);
            }
        }
    }

    /// True when some symbol satisfies `pred`.
    pub fn any_sym(&self, pred: &dyn Fn(Sym) -> bool) -> bool {
        let mut found = false;
        self.for_each_sym(&mut |s| found |= pred(s));
        found
    }

    pub fn contains(&self, s: Sym) -> bool {
        self.any_sym(&|t| t == s)
    }
}

/// Counts the bytes of a key as it is written.
struct KeyLength(usize);

impl Write for KeyLength {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0 += s.len();
        Ok(())
    }
}

/// `a + b + ...` in canonical form.
pub fn add(terms: Vec<Ex>) -> Ex {
    let mut constant = 0.0;
    // (non-numeric part, coefficient), in the order met.
    let mut parts: Vec<(Ex, f64)> = Vec::new();
    let mut stack = terms;
    while let Some(t) = stack.pop() {
        match t {
            Ex::Num(v) => constant += v,
            Ex::Add(inner) => stack.extend(inner),
            other => {
                let (c, rest) = split_coefficient(other);
                parts.push((rest, c));
            }
        }
    }
    // Like terms are neighbours after a stable sort, in the order met: their coefficients add up in that order.
    parts.sort_by(|a, b| key_cmp(&a.0, &b.0));
    let mut out: Vec<Ex> = Vec::new();
    if constant != 0.0 {
        out.push(Ex::Num(constant));
    }
    let mut parts = parts.into_iter().peekable();
    while let Some((rest, first)) = parts.next() {
        let mut c = 0.0 + first;
        while let Some((_, more)) = parts.next_if(|(r, _)| key_cmp(r, &rest).is_eq()) {
            c += more;
        }
        if c != 0.0 {
            out.push(scale(c, rest));
        }
    }
    match out.len() {
        0 => Ex::zero(),
        1 => out.pop().unwrap_or(Ex::zero()),
        _ => Ex::Add(out),
    }
}

/// Splits `c · rest` with `c` numeric.
fn split_coefficient(e: Ex) -> (f64, Ex) {
    match e {
        Ex::Mul(fs) => {
            let mut c = 1.0;
            let mut rest = Vec::new();
            for f in fs {
                match f {
                    Ex::Num(v) => c *= v,
                    other => rest.push(other),
                }
            }
            let rest = match rest.len() {
                1 => rest.pop().unwrap_or(Ex::one()),
                _ => Ex::Mul(rest),
            };
            (c, rest)
        }
        other => (1.0, other),
    }
}

fn scale(c: f64, rest: Ex) -> Ex {
    if c == 1.0 {
        rest
    } else {
        mul(vec![Ex::Num(c), rest])
    }
}

/// `a · b · ...` in canonical form.
pub fn mul(factors: Vec<Ex>) -> Ex {
    let mut constant = 1.0;
    // (base, exponent), in the order met.
    let mut parts: Vec<(Ex, Ex)> = Vec::new();
    let mut stack = factors;
    while let Some(f) = stack.pop() {
        match f {
            Ex::Num(v) => constant *= v,
            Ex::Mul(inner) => stack.extend(inner),
            Ex::Pow(b, e) => parts.push((*b, *e)),
            other => parts.push((other, Ex::one())),
        }
    }
    if constant == 0.0 {
        return Ex::zero();
    }
    // Equal bases are neighbours after a stable sort, their exponents in the order met.
    parts.sort_by(|a, b| key_cmp(&a.0, &b.0));
    let mut out: Vec<Ex> = Vec::new();
    let mut parts = parts.into_iter().peekable();
    while let Some((base, first)) = parts.next() {
        let exponent = if parts.peek().is_some_and(|(b, _)| key_cmp(b, &base).is_eq()) {
            let mut exps = vec![first];
            while let Some((_, more)) = parts.next_if(|(b, _)| key_cmp(b, &base).is_eq()) {
                exps.push(more);
            }
            add(exps)
        } else {
            match first {
                // What `add` makes of one number (`-0` becomes `0`), without its vectors: most bases come once
                // with a numeric exponent.
                Ex::Num(v) => Ex::Num(if v == 0.0 { 0.0 } else { v }),
                other => add(vec![other]),
            }
        };
        match pow(base, exponent) {
            Ex::Num(v) => constant *= v,
            Ex::Mul(inner) => {
                // A power that distributed over a product: fold it in again (its factors are already canonical).
                for f in inner {
                    match f {
                        Ex::Num(v) => constant *= v,
                        other => out.push(other),
                    }
                }
            }
            other => out.push(other),
        }
    }
    if constant == 0.0 {
        return Ex::zero();
    }
    out.sort_by(key_cmp);
    if constant != 1.0 {
        out.insert(0, Ex::Num(constant));
    }
    match out.len() {
        0 => Ex::one(),
        1 => out.pop().unwrap_or(Ex::one()),
        _ => Ex::Mul(out),
    }
}

/// `base ^ exponent`.
pub fn pow(base: Ex, exponent: Ex) -> Ex {
    match (&base, exponent.num()) {
        (_, Some(0.0)) => Ex::one(),
        (_, Some(1.0)) => base,
        (Ex::Num(b), Some(e)) => {
            let v = b.powf(e);
            if v.is_finite() {
                Ex::Num(v)
            } else {
                Ex::Pow(Box::new(base), Box::new(exponent))
            }
        }
        (Ex::Num(b), None) if *b == 1.0 => Ex::one(),
        (Ex::Pow(b, e1), Some(e)) => match e1.num() {
            // (b^n)^m = b^(nm) for integer m (always valid) or when b^n is known positive for even n... keep to
            // integer m.
            Some(n) if e.fract() == 0.0 => pow((**b).clone(), Ex::Num(n * e)),
            _ => Ex::Pow(Box::new(base), Box::new(exponent)),
        },
        (Ex::Mul(fs), Some(e)) if e.fract() == 0.0 => {
            mul(fs.iter().map(|f| pow(f.clone(), Ex::Num(e))).collect())
        }
        _ => Ex::Pow(Box::new(base), Box::new(exponent)),
    }
}

pub fn neg(a: Ex) -> Ex {
    mul(vec![Ex::Num(-1.0), a])
}

pub fn sub(a: Ex, b: Ex) -> Ex {
    add(vec![a, neg(b)])
}

pub fn div(a: Ex, b: Ex) -> Ex {
    mul(vec![a, pow(b, Ex::Num(-1.0))])
}

pub fn recip(a: Ex) -> Ex {
    pow(a, Ex::Num(-1.0))
}

/// A function call, folded when its arguments are numbers.
pub fn call(f: Func, args: Vec<Ex>) -> Ex {
    let nums: Option<Vec<f64>> = args.iter().map(Ex::num).collect();
    if let Some(v) = nums.and_then(|n| f.eval(&n))
        && v.is_finite()
    {
        return Ex::Num(v);
    }
    Ex::Call(f, args)
}

/// Products of sums multiplied out (`a (b + c)` → `a b + a c`), except a product that would make more than 64
/// terms, which stays as it is. To expand many expressions that share parts, keep one [`Expander`].
pub fn expand(e: &Ex) -> Ex {
    Expander::default().expand(e)
}

/// True when a product with a sum among its factors is reachable through sums and products (what [`expand`]
/// multiplies out).
fn has_product_of_sum(e: &Ex) -> bool {
    match e {
        Ex::Add(ts) => ts.iter().any(has_product_of_sum),
        Ex::Mul(fs) => fs
            .iter()
            .any(|f| matches!(f, Ex::Add(_)) || has_product_of_sum(f)),
        _ => false,
    }
}

/// Replaces symbols: `f(s)` gives the replacement or `None` to keep `s`. The result is re-canonicalised.
pub fn subst(e: &Ex, f: &mut dyn FnMut(Sym) -> Option<Ex>) -> Ex {
    match e {
        Ex::Num(_) => e.clone(),
        Ex::S(s) => f(*s).unwrap_or_else(|| e.clone()),
        Ex::Add(ts) => add(ts.iter().map(|t| subst(t, f)).collect()),
        Ex::Mul(fs) => mul(fs.iter().map(|t| subst(t, f)).collect()),
        Ex::Pow(b, x) => pow(subst(b, f), subst(x, f)),
        Ex::Call(func, args) => call(*func, args.iter().map(|a| subst(a, f)).collect()),
    }
}

/// Why an expression could not be differentiated.
#[derive(Clone, Debug, PartialEq)]
pub struct NotDifferentiable(pub Func);

/// `∂e/∂s`.
pub fn diff(e: &Ex, s: Sym) -> Result<Ex, NotDifferentiable> {
    if !e.contains(s) {
        return Ok(Ex::zero());
    }
    Ok(match e {
        Ex::Num(_) => Ex::zero(),
        Ex::S(t) => {
            if *t == s {
                Ex::one()
            } else {
                Ex::zero()
            }
        }
        Ex::Add(ts) => add(ts.iter().map(|t| diff(t, s)).collect::<Result<_, _>>()?),
        Ex::Mul(fs) => {
            let mut terms = Vec::new();
            for (i, fi) in fs.iter().enumerate() {
                let d = diff(fi, s)?;
                if d.is_zero() {
                    continue;
                }
                let mut prod: Vec<Ex> = fs
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, f)| f.clone())
                    .collect();
                prod.push(d);
                terms.push(mul(prod));
            }
            add(terms)
        }
        Ex::Pow(b, x) => {
            let db = diff(b, s)?;
            if !x.contains(s) {
                // n b^(n-1) b'
                mul(vec![
                    (**x).clone(),
                    pow((**b).clone(), sub((**x).clone(), Ex::one())),
                    db,
                ])
            } else {
                // b^x (x' ln b + x b'/b)
                let dx = diff(x, s)?;
                mul(vec![
                    e.clone(),
                    add(vec![
                        mul(vec![dx, call(Func::Ln, vec![(**b).clone()])]),
                        mul(vec![(**x).clone(), db, recip((**b).clone())]),
                    ]),
                ])
            }
        }
        Ex::Call(f, args) => {
            let a = args.first().cloned().unwrap_or(Ex::zero());
            let da = diff(&a, s)?;
            let outer = match f {
                Func::Sin => call(Func::Cos, vec![a]),
                Func::Cos => neg(call(Func::Sin, vec![a])),
                Func::Tan => pow(call(Func::Cos, vec![a]), Ex::Num(-2.0)),
                Func::Asin => pow(sub(Ex::one(), pow(a, Ex::Num(2.0))), Ex::Num(-0.5)),
                Func::Acos => neg(pow(sub(Ex::one(), pow(a, Ex::Num(2.0))), Ex::Num(-0.5))),
                Func::Atan => recip(add(vec![Ex::one(), pow(a, Ex::Num(2.0))])),
                Func::Exp => call(Func::Exp, vec![a]),
                Func::Ln => recip(a),
                Func::Log10 => recip(mul(vec![Ex::Num(std::f64::consts::LN_10), a])),
                Func::Sqrt => mul(vec![Ex::Num(0.5), pow(a, Ex::Num(-0.5))]),
                Func::Abs => call(Func::Sign, vec![a]),
                // The derivative of sign is zero almost everywhere.
                Func::Sign => Ex::zero(),
                Func::Tanh => sub(Ex::one(), pow(call(Func::Tanh, vec![a]), Ex::Num(2.0))),
                Func::Sinh => call(Func::Cosh, vec![a]),
                Func::Cosh => call(Func::Sinh, vec![a]),
                Func::Atan2 => {
                    // atan2(y, x): (x y' - y x') / (x^2 + y^2)
                    let y = a;
                    let x = args.get(1).cloned().unwrap_or(Ex::one());
                    let dx = diff(&x, s)?;
                    return Ok(div(
                        sub(mul(vec![x.clone(), da]), mul(vec![y.clone(), dx])),
                        add(vec![pow(x, Ex::Num(2.0)), pow(y, Ex::Num(2.0))]),
                    ));
                }
                Func::Min | Func::Max => return Err(NotDifferentiable(*f)),
            };
            mul(vec![outer, da])
        }
    })
}

/// Why an expression could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// A symbol without a value.
    Unbound(Sym),
    /// A function call with the wrong number of arguments.
    Arity(Func),
}

/// Evaluates with values of the symbols from `value`.
pub fn eval(e: &Ex, value: &dyn Fn(Sym) -> Option<f64>) -> Result<f64, EvalError> {
    Ok(match e {
        Ex::Num(v) => *v,
        Ex::S(s) => value(*s).ok_or(EvalError::Unbound(*s))?,
        Ex::Add(ts) => {
            let mut acc = 0.0;
            for t in ts {
                acc += eval(t, value)?;
            }
            acc
        }
        Ex::Mul(fs) => {
            let mut acc = 1.0;
            for f in fs {
                acc *= eval(f, value)?;
            }
            acc
        }
        Ex::Pow(b, x) => {
            let b = eval(b, value)?;
            let x = eval(x, value)?;
            if x.fract() == 0.0 && x.abs() < 64.0 {
                b.powi(x as i32)
            } else {
                b.powf(x)
            }
        }
        Ex::Call(f, args) => {
            let vals = args
                .iter()
                .map(|a| eval(a, value))
                .collect::<Result<Vec<_>, _>>()?;
            f.eval(&vals).ok_or(EvalError::Arity(*f))?
        }
    })
}

/// `e = a·s + b` with `a`, `b` free of `s`, or `None` when `e` is not affine in `s`.
pub fn affine_in(e: &Ex, s: Sym) -> Option<(Ex, Ex)> {
    // Functions such as sign have a zero derivative almost everywhere: the derivative test alone would take
    // `sign(s)` for a constant. `s` must appear only under sums, products and integer powers.
    if !algebraic_in(e, s) {
        return None;
    }
    let a = diff(e, s).ok()?;
    if a.contains(s) {
        return None;
    }
    let b = subst(e, &mut |t| (t == s).then(Ex::zero));
    Some((a, b))
}

/// True when `s` appears in `e` only under sums, products and integer powers.
fn algebraic_in(e: &Ex, s: Sym) -> bool {
    match e {
        Ex::Num(_) | Ex::S(_) => true,
        Ex::Add(v) | Ex::Mul(v) => v.iter().all(|t| algebraic_in(t, s)),
        Ex::Pow(b, x) => {
            !x.contains(s)
                && (!b.contains(s) || x.num().is_some_and(|n| n.fract() == 0.0))
                && algebraic_in(b, s)
        }
        Ex::Call(_, args) => !args.iter().any(|a| a.contains(s)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x() -> Ex {
        Ex::S(Sym::Param(0))
    }
    fn y() -> Ex {
        Ex::S(Sym::Param(1))
    }

    #[test]
    fn cancellation_and_collection() {
        assert_eq!(sub(x(), x()), Ex::zero());
        assert_eq!(div(x(), x()), Ex::one());
        assert_eq!(add(vec![x(), x()]), mul(vec![Ex::Num(2.0), x()]));
        assert_eq!(mul(vec![x(), x()]), pow(x(), Ex::Num(2.0)));
        // Order does not matter.
        assert_eq!(add(vec![x(), y()]), add(vec![y(), x()]));
        assert_eq!(mul(vec![x(), y()]), mul(vec![y(), x()]));
        // (x y)^-1 x = y^-1
        assert_eq!(mul(vec![recip(mul(vec![x(), y()])), x()]), recip(y()));
    }

    #[test]
    fn derivatives_match_finite_differences() {
        // e = x^3 sin(x y) + exp(x)/y
        let e = add(vec![
            mul(vec![
                pow(x(), Ex::Num(3.0)),
                call(Func::Sin, vec![mul(vec![x(), y()])]),
            ]),
            div(call(Func::Exp, vec![x()]), y()),
        ]);
        let d = diff(&e, Sym::Param(0)).unwrap_or(Ex::zero());
        let at = |xv: f64| {
            move |s: Sym| match s {
                Sym::Param(0) => Some(xv),
                Sym::Param(1) => Some(0.7),
                _ => None,
            }
        };
        let h = 1e-6;
        let fd = (eval(&e, &at(1.3 + h)).unwrap_or(0.0) - eval(&e, &at(1.3 - h)).unwrap_or(0.0))
            / (2.0 * h);
        let exact = eval(&d, &at(1.3)).unwrap_or(f64::NAN);
        assert!(
            (fd - exact).abs() < 1e-6 * exact.abs().max(1.0),
            "{fd} vs {exact}"
        );
    }

    #[test]
    fn symbol_keys_are_their_debug_form() {
        for s in [
            Sym::Param(0),
            Sym::Input(12),
            Sym::InputDot(3),
            Sym::State(105),
            Sym::StateDot(7),
            Sym::Var(40),
            Sym::Tear(2),
            Sym::Output(9),
            Sym::Time,
        ] {
            assert_eq!(Ex::S(s).key(), format!("{s:?}"));
            assert_eq!(Ex::S(s).key_len(), format!("{s:?}").len());
        }
    }

    /// Raw trees (not canonical: every shape the order must handle) from a small generator.
    fn random_tree(seed: &mut u64, depth: usize) -> Ex {
        let mut next = |n: u64| {
            *seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (*seed >> 33) % n
        };
        // Numbers whose keys are prefixes of each other (`#1e1`, `#1e10`), signs, fractions.
        const NUMS: [f64; 9] = [1.0, 10.0, 1e10, -1.0, 0.5, 1.5, 15.0, -0.0, 2.0];
        let syms = [
            Sym::Param(1),
            Sym::Param(12),
            Sym::Param(2),
            Sym::Input(0),
            Sym::InputDot(0),
            Sym::State(3),
            Sym::StateDot(3),
            Sym::Tear(1),
            Sym::Time,
            Sym::Output(0),
            Sym::Var(7),
        ];
        let funcs = [Func::Sin, Func::Sinh, Func::Atan, Func::Atan2, Func::Ln];
        let kind = if depth == 0 { next(2) } else { next(6) };
        match kind {
            0 => Ex::Num(NUMS[next(NUMS.len() as u64) as usize]),
            1 => Ex::S(syms[next(syms.len() as u64) as usize]),
            2 | 3 => {
                let n = next(3) as usize;
                let items = (0..n).map(|_| random_tree(seed, depth - 1)).collect();
                if kind == 2 {
                    Ex::Add(items)
                } else {
                    Ex::Mul(items)
                }
            }
            4 => Ex::Pow(
                Box::new(random_tree(seed, depth - 1)),
                Box::new(random_tree(seed, depth - 1)),
            ),
            _ => {
                let f = funcs[next(funcs.len() as u64) as usize];
                let n = 1 + next(2) as usize;
                Ex::Call(f, (0..n).map(|_| random_tree(seed, depth - 1)).collect())
            }
        }
    }

    #[test]
    fn order_is_that_of_the_keys() {
        let mut seed = 7;
        let trees: Vec<Ex> = (0..400).map(|i| random_tree(&mut seed, i % 4)).collect();
        for a in &trees {
            for b in &trees {
                assert_eq!(
                    key_cmp(a, b),
                    a.key().cmp(&b.key()),
                    "{} vs {}",
                    a.key(),
                    b.key()
                );
            }
        }
    }

    #[test]
    fn remembered_expansions_are_those_from_scratch() {
        // A chain as the resolver builds it: each value holds the previous one, multiplied by a sum; some levels
        // multiply out, the deeper ones are too large to.
        let n = add(vec![
            Ex::one(),
            mul(vec![Ex::Num(0.1), call(Func::Cos, vec![x()])]),
        ]);
        let mut expander = Expander::default();
        let mut value = y();
        for k in 0..12 {
            let term = mul(vec![Ex::Num(f64::from(k)), call(Func::Sin, vec![x()]), y()]);
            value = add(vec![term, mul(vec![n.clone(), value])]);
            let remembered = expander.expand(&value);
            assert_eq!(remembered, expand(&value), "level {k}");
            // Asked again, the memory answers with the same.
            assert_eq!(expander.expand(&value), remembered, "level {k}");
        }
    }

    #[test]
    fn affine_split() {
        let e = add(vec![mul(vec![x(), y()]), Ex::Num(3.0)]);
        let (a, b) = affine_in(&e, Sym::Param(0)).unwrap_or((Ex::zero(), Ex::zero()));
        assert_eq!(a, y());
        assert_eq!(b, Ex::Num(3.0));
        assert!(affine_in(&pow(x(), Ex::Num(2.0)), Sym::Param(0)).is_none());
        // sign(x) has a zero derivative but is not affine.
        let coulomb = add(vec![call(Func::Sign, vec![x()]), mul(vec![y(), x()])]);
        assert!(affine_in(&coulomb, Sym::Param(0)).is_none());
    }
}
