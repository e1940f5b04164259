//! A measured record: sample times, the inputs applied and the outputs measured, read from CSV and checked.
//!
//! The CSV has a header with a `t` column (or `time`), one column per model input and one per measured output, by name. An
//! empty output cell is a missing sample; every other cell must be a finite number. Inputs are held between
//! samples ([`Interp::Zoh`], the way a logger records a digitally commanded signal) or interpolated linearly.

use std::fmt::Write as _;

/// How the inputs are reconstructed between samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interp {
    /// Each sample is held until the next (zero-order hold).
    #[default]
    Zoh,
    /// Straight lines between samples.
    Linear,
}

/// A checked record: strictly increasing finite times, finite inputs, measured outputs with `NaN` for missing.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    pub times: Vec<f64>,
    /// Per sample, the model's inputs in model order.
    pub inputs: Vec<Vec<f64>>,
    /// The model output index of each measured column.
    pub outputs: Vec<usize>,
    /// Per sample, one value per measured column (`NaN`: not measured at that sample).
    pub measured: Vec<Vec<f64>>,
}

/// Why a record was refused; rows are numbered as lines of the file (the header is line 1).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RecordError {
    #[error(
        "the record has too few samples ({samples}): it needs a header line and at least two samples"
    )]
    TooShort { samples: usize },
    #[error("the record has no `t` (or `time`) column (the header is `{header}`)")]
    NoTime { header: String },
    #[error("the record has no column for the model input `{name}`; inputs must all be given")]
    MissingInput { name: String },
    #[error("the record has no column for any model output (the model's outputs: {known})")]
    NoOutputs { known: String },
    #[error(
        "column {column} `{name}` is no input or output of the model (inputs: {inputs}; outputs: {outputs})"
    )]
    UnknownColumn {
        column: usize,
        name: String,
        inputs: String,
        outputs: String,
    },
    #[error(
        "column {column} has no name in the header: name it `t`, an input or a measured output"
    )]
    UnnamedColumn { column: usize },
    #[error("column `{name}` appears twice (columns {first} and {second})")]
    DuplicateColumn {
        name: String,
        first: usize,
        second: usize,
    },
    #[error("line {line} has {got} cells, the header has {expected}")]
    Ragged {
        line: usize,
        got: usize,
        expected: usize,
    },
    #[error("line {line}, column `{column}`: `{text}` is not a number")]
    NotANumber {
        line: usize,
        column: String,
        text: String,
    },
    #[error(
        "line {line}, column `{column}` is {what}: a missing sample is an empty cell, and only outputs may be missing"
    )]
    NonFinite {
        line: usize,
        column: String,
        what: &'static str,
    },
    #[error(
        "line {line}: time {t:?} does not follow the previous time {previous:?}; times must be strictly increasing"
    )]
    Unsorted { line: usize, t: f64, previous: f64 },
    #[error("the record has no measured sample: every output cell is empty")]
    NothingMeasured,
    #[error("the record's sizes do not agree: {what}")]
    Shape { what: String },
}

/// The line number (1-based, header at 1) of data row `k`.
fn line(k: usize) -> usize {
    k + 2
}

impl Record {
    /// A record from its parts, checked as one read from CSV is (sample `k` is reported as line `k + 2`).
    pub fn new(
        times: Vec<f64>,
        inputs: Vec<Vec<f64>>,
        outputs: Vec<usize>,
        measured: Vec<Vec<f64>>,
    ) -> Result<Record, RecordError> {
        let n = times.len();
        if inputs.len() != n || measured.len() != n {
            return Err(RecordError::Shape {
                what: format!(
                    "{n} times, {} input rows, {} measured rows",
                    inputs.len(),
                    measured.len()
                ),
            });
        }
        let width = inputs.first().map_or(0, Vec::len);
        if let Some(k) = inputs.iter().position(|u| u.len() != width) {
            return Err(RecordError::Shape {
                what: format!(
                    "input row {k} has {} values, the first has {width}",
                    inputs[k].len()
                ),
            });
        }
        if measured.iter().any(|r| r.len() != outputs.len()) {
            return Err(RecordError::Shape {
                what: format!("a measured row does not have {} values", outputs.len()),
            });
        }
        let r = Record {
            times,
            inputs,
            outputs,
            measured,
        };
        r.check(Measured::Required)?;
        Ok(r)
    }

    /// Reads a CSV record for a model with the given input and output names. Cells may be in quotes; a header with
    /// `;` between its cells makes `;` the separator and a comma the decimal separator ([`super::csv::Dialect`]).
    pub fn from_csv(
        text: &str,
        input_names: &[&str],
        output_names: &[&str],
    ) -> Result<Record, RecordError> {
        Record::read_csv(text, input_names, output_names, Measured::Required)
    }

    /// Reads a CSV record of the inputs to replay (as [`Record::from_csv`] does), for a simulation: the columns of
    /// measured outputs may be there (and are read) or not.
    pub fn inputs_from_csv(
        text: &str,
        input_names: &[&str],
        output_names: &[&str],
    ) -> Result<Record, RecordError> {
        Record::read_csv(text, input_names, output_names, Measured::Optional)
    }

    fn read_csv(
        text: &str,
        input_names: &[&str],
        output_names: &[&str],
        measured_columns: Measured,
    ) -> Result<Record, RecordError> {
        // A spreadsheet's "CSV UTF-8" begins with a byte-order mark, which is not part of the first column's name.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(RecordError::TooShort { samples: 0 });
        };
        let dialect = super::csv::Dialect::of_header(header);
        let header_cells = dialect.cells(header);
        let names: Vec<&str> = header_cells.iter().map(|c| c.as_ref()).collect();
        let columns = Columns::map(&names, input_names, output_names, measured_columns)?;
        let mut times = Vec::new();
        let mut inputs = Vec::new();
        let mut measured = Vec::new();
        for (index, row) in lines {
            let cells = dialect.cells(row);
            let line = index + 1;
            if cells.len() != names.len() {
                return Err(RecordError::Ragged {
                    line,
                    got: cells.len(),
                    expected: names.len(),
                });
            }
            let cell = |c: usize, may_be_missing: bool| -> Result<f64, RecordError> {
                let text = cells[c].as_ref();
                if text.is_empty() && may_be_missing {
                    return Ok(f64::NAN);
                }
                let v: f64 =
                    dialect
                        .number_text(text)
                        .parse()
                        .map_err(|_| RecordError::NotANumber {
                            line,
                            column: names[c].to_string(),
                            text: text.to_string(),
                        })?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(RecordError::NonFinite {
                        line,
                        column: names[c].to_string(),
                        what: if v.is_nan() { "NaN" } else { "infinite" },
                    })
                }
            };
            times.push(cell(columns.time, false)?);
            inputs.push(
                columns
                    .inputs
                    .iter()
                    .map(|&c| cell(c, false))
                    .collect::<Result<Vec<_>, _>>()?,
            );
            measured.push(
                columns
                    .outputs
                    .iter()
                    .map(|&(c, _)| cell(c, true))
                    .collect::<Result<Vec<_>, _>>()?,
            );
        }
        let outputs = columns.outputs.iter().map(|&(_, o)| o).collect();
        let record = Record {
            times,
            inputs,
            outputs,
            measured,
        };
        record.check(measured_columns)?;
        Ok(record)
    }

    fn check(&self, measured_columns: Measured) -> Result<(), RecordError> {
        if self.times.len() < 2 {
            return Err(RecordError::TooShort {
                samples: self.times.len(),
            });
        }
        for (k, w) in self.times.windows(2).enumerate() {
            if w[1] <= w[0] || w[1].is_nan() {
                return Err(RecordError::Unsorted {
                    line: line(k + 1),
                    t: w[1],
                    previous: w[0],
                });
            }
        }
        for (k, (&t, u)) in self.times.iter().zip(&self.inputs).enumerate() {
            let bad = (!t.is_finite())
                .then_some("t")
                .or_else(|| u.iter().position(|v| !v.is_finite()).map(|_| "an input"));
            if let Some(column) = bad {
                return Err(RecordError::NonFinite {
                    line: line(k),
                    column: column.to_string(),
                    what: "not finite",
                });
            }
        }
        for (k, row) in self.measured.iter().enumerate() {
            if row.iter().any(|v| v.is_infinite()) {
                return Err(RecordError::NonFinite {
                    line: line(k),
                    column: "an output".into(),
                    what: "infinite",
                });
            }
        }
        if measured_columns == Measured::Required && self.sample_count() == 0 {
            return Err(RecordError::NothingMeasured);
        }
        Ok(())
    }

    /// The time column among the header's `names`: `t`, else `time` (as FMPy, Modelica tools and MATLAB's
    /// timetables name it) when no input or output has that name.
    pub fn time_column<S: AsRef<str>>(
        names: &[S],
        inputs: &[&str],
        outputs: &[&str],
    ) -> Option<usize> {
        let time_alias = !inputs.contains(&"time") && !outputs.contains(&"time");
        names.iter().position(|n| n.as_ref() == "t").or_else(|| {
            names
                .iter()
                .position(|n| n.as_ref() == "time" && time_alias)
        })
    }

    /// The number of measured (non-missing) values.
    pub fn sample_count(&self) -> usize {
        self.measured
            .iter()
            .map(|r| r.iter().filter(|v| !v.is_nan()).count())
            .sum()
    }

    /// Writes the inputs at time `t` in `[t_0, t_end]` (held outside it) into `u`. Returns `false`, and writes
    /// nothing, when `t` is not finite or `u` is not as long as a row of inputs.
    #[must_use]
    pub fn input_at(&self, interp: Interp, t: f64, u: &mut [f64]) -> bool {
        let k = self.times.partition_point(|&s| s <= t).saturating_sub(1);
        let Some(here) = self.inputs.get(k) else {
            return false;
        };
        if !t.is_finite() || u.len() != here.len() {
            return false;
        }
        match (interp, self.times.get(k + 1), self.inputs.get(k + 1)) {
            (Interp::Linear, Some(&t1), Some(next)) => {
                let s = ((t - self.times[k]) / (t1 - self.times[k])).clamp(0.0, 1.0);
                // The weighted mean, not `a + s (b − a)`: the difference of two finite samples may overflow.
                for ((o, a), b) in u.iter_mut().zip(here).zip(next) {
                    *o = a * (1.0 - s) + b * s;
                }
            }
            _ => u.copy_from_slice(here),
        }
        true
    }

    /// The sample indices at which a held input changes (where an integration segment must end), and the last
    /// sample; with linear interpolation only the last.
    pub fn segment_ends(&self, interp: Interp) -> Vec<usize> {
        let last = self.times.len() - 1;
        let mut ends: Vec<usize> = match interp {
            Interp::Linear => Vec::new(),
            Interp::Zoh => (1..last)
                .filter(|&k| self.inputs[k] != self.inputs[k - 1])
                .collect(),
        };
        ends.push(last);
        ends
    }
}

/// Whether a record must hold measured outputs: a fit's must, a replay's may.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Measured {
    Required,
    Optional,
}

/// Which CSV column holds what.
struct Columns {
    time: usize,
    inputs: Vec<usize>,
    /// `(column, model output index)`.
    outputs: Vec<(usize, usize)>,
}

impl Columns {
    fn map(
        names: &[&str],
        inputs: &[&str],
        outputs: &[&str],
        measured: Measured,
    ) -> Result<Columns, RecordError> {
        for (i, a) in names.iter().enumerate() {
            if let Some(j) = names[i + 1..].iter().position(|b| b == a) {
                return Err(RecordError::DuplicateColumn {
                    name: a.to_string(),
                    first: i + 1,
                    second: i + j + 2,
                });
            }
        }
        let time =
            Record::time_column(names, inputs, outputs).ok_or_else(|| RecordError::NoTime {
                header: names.join(","),
            })?;
        let mut input_columns = Vec::with_capacity(inputs.len());
        for name in inputs {
            let c =
                names
                    .iter()
                    .position(|n| n == name)
                    .ok_or_else(|| RecordError::MissingInput {
                        name: name.to_string(),
                    })?;
            input_columns.push(c);
        }
        let mut output_columns = Vec::new();
        for (c, name) in names.iter().enumerate() {
            if c == time || input_columns.contains(&c) {
                continue;
            }
            match outputs.iter().position(|o| o == name) {
                Some(o) => output_columns.push((c, o)),
                None if name.is_empty() => {
                    return Err(RecordError::UnnamedColumn { column: c + 1 });
                }
                None => {
                    return Err(RecordError::UnknownColumn {
                        column: c + 1,
                        name: name.to_string(),
                        inputs: list(inputs),
                        outputs: list(outputs),
                    });
                }
            }
        }
        if measured == Measured::Required && output_columns.is_empty() {
            return Err(RecordError::NoOutputs {
                known: list(outputs),
            });
        }
        Ok(Columns {
            time,
            inputs: input_columns,
            outputs: output_columns,
        })
    }
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        return "none".into();
    }
    let mut s = String::new();
    for (i, n) in names.iter().enumerate() {
        let _ = write!(s, "{}`{n}`", if i == 0 { "" } else { ", " });
    }
    s
}
