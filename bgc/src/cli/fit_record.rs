//! The record of `bgc fit` and `bgc simulate --data`: a CSV file whose header may carry units, as `bgc simulate` writes it.
//!
//! A header cell is a name (`x`) or a name and a unit in brackets (`x [mm]`, `t [s]`), in quotes or not, and the
//! cells are separated as the runtime's reader separates them ([`Dialect`]). A column in a unit is
//! converted to the unit the model declares for that input or output (to seconds for `t`), as `--param` converts
//! a value in brackets; a unit of another dimension is an error naming both. The runtime's reader then sees bare
//! names, and says what is wrong with the columns themselves. A column that `bgc simulate` writes but a fit does
//! not read (a state, an energy column) gets an error that says so.

use super::quantities::{self, Declared, factor_to_declared, split_unit};
use bgc::equations::Equations;
use bgc::ir::Model;
use bgc::units::parse_unit_text;
use bgc_runtime::fit::csv::Dialect;
use bgc_runtime::fit::{Record, RecordError};
use std::collections::HashMap;

/// The names of the time column: `t`, as `bgc simulate` writes it, or `time`, as FMPy and Modelica tools do.
const TIME_COLUMNS: [&str; 2] = ["t", "time"];

/// The columns `bgc simulate` writes after the states and outputs.
const ENERGY_COLUMNS: [&str; 3] = ["energy", "dissipated", "supplied"];

/// Reads the record `text` of a fit, with each column in a unit converted to the model's unit.
pub fn read(model: &Model, eqs: &Equations, text: &str) -> Result<Record, String> {
    let inputs: Vec<&str> = eqs.inputs.iter().map(String::as_str).collect();
    read_with(model, eqs, text, &inputs, Record::from_csv)
}

/// Reads a record whose inputs are replayed in a simulation: each input but those in `elsewhere` (given another
/// way, and then not in the record), and measured outputs if it has any.
pub fn read_inputs(
    model: &Model,
    eqs: &Equations,
    text: &str,
    elsewhere: &[&str],
) -> Result<Record, String> {
    let inputs: Vec<&str> = eqs
        .inputs
        .iter()
        .map(String::as_str)
        .filter(|n| !elsewhere.contains(n))
        .collect();
    read_with(model, eqs, text, &inputs, Record::inputs_from_csv)
}

type Reader = fn(&str, &[&str], &[&str]) -> Result<Record, RecordError>;

/// Reads the record with the columns of `inputs`, converting units, by `reader`.
fn read_with(
    model: &Model,
    eqs: &Equations,
    text: &str,
    inputs: &[&str],
    reader: Reader,
) -> Result<Record, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Blank lines before the header are kept, so that the reader's line numbers stay those of the file.
    let header_start = text
        .split_inclusive('\n')
        .take_while(|l| l.trim().is_empty())
        .map(str::len)
        .sum::<usize>();
    let (blank, rest) = text.split_at(header_start);
    let (header, body) = rest.split_once('\n').unwrap_or((rest, ""));
    let declared = declared(model);
    let mut names = Vec::new();
    let mut factors = Vec::new();
    let dialect = Dialect::of_header(header);
    for cell in dialect.cells(header.trim_end_matches('\r')) {
        let (name, unit) = split_unit(&cell).map_err(|e| format!("the record's header: {e}"))?;
        factors.push(match declared.get(name) {
            Some(d) => factor_to_declared("the record's column", d, unit)?,
            None => 1.0,
        });
        names.push(name.to_string());
    }
    if let Some((c, name)) = names
        .iter()
        .enumerate()
        .find(|(_, n)| eqs.inputs.contains(n) && !inputs.contains(&n.as_str()))
    {
        return Err(format!(
            "input `{name}` is given on the command line and in column {} of the record: give it once",
            c + 1
        ));
    }
    let outputs: Vec<&str> = eqs.outputs.iter().map(|o| o.name.as_str()).collect();
    let bare = format!(
        "{blank}{}\n{body}",
        names.join(&dialect.delimiter.to_string())
    );
    let mut record = reader(&bare, inputs, &outputs).map_err(|e| match &e {
        RecordError::UnknownColumn { name, .. } => e.to_string() + &not_read(model, eqs, name),
        _ => e.to_string(),
    })?;
    convert(&mut record, &names, &factors, inputs, &outputs);
    Ok(record)
}

/// The quantities a column may hold, by name: the time, the inputs and the outputs.
fn declared(model: &Model) -> HashMap<String, Declared> {
    let mut all = quantities::inputs(model);
    all.extend(quantities::outputs(model));
    if let Ok(unit) = parse_unit_text("s") {
        for name in TIME_COLUMNS {
            if !all.iter().any(|d| d.name == name) {
                all.push(Declared {
                    name: name.into(),
                    unit,
                    text: "s".into(),
                });
            }
        }
    }
    all.into_iter().map(|d| (d.name.clone(), d)).collect()
}

/// Multiplies each column by its factor to the model's unit.
fn convert(
    record: &mut Record,
    names: &[String],
    factors: &[f64],
    inputs: &[&str],
    outputs: &[&str],
) {
    let factor = |name: &str| {
        names
            .iter()
            .position(|n| n == name)
            .and_then(|c| factors.get(c))
            .copied()
            .unwrap_or(1.0)
    };
    let t = Record::time_column(names, inputs, outputs)
        .and_then(|c| factors.get(c))
        .copied()
        .unwrap_or(1.0);
    record.times.iter_mut().for_each(|v| *v *= t);
    let per_input: Vec<f64> = inputs.iter().map(|n| factor(n)).collect();
    for row in &mut record.inputs {
        row.iter_mut().zip(&per_input).for_each(|(v, f)| *v *= f);
    }
    let per_column: Vec<f64> = record
        .outputs
        .iter()
        .map(|&o| outputs.get(o).map_or(1.0, |n| factor(n)))
        .collect();
    for row in &mut record.measured {
        row.iter_mut().zip(&per_column).for_each(|(v, f)| *v *= f);
    }
}

/// A sentence for a column that `bgc simulate` writes and a record does not hold (a state, an energy), or nothing.
fn not_read(model: &Model, eqs: &Equations, name: &str) -> String {
    let simulated = ENERGY_COLUMNS.contains(&name)
        || quantities::states(model, eqs)
            .iter()
            .any(|s| s.name == name);
    if !simulated {
        return String::new();
    }
    format!(
        "; `{name}` is a column of `bgc simulate` (a state or an energy), which a record does not hold: a record holds \
         `t`, the inputs and measured outputs (declare an `output` for what was measured)"
    )
}
