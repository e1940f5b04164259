//! Time derivatives of input signals.
//!
//! A source that drives a storage in derivative causality delivers the power `e·f` with `e = J·du/dt` (a flow
//! source imposing an inertia's velocity), so the `supplied` column needs `du/dt`. Inputs are expressions of `t`
//! ([`Signal`]); their derivative is taken symbolically on the expression tree, once, by the usual rules (sum,
//! product, quotient and chain rules), with:
//!
//! ```text
//! d/dt step(a)   = 0                          (away from t = a: the jump itself is an impulse, see below)
//! d/dt ramp(a)   = step(a) · (1 − a')         (ramp(a) = max(t − a, 0))
//! d/dt abs(a)    = sign(a) · a'
//! d/dt sign(a)   = 0
//! d/dt min(a, b) = (a' + b')/2 − sign(a − b)·(a' − b')/2    (min = (a + b)/2 − |a − b|/2; max with +)
//! d/dt a^b       = b·a^(b−1)·a'  for b free of t,  a^b·(b'·ln a + b·a'/a) otherwise
//! ```
//!
//! At a kink (`ramp`, `abs`, `min`, `max`) the derivative is one of its one-sided values. A jump (`step`) has no
//! derivative: the energy it moves into a storage in derivative causality is accounted by the integrator as the
//! jump of the stored energy at the breakpoint ([`super::integrate`]).

use super::input::{Signal, SignalFunc};

fn num(v: f64) -> Signal {
    Signal::Num(v)
}

fn is_num(s: &Signal, v: f64) -> bool {
    matches!(s, Signal::Num(x) if *x == v)
}

fn add(a: Signal, b: Signal) -> Signal {
    match (&a, &b) {
        (Signal::Num(x), Signal::Num(y)) => num(x + y),
        _ if is_num(&a, 0.0) => b,
        _ if is_num(&b, 0.0) => a,
        _ => Signal::Add(Box::new(a), Box::new(b)),
    }
}

fn sub(a: Signal, b: Signal) -> Signal {
    match (&a, &b) {
        (Signal::Num(x), Signal::Num(y)) => num(x - y),
        _ if is_num(&b, 0.0) => a,
        _ if is_num(&a, 0.0) => neg(b),
        _ => Signal::Sub(Box::new(a), Box::new(b)),
    }
}

fn neg(a: Signal) -> Signal {
    match a {
        Signal::Num(x) => num(-x),
        Signal::Neg(inner) => *inner,
        other => Signal::Neg(Box::new(other)),
    }
}

fn mul(a: Signal, b: Signal) -> Signal {
    match (&a, &b) {
        (Signal::Num(x), Signal::Num(y)) => num(x * y),
        _ if is_num(&a, 0.0) || is_num(&b, 0.0) => num(0.0),
        _ if is_num(&a, 1.0) => b,
        _ if is_num(&b, 1.0) => a,
        _ => Signal::Mul(Box::new(a), Box::new(b)),
    }
}

fn div(a: Signal, b: Signal) -> Signal {
    match (&a, &b) {
        _ if is_num(&a, 0.0) => num(0.0),
        _ if is_num(&b, 1.0) => a,
        _ => Signal::Div(Box::new(a), Box::new(b)),
    }
}

fn call(f: SignalFunc, args: Vec<Signal>) -> Signal {
    Signal::Call(f, args)
}

impl Signal {
    /// `d/dt` of the signal, as a signal (see the module documentation for the rules at jumps and kinks).
    pub fn derivative(&self) -> Signal {
        if !self.uses_time() {
            return num(0.0);
        }
        match self {
            Signal::Num(_) => num(0.0),
            Signal::Time => num(1.0),
            Signal::Samples(s) => s.derivative().map_or(num(0.0), Signal::Samples),
            Signal::Neg(a) => neg(a.derivative()),
            Signal::Add(a, b) => add(a.derivative(), b.derivative()),
            Signal::Sub(a, b) => sub(a.derivative(), b.derivative()),
            Signal::Mul(a, b) => add(
                mul(a.derivative(), (**b).clone()),
                mul((**a).clone(), b.derivative()),
            ),
            Signal::Div(a, b) => {
                // (a' b − a b') / b²
                let top = sub(
                    mul(a.derivative(), (**b).clone()),
                    mul((**a).clone(), b.derivative()),
                );
                div(top, mul((**b).clone(), (**b).clone()))
            }
            Signal::Pow(a, b) => {
                let (a0, b0) = ((**a).clone(), (**b).clone());
                if b.uses_time() {
                    // a^b (b' ln a + b a'/a)
                    let inner = add(
                        mul(b.derivative(), call(SignalFunc::Ln, vec![a0.clone()])),
                        div(mul(b0, a.derivative()), a0),
                    );
                    mul(self.clone(), inner)
                } else {
                    // b a^(b−1) a'
                    let lowered = Signal::Pow(Box::new(a0), Box::new(sub(b0.clone(), num(1.0))));
                    mul(mul(b0, lowered), a.derivative())
                }
            }
            Signal::Call(f, args) => call_derivative(*f, args),
        }
    }
}

fn call_derivative(f: SignalFunc, args: &[Signal]) -> Signal {
    let a = args.first().cloned().unwrap_or(num(f64::NAN));
    let b = args.get(1).cloned().unwrap_or(num(f64::NAN));
    let da = a.derivative();
    let chain = |outer: Signal| mul(outer, da.clone());
    match f {
        SignalFunc::Step | SignalFunc::Sign => num(0.0),
        SignalFunc::Ramp => mul(call(SignalFunc::Step, vec![a]), sub(num(1.0), da)),
        SignalFunc::Sin => chain(call(SignalFunc::Cos, vec![a])),
        SignalFunc::Cos => chain(neg(call(SignalFunc::Sin, vec![a]))),
        SignalFunc::Tan => {
            let c = call(SignalFunc::Cos, vec![a]);
            div(da, mul(c.clone(), c))
        }
        SignalFunc::Exp => chain(call(SignalFunc::Exp, vec![a])),
        SignalFunc::Ln => div(da, a),
        SignalFunc::Sqrt => div(da, mul(num(2.0), call(SignalFunc::Sqrt, vec![a]))),
        SignalFunc::Abs => chain(call(SignalFunc::Sign, vec![a])),
        SignalFunc::Min | SignalFunc::Max => {
            let db = b.derivative();
            let mean = div(add(da.clone(), db.clone()), num(2.0));
            let half_gap = div(
                mul(call(SignalFunc::Sign, vec![sub(a, b)]), sub(da, db)),
                num(2.0),
            );
            if f == SignalFunc::Min {
                sub(mean, half_gap)
            } else {
                add(mean, half_gap)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d_at(text: &str, t: f64) -> f64 {
        Signal::parse(text).map_or(f64::NAN, |s| s.derivative().eval(t))
    }

    #[test]
    fn derivatives_match_central_differences() {
        // Smooth signals, away from every kink: the symbolic derivative against (s(t+h) − s(t−h))/2h, whose error
        // is O(h²) ≈ 1e-10 relative for h = 1e-5.
        let cases = [
            "0.5*sin(3*t) + 2",
            "t^3 - 4*t/(1 + t^2)",
            "exp(-2*t)*cos(5*t)",
            "sqrt(1 + t) * ln(2 + t)",
            "tan(t/2)",
            "(1 + t)^(t/3)",
            "2^t",
            "abs(t - 1) + min(t, 2*t - 1) + max(sin(t), 0.2)",
            "ramp(0.3) * 2 + 3*step(0.1)",
            "-(t^2)/-(1 + t)",
        ];
        let h = 1e-5;
        for text in cases {
            let s = Signal::parse(text).unwrap_or(Signal::Num(f64::NAN));
            let ds = s.derivative();
            for t in [0.45, 0.7, 1.3, 2.2] {
                let fd = (s.eval(t + h) - s.eval(t - h)) / (2.0 * h);
                let exact = ds.eval(t);
                assert!(
                    (fd - exact).abs() <= 1e-8 * exact.abs().max(1.0),
                    "{text} at t = {t}: {exact} vs finite difference {fd}"
                );
            }
        }
    }

    #[test]
    fn steps_and_constants_have_no_derivative() {
        assert_eq!(d_at("3*step(1)", 2.0), 0.0);
        assert_eq!(d_at("3*step(1)", 0.5), 0.0);
        assert_eq!(d_at("2 + pi", 0.5), 0.0);
        assert_eq!(d_at("ramp(1)", 0.5), 0.0);
        assert_eq!(d_at("ramp(1)", 1.5), 1.0);
        // d/dt ramp(t/2) = step(t/2)·(1 − 1/2): the breakpoint moves with t.
        assert_eq!(d_at("ramp(t/2)", 1.0), 0.5);
        assert_eq!(d_at("7*t", 3.0), 7.0);
    }
}
