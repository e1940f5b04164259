//! The variables of an FMU, in the value-reference layout the binary uses (`template/plant.rs`): 0 is the time,
//! then the free parameters, the inputs, the outputs, the states and the state derivatives.

use crate::codegen::CompiledModel;
use crate::units::{Dim, Unit};

/// What a variable is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Time,
    Parameter,
    Input,
    Output,
    State,
    /// The derivative of the state with this index (0-based, among the states).
    Derivative(usize),
}

/// One scalar variable.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    pub name: String,
    pub role: Role,
    /// The value reference (its position in the list).
    pub vr: u32,
    pub start: Option<f64>,
    /// The unit's name in `UnitDefinitions`, with its dimension and factor to SI.
    pub unit: Option<(String, Dim, f64)>,
    pub description: Option<String>,
}

/// Every variable of `m`, in value-reference order.
pub fn variables(m: &CompiledModel) -> Vec<Variable> {
    let eqs = &m.equations;
    let mut out: Vec<Variable> = Vec::new();
    let mut push = |name: String, role, start, unit, description| {
        let vr = out.len() as u32;
        out.push(Variable {
            name,
            role,
            vr,
            start,
            unit,
            description,
        });
    };
    push(
        "time".into(),
        Role::Time,
        None,
        Some(("s".into(), Dim::new(0, 0, 1, 0, 0, 0, 0), 1.0)),
        None,
    );
    for (k, (name, value)) in eqs.params.iter().enumerate() {
        if eqs.derived.get(k).is_some_and(Option::is_some) {
            continue;
        }
        let decl = m.model.params.iter().find(|p| &p.name == name);
        // The binary holds parameters in SI units: the declared unit when it is SI, else the SI form.
        let unit = decl.and_then(|p| si_unit(&p.unit_text, p.unit));
        let description = decl.and_then(|p| p.description.clone());
        push(
            name.clone(),
            Role::Parameter,
            Some(*value),
            unit,
            description,
        );
    }
    for name in &eqs.inputs {
        let decl = m.model.inputs.iter().find(|i| &i.name == name);
        let unit = decl.and_then(|i| declared_unit(&i.unit_text, i.unit));
        let description = decl.and_then(|i| i.description.clone());
        push(name.clone(), Role::Input, Some(0.0), unit, description);
    }
    for o in &eqs.outputs {
        let decl = m.model.outputs.iter().find(|d| d.name == o.name);
        let unit = decl.and_then(|d| declared_unit(&d.unit_text, d.unit));
        let description = decl.and_then(|d| d.description.clone());
        push(o.name.clone(), Role::Output, None, unit, description);
    }
    for s in &eqs.states {
        let unit = m
            .model
            .vars
            .iter()
            .find(|v| v.name == s.name)
            .and_then(|v| declared_unit(&v.unit_text, v.unit));
        push(s.name.clone(), Role::State, Some(0.0), unit, None);
    }
    for (k, s) in eqs.states.iter().enumerate() {
        push(
            format!("der({})", s.name),
            Role::Derivative(k),
            None,
            None,
            None,
        );
    }
    out
}

/// A declared unit the values are in (inputs, outputs, integrated flows): its text, dimension and scale; none
/// for a plain number.
fn declared_unit(text: &str, unit: Unit) -> Option<(String, Dim, f64)> {
    let text = text.trim();
    if text.is_empty() || (text == "1" && unit.dim.is_dimensionless() && unit.scale == 1.0) {
        return None;
    }
    Some((text.to_string(), unit.dim, unit.scale))
}

/// The unit of a value held in SI units: the declared one when its scale is 1, else the SI base form.
fn si_unit(text: &str, unit: Unit) -> Option<(String, Dim, f64)> {
    if unit.scale == 1.0 {
        return declared_unit(text, unit);
    }
    if unit.dim.is_dimensionless() {
        return None;
    }
    Some((base_form(unit.dim), unit.dim, 1.0))
}

/// `kg.m2.s-2`: the SI base units with their exponents, in the notation of Modelica's unit strings.
pub fn base_form(dim: Dim) -> String {
    const SYMBOLS: [&str; 7] = ["m", "kg", "s", "A", "K", "mol", "cd"];
    let parts: Vec<String> = SYMBOLS
        .iter()
        .zip(dim.0)
        .filter(|(_, e)| *e != 0)
        .map(|(s, e)| {
            if e == 1 {
                s.to_string()
            } else {
                format!("{s}{e}")
            }
        })
        .collect();
    if parts.is_empty() {
        "1".into()
    } else {
        parts.join(".")
    }
}
