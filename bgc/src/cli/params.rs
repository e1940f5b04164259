//! `NAME=VALUE` arguments: parameter overrides, initial states, operating points, and the physical check of the
//! parameter values.

use bgc::ir::{Expr, Model, Relation};
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

/// A finite number, or a message naming the argument.
pub fn number(what: &str, a: &Assignment) -> Result<f64, String> {
    match a.value.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!(
            "{what} `{}` = {}: the value must be finite",
            a.name, a.value
        )),
        Err(_) => Err(format!("{what} `{}` = `{}`: not a number", a.name, a.value)),
    }
}

/// Sets `values[i]` for each assignment whose name is `names[i]`; an unknown name is an error listing the known.
pub fn assign(
    what: &str,
    names: &[String],
    values: &mut [f64],
    given: &[Assignment],
) -> Result<(), String> {
    for a in given {
        let Some(i) = names.iter().position(|n| *n == a.name) else {
            return Err(format!(
                "unknown {what} `{}`; the model has {}",
                a.name,
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ));
        };
        let v = number(what, a)?;
        if let Some(slot) = values.get_mut(i) {
            *slot = v;
        }
    }
    Ok(())
}

/// The parameter values: the defaults with the overrides, checked to be physical (see [`check_physical`]).
pub fn param_values(
    model: &Model,
    eqs: &bgc::equations::Equations,
    given: &[Assignment],
) -> Result<Vec<f64>, String> {
    let names: Vec<String> = model.params.iter().map(|p| p.name.clone()).collect();
    // The given values, marked by being set; the others follow from the defaults and the derived parameters.
    let mut values: Vec<f64> = vec![f64::NAN; names.len()];
    assign("parameter", &names, &mut values, given)?;
    let given_values: Vec<Option<f64>> =
        values.iter().map(|v| (!v.is_nan()).then_some(*v)).collect();
    let values = eqs.param_values(&given_values);
    check_physical(model, &values)?;
    Ok(values)
}

/// Checks the coefficients of the linear storages and resistors: an inertia or a compliance must be positive
/// (otherwise the stored energy is not positive definite), a resistance must not be negative (it would create
/// energy). Coefficients that depend on more than parameters are not checked here.
pub fn check_physical(model: &Model, params: &[f64]) -> Result<(), String> {
    for node in model.graph.node_weights() {
        let Relation::Linear(e) = &node.relation else {
            continue;
        };
        let Some(v) = eval_params(e, params) else {
            continue;
        };
        let (ok, rule) = match node.kind {
            ElementKind::I => (v > 0.0, "an inertia must be positive"),
            ElementKind::C => (v > 0.0, "a compliance must be positive"),
            ElementKind::R => (v >= 0.0, "a resistance must not be negative"),
            _ => continue,
        };
        if !ok || !v.is_finite() {
            return Err(format!(
                "{} `{}` = {v} with these parameter values: {rule} and finite",
                node.kind.keyword(),
                node.name
            ));
        }
    }
    Ok(())
}

/// The value of an expression of constants and parameters; `None` when it uses anything else.
fn eval_params(e: &Expr, params: &[f64]) -> Option<f64> {
    e.eval_const(&|i| params.get(i).copied())
}
