//! Calls of elementary functions bound once at the top of a body: a `libm` call whose arguments are computed
//! from states, inputs, parameters, time, the loops' tears and literals alone (`libm::cos(theta)`,
//! `libm::cos(q_1 - q_2)`, `libm::exp((u - r*loop_f_d)/v_t)` in a loop's residual and slope) is
//! computed once (`let cos_theta = ...;`, calls nested in its arguments first) and its name replaces it in the
//! statements. The same call on the same values gives the same bits, so nothing changes
//! but the number of calls and the length of the lines.

use crate::symbolic::RustCode;
use std::collections::{BTreeMap, BTreeSet};

/// Whether `code` is a value known from the start of the body: a name of `early` or a literal, or arithmetic
/// and `libm` calls on such values.
fn is_early_value(code: &RustCode, early: &BTreeSet<String>) -> bool {
    match code {
        RustCode::Atom(s) => early.contains(s) || s.parse::<f64>().is_ok(),
        RustCode::Neg(inner) | RustCode::Paren(inner) => is_early_value(inner, early),
        RustCode::Chain(first, rest) => {
            is_early_value(first, early) && rest.iter().all(|(_, o)| is_early_value(o, early))
        }
        RustCode::Call(..) => is_early_call(code, early),
    }
}

/// Whether `code` is a call of a `libm` function on values known from the start of the body
/// (`libm::cos(q_1 - q_2 + q_3)` as well as `libm::cos(theta)`).
fn is_early_call(code: &RustCode, early: &BTreeSet<String>) -> bool {
    match code {
        RustCode::Call(callee, args) => {
            callee.starts_with("libm::") && args.iter().all(|a| is_early_value(a, early))
        }
        _ => false,
    }
}

/// How many calls are nested in `code`, itself included: a call is bound after those in its arguments.
pub(super) fn call_depth(code: &RustCode) -> usize {
    match code {
        RustCode::Atom(_) => 0,
        RustCode::Neg(inner) | RustCode::Paren(inner) => call_depth(inner),
        RustCode::Chain(first, rest) => rest
            .iter()
            .map(|(_, o)| call_depth(o))
            .fold(call_depth(first), usize::max),
        RustCode::Call(_, args) => 1 + args.iter().map(call_depth).max().unwrap_or(0),
    }
}

/// Collects the calls of `code` that [`is_early_call`] accepts, by text, with the early calls nested in their
/// arguments.
pub(super) fn early_calls(
    code: &RustCode,
    early: &BTreeSet<String>,
    out: &mut BTreeMap<String, RustCode>,
) {
    if is_early_call(code, early) {
        out.insert(code.to_string(), code.clone());
    }
    match code {
        RustCode::Atom(_) => {}
        RustCode::Neg(inner) | RustCode::Paren(inner) => early_calls(inner, early, out),
        RustCode::Chain(first, rest) => {
            early_calls(first, early, out);
            for (_, o) in rest {
                early_calls(o, early, out);
            }
        }
        RustCode::Call(_, args) => args.iter().for_each(|a| early_calls(a, early, out)),
    }
}

/// `code` with the calls bound in `calls` replaced by their names.
pub(super) fn with_bound_calls(code: RustCode, calls: &BTreeMap<String, String>) -> RustCode {
    if let RustCode::Call(..) = code
        && let Some(name) = calls.get(&code.to_string())
    {
        return RustCode::Atom(name.clone());
    }
    match code {
        RustCode::Neg(inner) => RustCode::Neg(Box::new(with_bound_calls(*inner, calls))),
        RustCode::Paren(inner) => RustCode::Paren(Box::new(with_bound_calls(*inner, calls))),
        RustCode::Chain(first, rest) => RustCode::Chain(
            Box::new(with_bound_calls(*first, calls)),
            rest.into_iter()
                .map(|(op, o)| (op, with_bound_calls(o, calls)))
                .collect(),
        ),
        RustCode::Call(callee, args) => RustCode::Call(
            callee,
            args.into_iter()
                .map(|a| with_bound_calls(a, calls))
                .collect(),
        ),
        atom => atom,
    }
}

/// A local name for the value of `call`: the function's name and the names and literals of its arguments
/// (`cos_theta`, `sqrt_k`, `cos_q_1_q_2_q_3` for `libm::cos(q_1 - q_2 + q_3)`). A literal is named by its first
/// four significant digits (`cos_6_283_t` for `libm::cos(6.283185307179586 * t)`): its full digits made names of
/// 30 characters, and past [`MAX_NAME`] a later word was dropped, so that `cos(theta + 0.35000000000000003)` was
/// bound as `cos_theta`.
pub(super) fn call_name(call: &RustCode) -> String {
    fn words(code: &RustCode, out: &mut Vec<String>) {
        match code {
            RustCode::Atom(s) => out.push(short_number(s).unwrap_or_else(|| {
                s.trim_start_matches("p.")
                    .trim_start_matches("c.")
                    .to_string()
            })),
            RustCode::Neg(inner) | RustCode::Paren(inner) => words(inner, out),
            RustCode::Chain(first, rest) => {
                words(first, out);
                rest.iter().for_each(|(_, o)| words(o, out));
            }
            RustCode::Call(callee, args) => {
                out.push(callee.trim_start_matches("libm::").to_string());
                args.iter().for_each(|a| words(a, out));
            }
        }
    }
    let mut parts = Vec::new();
    words(call, &mut parts);
    // A name of a few words: the binding is right above its uses, and the name only has to be unique there.
    let mut name = String::new();
    for part in parts {
        if !name.is_empty() && name.len() + part.len() > MAX_NAME {
            break;
        }
        if !name.is_empty() {
            name.push('_');
        }
        name.push_str(&part);
    }
    name
}

/// The longest name [`call_name`] builds from several words.
const MAX_NAME: usize = 24;

/// A numeric literal written with at most four significant digits, positionally from 0.001 to 99,999 (`6.283`,
/// `0.35`, `1`) and in exponent form beyond (`1e-12`); `None` for anything else.
fn short_number(text: &str) -> Option<String> {
    let value: f64 = text.parse().ok().filter(|v: &f64| v.is_finite())?;
    let scientific = format!("{value:.3e}");
    let (mantissa, exponent) = scientific.split_once('e')?;
    let exponent: i32 = exponent.parse().ok()?;
    if (-3..=4).contains(&exponent) {
        let rounded: f64 = scientific.parse().ok()?;
        Some(format!("{rounded}"))
    } else {
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        Some(format!("{mantissa}e{exponent}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn call(callee: &str, args: Vec<RustCode>) -> RustCode {
        RustCode::Call(callee.to_string(), args)
    }

    fn atom(s: &str) -> RustCode {
        RustCode::Atom(s.to_string())
    }

    #[test]
    fn literals_are_named_by_four_significant_digits() {
        let cases = [
            ("6.283185307179586", "6.283"),
            ("12.566370614359172", "12.57"),
            ("0.35000000000000003", "0.35"),
            ("1.0", "1"),
            ("1234.5678", "1235"),
            ("0.001", "0.001"),
            ("1e-12", "1e-12"),
            ("-2.5e7", "-2.5e7"),
        ];
        for (text, short) in cases {
            assert_eq!(short_number(text).as_deref(), Some(short), "{text}");
        }
        assert_eq!(short_number("theta"), None);
        assert_eq!(short_number("inf"), None);
    }

    #[test]
    fn a_call_with_a_long_literal_keeps_every_word_of_its_name() {
        let plus = |a: RustCode, b: RustCode| {
            RustCode::Chain(Box::new(a), vec![(crate::symbolic::RustOp::Add, b)])
        };
        let shifted = call(
            "libm::cos",
            vec![plus(atom("theta"), atom("0.35000000000000003"))],
        );
        assert_eq!(call_name(&shifted), "cos_theta_0.35");
        let scaled = call(
            "libm::sin",
            vec![RustCode::Chain(
                Box::new(atom("6.283185307179586")),
                vec![(crate::symbolic::RustOp::Mul, atom("t"))],
            )],
        );
        assert_eq!(call_name(&scaled), "sin_6.283_t");
        assert_eq!(call_name(&call("libm::sqrt", vec![atom("p.k")])), "sqrt_k");
    }
}
