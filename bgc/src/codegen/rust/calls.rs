//! Calls of elementary functions bound once at the top of a body: a `libm` call whose arguments are states,
//! inputs, parameters, time or literals (`libm::cos(theta)`) is computed once (`let cos_theta = ...;`) and its
//! name replaces it in the statements. The same call on the same values gives the same bits, so nothing changes
//! but the number of calls and the length of the lines.

use crate::symbolic::RustCode;
use std::collections::{BTreeMap, BTreeSet};

/// Whether `code` is a call of a `libm` function on names and literals available from the start of the body.
fn is_early_call(code: &RustCode, early: &BTreeSet<String>) -> bool {
    match code {
        RustCode::Call(callee, args) => {
            callee.starts_with("libm::")
                && args.iter().all(|a| match a {
                    RustCode::Atom(s) => early.contains(s) || s.parse::<f64>().is_ok(),
                    _ => false,
                })
        }
        _ => false,
    }
}

/// Collects the calls of `code` that [`is_early_call`] accepts, by text.
pub(super) fn early_calls(
    code: &RustCode,
    early: &BTreeSet<String>,
    out: &mut BTreeMap<String, RustCode>,
) {
    if is_early_call(code, early) {
        out.insert(code.to_string(), code.clone());
        return;
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

/// A local name for the value of `call`: the function's name and its arguments' (`cos_theta`, `sqrt_k`).
pub(super) fn call_name(call: &RustCode) -> String {
    match call {
        RustCode::Call(callee, args) => {
            let mut name = callee.trim_start_matches("libm::").to_string();
            for a in args {
                name.push('_');
                name.push_str(a.to_string().trim_start_matches("p."));
            }
            name
        }
        other => other.to_string(),
    }
}
