//! `NAME=VALUE` arguments: parameter overrides, initial states, operating points, and the physical check of the
//! parameter values.

use super::quantities::{self, Declared};
use bgc::equations::Equations;
use bgc::ir::{CoefficientFault, Expr, Model, Relation, coefficient_fault};
use bgc::simulate::input::Signal;
use bgc::syntax::ast::ElementKind;

/// A `NAME=VALUE` pair as given (the value is checked by the command, so that a bad number is an input error).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    pub name: String,
    pub value: String,
}

/// clap's parser for `NAME=VALUE`: a missing `=` or an empty side is a usage error (exit 2).
pub fn parse_assignment(s: &str) -> Result<Assignment, String> {
    match s.split_once('=') {
        Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => Ok(Assignment {
            name: n.trim().to_string(),
            value: v.trim().to_string(),
        }),
        _ => Err(format!("`{s}` is not of the form NAME=VALUE")),
    }
}

/// An error when a name is given twice: the last value would win silently.
pub fn reject_repeats(what: &str, option: &str, given: &[Assignment]) -> Result<(), String> {
    for (k, a) in given.iter().enumerate() {
        if let Some(b) = given[k + 1..].iter().find(|b| b.name == a.name) {
            return Err(format!(
                "{what} `{}` is given twice with {option} (`{}={}` and `{}={}`); give each name once",
                a.name, a.name, a.value, b.name, b.value
            ));
        }
    }
    Ok(())
}

/// For each assignment, its index among `declared` and its value in the declared unit (see
/// [`quantities::value_in_declared`]); an unknown name is an error listing the known, a repeated one an error.
pub fn assign(
    what: &str,
    option: &str,
    declared: &[Declared],
    given: &[Assignment],
) -> Result<Vec<(usize, f64)>, String> {
    reject_repeats(what, option, given)?;
    let mut out = Vec::with_capacity(given.len());
    for a in given {
        let Some(i) = declared.iter().position(|d| d.name == a.name) else {
            return Err(unknown_name(what, &a.name, &names(declared)));
        };
        out.push((i, quantities::value_in_declared(what, &declared[i], a)?));
    }
    Ok(out)
}

/// The names a message lists in full; a model of thousands of states lists the first ones and the count.
const LISTED_NAMES: usize = 24;

/// The error for a name that is none of `names` (what the model has of a kind): the nearest name when it is likely a
/// typo, and the names.
pub fn unknown_name(what: &str, name: &str, names: &[&str]) -> String {
    let suggestion = bgc::lower::closest(name, names.iter().copied())
        .map(|c| format!(" (did you mean `{c}`?)"))
        .unwrap_or_default();
    format!(
        "unknown {what} `{name}`{suggestion}; the model has {}",
        name_list(names)
    )
}

/// `names` for a message, comma-separated: "none" when empty, the first [`LISTED_NAMES`] and the count when more.
pub fn name_list<S: AsRef<str>>(names: &[S]) -> String {
    let first: Vec<&str> = names.iter().take(LISTED_NAMES).map(AsRef::as_ref).collect();
    match names.len() {
        0 => "none".to_string(),
        n if n <= LISTED_NAMES => first.join(", "),
        n => format!("{}, ... ({n} in all)", first.join(", ")),
    }
}

/// The names of `declared`.
pub fn names(declared: &[Declared]) -> Vec<&str> {
    declared.iter().map(|d| d.name.as_str()).collect()
}

/// The values of `declared` in their declared units: 0 where not given.
pub fn values_or_zero(
    what: &str,
    option: &str,
    declared: &[Declared],
    given: &[Assignment],
) -> Result<Vec<f64>, String> {
    let mut values = vec![0.0; declared.len()];
    for (i, v) in assign(what, option, declared, given)? {
        values[i] = v;
    }
    Ok(values)
}

/// The parameter values in SI: the defaults with the overrides (a bare number in the parameter's declared unit),
/// checked to be physical (see [`check_physical`]).
pub fn param_values(
    model: &Model,
    eqs: &bgc::equations::Equations,
    given: &[Assignment],
) -> Result<Vec<f64>, String> {
    let declared = quantities::params(model);
    // The given values; the others follow from the defaults and the derived parameters.
    let mut given_values: Vec<Option<f64>> = vec![None; declared.len()];
    for (i, v) in assign("parameter", "--param", &declared, given)? {
        given_values[i] = Some(v * declared[i].unit.scale);
    }
    let values = eqs.param_values(&given_values);
    check_physical(model, &values)?;
    check_divisors(model, eqs, &values)?;
    Ok(values)
}

/// Refuses a parameter value without a finite reciprocal (0) that the derived equations divide by. A resistance
/// of 0 is physical, a short, but in the causality the graph gives the resistor (conductance: `f = e/R`) the
/// equations divide by it; before, the run said only that the first value was not finite.
pub fn check_divisors(model: &Model, eqs: &Equations, values: &[f64]) -> Result<(), String> {
    for i in eqs.divisor_params() {
        let Some(&v) = values.get(i) else {
            continue;
        };
        if (1.0 / v).is_finite() {
            continue;
        }
        let name = eqs.params.get(i).map_or("?", |(n, _)| n.as_str());
        let users = elements_using(model, i, values);
        let used = match users.is_empty() {
            true => String::new(),
            false => format!(" (the coefficient of {})", name_list(&users)),
        };
        return Err(format!(
            "parameter `{name}` = {} with these parameter values: the derived equations divide by it{used}; \
             give it a value whose reciprocal is finite",
            bgc::diagnostic::number(v)
        ));
    }
    Ok(())
}

/// The elements (`R lower`) whose coefficient depends on parameter `i`.
fn elements_using(model: &Model, i: usize, values: &[f64]) -> Vec<String> {
    let all = |j: usize| values.get(j).copied();
    let without = |j: usize| if j == i { None } else { values.get(j).copied() };
    model
        .graph
        .node_weights()
        .filter(|n| match &n.relation {
            Relation::Linear(e) | Relation::Modulus(e) => {
                e.eval_const(&all).is_some() && e.eval_const(&without).is_none()
            }
            _ => false,
        })
        .map(|n| format!("{} `{}`", n.kind.keyword(), n.name))
        .collect()
}

/// Checks the coefficients of the linear storages and resistors: an inertia or a compliance must be positive
/// (otherwise the stored energy is not positive definite), a resistance must not be negative (it would create
/// energy); and, as BG0401 does for the defaults, the modulus of a TF or GY must not be zero (it would cut the
/// graph in two, and a model on either side would run as if the other did not exist). Coefficients that depend on
/// more than parameters are not checked here.
pub fn check_physical(model: &Model, params: &[f64]) -> Result<(), String> {
    for node in model.graph.node_weights() {
        let (Relation::Linear(e) | Relation::Modulus(e)) = &node.relation else {
            continue;
        };
        let Some(v) = eval_params(e, params) else {
            continue;
        };
        let Some(fault) = coefficient_fault(node.kind, v) else {
            continue;
        };
        let rule = match (fault, node.kind) {
            (CoefficientFault::NotFinite, _) => "the value must be finite",
            (CoefficientFault::NotPositive, ElementKind::I) => "an inertia must be positive",
            (CoefficientFault::NotPositive, _) => "a compliance must be positive",
            (CoefficientFault::Negative, _) => "a resistance must not be negative",
            (CoefficientFault::Zero, ElementKind::TF) => "a transformer ratio must not be zero",
            (CoefficientFault::Zero, _) => "a gyrator modulus must not be zero",
            (CoefficientFault::ReciprocalNotFinite, _) => {
                "the equations divide by it, and its reciprocal is not finite"
            }
        };
        return Err(format!(
            "{} `{}` = {} with these parameter values: {rule}",
            node.kind.keyword(),
            node.name,
            bgc::diagnostic::number(v)
        ));
    }
    Ok(())
}

/// The value of an expression of constants and parameters; `None` when it uses anything else.
fn eval_params(e: &Expr, params: &[f64]) -> Option<f64> {
    e.eval_const(&|i| params.get(i).copied())
}

/// The input signals of `bgc simulate` from `--input NAME=EXPR` (an expression of `t` in the input's declared unit,
/// or followed by a unit in brackets: `'theta=30*sin(t) [deg]'`), with the names of the inputs not given, which are
/// held at zero.
pub fn input_signals(
    model: &Model,
    given: &[Assignment],
) -> Result<(Vec<Signal>, Vec<String>), String> {
    reject_repeats("input", "--input", given)?;
    let declared = quantities::inputs(model);
    let mut signals: Vec<Option<Signal>> = vec![None; declared.len()];
    for a in given {
        let Some(i) = declared.iter().position(|d| d.name == a.name) else {
            return Err(unknown_name("input", &a.name, &names(&declared)));
        };
        let (text, unit) =
            quantities::split_unit(&a.value).map_err(|e| format!("input `{}` = {e}", a.name))?;
        let s = Signal::parse(text).map_err(|e| format!("input `{}` = `{text}`: {e}", a.name))?;
        let factor = quantities::factor_to_declared("input", &declared[i], unit)?;
        signals[i] = Some(if factor == 1.0 {
            s
        } else {
            Signal::Mul(Box::new(Signal::Num(factor)), Box::new(s))
        });
    }
    let zero: Vec<String> = declared
        .iter()
        .zip(&signals)
        .filter(|(_, s)| s.is_none())
        .map(|(d, _)| d.name.clone())
        .collect();
    let signals = signals
        .into_iter()
        .map(|s| s.unwrap_or(Signal::Num(0.0)))
        .collect();
    Ok((signals, zero))
}

/// The line `bgc simulate` prints on standard error when inputs are not given.
pub fn zero_inputs_warning(zero: &[String]) -> Option<String> {
    let list: Vec<String> = zero.iter().map(|n| format!("`{n}`")).collect();
    match list.len() {
        0 => None,
        1 => Some(format!(
            "warning: input {} is not given and is held at 0 (set it with --input NAME=EXPR)",
            list[0]
        )),
        _ => Some(format!(
            "warning: inputs {} are not given and are held at 0 (set them with --input NAME=EXPR)",
            list.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_name_lists_the_first_names_of_a_large_model_and_the_nearest() {
        let many: Vec<String> = (1..=1000).map(|i| format!("p_mass{i}")).collect();
        let names: Vec<&str> = many.iter().map(String::as_str).collect();
        let err = unknown_name("state", "p_mas7", &names);
        assert!(err.starts_with(
            "unknown state `p_mas7` (did you mean `p_mass7`?); the model has p_mass1, p_mass2,"
        ));
        assert!(err.ends_with("p_mass24, ... (1000 in all)"), "{err}");
        assert_eq!(
            unknown_name("input", "u", &[]),
            "unknown input `u`; the model has none"
        );
        // Every list of a model's names in a message is bounded the same way.
        assert_eq!(name_list(&many[..24]).matches(", ").count(), 23);
        assert!(name_list(&many[..25]).ends_with("p_mass24, ... (25 in all)"));
        assert_eq!(
            unknown_name("parameter", "q", &["m", "k", "d"]),
            "unknown parameter `q`; the model has m, k, d"
        );
    }
}
