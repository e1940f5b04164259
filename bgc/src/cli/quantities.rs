//! The units of what the command line sets and prints: parameters, inputs, states, outputs.
//!
//! A number given on the command line is in the unit the file declares for what it sets (`--param L_a=2.5` on a
//! `[mH]` parameter is 2.5 mH), or in the unit written after it in brackets (`--param 'L_a=2.5 [H]'`), which must
//! measure the same dimension. Parameters are kept in SI inside the compiler; inputs, outputs and integrated flows
//! hold their values in their declared units; energy states are in the SI units of their domain.

use super::params::Assignment;
use bgc::equations::{Equations, StateKind};
use bgc::ir::Model;
use bgc::units::{Unit, cycles_and_angle, domain_units, parse_unit_text};
use petgraph::Direction;

/// What a name on the command line stands for, with the unit its values are written in.
#[derive(Clone, Debug, PartialEq)]
pub struct Declared {
    pub name: String,
    pub unit: Unit,
    /// The unit as the file writes it (`mH`), or the domain's SI unit for an energy state.
    pub text: String,
}

/// The parameters with their declared units.
pub fn params(model: &Model) -> Vec<Declared> {
    model
        .params
        .iter()
        .map(|p| Declared {
            name: p.name.clone(),
            unit: p.unit,
            text: p.unit_text.clone(),
        })
        .collect()
}

/// The inputs with their declared units.
pub fn inputs(model: &Model) -> Vec<Declared> {
    model
        .inputs
        .iter()
        .map(|i| Declared {
            name: i.name.clone(),
            unit: i.unit,
            text: i.unit_text.clone(),
        })
        .collect()
}

/// The outputs with their declared units.
pub fn outputs(model: &Model) -> Vec<Declared> {
    model
        .outputs
        .iter()
        .map(|o| Declared {
            name: o.name.clone(),
            unit: o.unit,
            text: o.unit_text.clone(),
        })
        .collect()
}

/// The states of `eqs` (all of them, energy states first) with their units: a momentum or displacement in its
/// domain's SI unit, a `var` in its declared unit.
pub fn states(model: &Model, eqs: &Equations) -> Vec<Declared> {
    eqs.states
        .iter()
        .map(|s| {
            let (unit, text) = match (s.kind, s.var.and_then(|v| model.vars.get(v))) {
                (StateKind::Integrated, Some(v)) => (v.unit, v.unit_text.clone()),
                _ => energy_unit(model, s.kind, s.node, s.port),
            };
            Declared {
                name: s.name.clone(),
                unit,
                text,
            }
        })
        .collect()
}

/// The SI unit of an energy state from the domain of the bond on its element (or field port).
fn energy_unit(
    model: &Model,
    kind: StateKind,
    node: Option<petgraph::graph::NodeIndex>,
    port: Option<u32>,
) -> (Unit, String) {
    let domain = node.and_then(|n| {
        let g = &model.graph;
        let ins = g
            .edges_directed(n, Direction::Incoming)
            .filter(|e| port.is_none_or(|p| e.weight().to_port == p));
        let outs = g
            .edges_directed(n, Direction::Outgoing)
            .filter(|e| port.is_none_or(|p| e.weight().from_port == p));
        ins.chain(outs).map(|e| e.weight().domain).next()
    });
    let Some(d) = domain else {
        return (Unit::ONE, "1".into());
    };
    let u = domain_units(d);
    let (dim, text) = match kind {
        StateKind::Momentum => (u.momentum, u.momentum_text),
        StateKind::Displacement | StateKind::Integrated => (u.displacement, u.displacement_text),
        StateKind::Velocity => (u.flow, u.flow_text),
    };
    (Unit::si(dim), text.to_string())
}

/// Splits `2.5 [mH]` into the number text and the unit text; a value without brackets has no unit.
pub fn split_unit(value: &str) -> Result<(&str, Option<&str>), String> {
    let Some(open) = value.find('[') else {
        return Ok((value.trim(), None));
    };
    let rest = &value[open + 1..];
    match rest
        .strip_suffix(']')
        .or_else(|| rest.trim_end().strip_suffix(']'))
    {
        Some(unit) if !unit.contains('[') && !unit.contains(']') => {
            Ok((value[..open].trim(), Some(unit.trim())))
        }
        _ => Err(format!(
            "`{value}`: write the unit once, in brackets at the end, as in `2.5 [mH]`"
        )),
    }
}

/// The factor that converts a value written in `written` (a unit text of the command line) to the unit of `d`;
/// 1 without a unit. A unit of another dimension is an error naming both.
pub fn factor_to_declared(what: &str, d: &Declared, written: Option<&str>) -> Result<f64, String> {
    let Some(text) = written else {
        return Ok(1.0);
    };
    let unit = parse_unit_text(text).map_err(|e| format!("{what} `{}`: {e}", d.name))?;
    if unit.dim != d.unit.dim {
        // The declared unit as written, and in SI where that reads differently (`[mH]` (kg m^2/s^2 A^2), but not
        // `[N s]` (N s)).
        let si = d.unit.dim.to_string();
        let declared = match si == d.text.trim() {
            true => format!("[{}]", d.text),
            false => format!("[{}] ({si})", d.text),
        };
        return Err(format!(
            "{what} `{}` is in {declared}, but [{text}] is in {}",
            d.name, unit.dim
        ));
    }
    let (cycles, angle) = cycles_and_angle(text);
    let (declared_cycles, declared_angle) = cycles_and_angle(&d.text);
    if (cycles && declared_angle) || (angle && declared_cycles) {
        let instead = match declared_cycles {
            true => format!("give the value in [{}], cycles per second", d.text),
            false => "give the value in an angle unit such as [rad/s] or [rpm] (one turn per second is 60 rpm, \
                      2π rad/s)"
                .to_string(),
        };
        return Err(format!(
            "{what} `{}` is in [{}] and the value in [{text}]: a hertz counts cycles of 2π rad, so converting between \
             hertz and an angle unit is ambiguous by 2π (bgc's hertz is 1/s, which is 1 rad/s, not one turn per \
             second); {instead}",
            d.name, d.text
        ));
    }
    Ok(unit.scale / d.unit.scale)
}

/// The value of `a` in the declared unit of `d`: a finite number, with an optional unit in brackets.
pub fn value_in_declared(what: &str, d: &Declared, a: &Assignment) -> Result<f64, String> {
    let (number, unit) = split_unit(&a.value).map_err(|e| format!("{what} `{}` = {e}", a.name))?;
    let v = match number.parse::<f64>() {
        Ok(v) if v.is_finite() => v,
        Ok(_) => {
            return Err(format!(
                "{what} `{}` = {}: the value must be finite",
                a.name, a.value
            ));
        }
        Err(_) => {
            return Err(format!(
                "{what} `{}` = `{}`: not a number{}",
                a.name,
                a.value,
                not_a_number_hint(number)
            ));
        }
    };
    Ok(v * factor_to_declared(what, d, unit)?)
}

/// What a value that is not a number probably meant, as a clause to append.
fn not_a_number_hint(text: &str) -> String {
    let number_end = text
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-')))
        .unwrap_or(text.len());
    let (number, rest) = text.split_at(number_end);
    if text.contains(',') && text.contains('=') {
        "; give each NAME=VALUE its own option, as in `--x0 a=1 --x0 b=2`".to_string()
    } else if !number.is_empty()
        && number.parse::<f64>().is_ok()
        && rest
            .trim_start()
            .starts_with(|c: char| c.is_alphabetic() || c == '°')
    {
        // `800N/m`, `3000rpm`: a number with its unit stuck to it.
        format!(
            "; a unit goes in brackets after the number: '{number} [{}]'",
            rest.trim()
        )
    } else if text.contains(['*', '/', '+', '(', '^']) {
        // `2*pi`, `1/3`: the value of an option is a number; only `--input` signals are expressions.
        "; a value is a number (with an optional unit in brackets, `0.5 [deg]`), not an expression: \
         write its value"
            .to_string()
    } else {
        String::new()
    }
}

/// The CSV header of `bgc simulate`: each column with its unit, `speed [rpm]`, `q_spring [m]`, `energy [J]`.
pub fn csv_header(model: &Model, eqs: &Equations, columns: &[String]) -> String {
    let mut units: Vec<(String, String)> = states(model, eqs)
        .into_iter()
        .chain(outputs(model))
        .map(|d| (d.name, d.text))
        .collect();
    for c in ["energy", "dissipated", "supplied"] {
        units.push((c.to_string(), "J".to_string()));
    }
    let mut out = String::from("t [s]");
    for (i, c) in columns.iter().enumerate() {
        out.push(',');
        out.push_str(c);
        if let Some((_, text)) = units.get(i).filter(|(n, _)| n == c) {
            out.push_str(&format!(" [{text}]"));
        }
    }
    out
}

/// A value in its declared unit, with its SI value when the unit has a factor: `2.5 [mH] = 0.0025 H`.
fn with_si(value_declared: f64, d: &Declared) -> String {
    if d.unit.scale == 1.0 {
        format!("{value_declared} [{}]", d.text)
    } else {
        format!(
            "{value_declared} [{}] = {} {}",
            d.text,
            value_declared * d.unit.scale,
            d.unit.dim
        )
    }
}

/// The effective parameter values (SI, in [`Equations::params`] order) as `--verbose` prints them, one a line:
/// the value in its declared unit, its SI value, and where it came from.
pub fn describe_params(
    model: &Model,
    eqs: &Equations,
    values: &[f64],
    given: &[Assignment],
) -> String {
    let mut out = String::from("parameters:\n");
    for (i, (d, v)) in params(model).iter().zip(values).enumerate() {
        let origin = if given.iter().any(|a| a.name == d.name) {
            "given"
        } else if eqs.derived.get(i).is_some_and(Option::is_some) {
            "derived"
        } else {
            "default"
        };
        out.push_str(&format!(
            "  {} = {} ({origin})\n",
            d.name,
            with_si(v / d.unit.scale, d)
        ));
    }
    out
}

/// Values in declared units, as `--verbose` prints them: `title:` and one line per name.
pub fn describe_values(
    title: &str,
    declared: &[Declared],
    values: &[f64],
    given: &[Assignment],
) -> String {
    let mut out = format!("{title}:\n");
    for (d, v) in declared.iter().zip(values) {
        let origin = if given.iter().any(|a| a.name == d.name) {
            "given"
        } else {
            "not given"
        };
        out.push_str(&format!("  {} = {} ({origin})\n", d.name, with_si(*v, d)));
    }
    out
}
