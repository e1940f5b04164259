//! `bgc simulate --data`: the inputs of a measured record as input signals.

use super::params::Assignment;
use bgc::equations::Equations;
use bgc::ir::Model;
use bgc::simulate::input::Signal;
use bgc::simulate::samples::{Replay, Samples};
use std::path::Path;

/// The record to replay and how.
#[derive(Clone, Copy, Debug)]
pub struct RecordArg<'a> {
    pub path: &'a Path,
    pub replay: Replay,
}

/// The recorded signals, by model input index, for the inputs not given with `--input`, and a warning when the
/// record does not cover the run `[0, t_end]`.
pub struct Recorded {
    pub signals: Vec<(usize, Signal)>,
    pub warning: Option<String>,
}

/// Reads the record at `arg.path` (already read into `text`) and makes a signal of each input it holds.
pub fn recorded_inputs(
    model: &Model,
    eqs: &Equations,
    arg: RecordArg<'_>,
    text: &str,
    given: &[Assignment],
    t_end: f64,
) -> Result<Recorded, String> {
    let elsewhere: Vec<&str> = given.iter().map(|a| a.name.as_str()).collect();
    let place = arg.path.display();
    let record = super::fit_record::read_inputs(model, eqs, text, &elsewhere)
        .map_err(|e| format!("{place}: {e}"))?;
    let read: Vec<usize> = (0..eqs.inputs.len())
        .filter(|&i| !elsewhere.contains(&eqs.inputs[i].as_str()))
        .collect();
    let mut signals = Vec::with_capacity(read.len());
    for (column, &input) in read.iter().enumerate() {
        let values = record
            .inputs
            .iter()
            .map(|row| row.get(column).copied().unwrap_or(f64::NAN))
            .collect();
        let samples = Samples::new(record.times.clone(), values, arg.replay)
            .map_err(|e| format!("{place}: input `{}`: {e}", eqs.inputs[input]))?;
        signals.push((input, Signal::Samples(samples)));
    }
    let warning = match (read.is_empty(), eqs.inputs.is_empty()) {
        (true, true) => Some(format!(
            "the model has no inputs: nothing of the record {place} is replayed"
        )),
        (true, false) => Some(format!(
            "every input is given with --input: nothing of the record {place} is replayed"
        )),
        (false, _) => coverage_warning(&place.to_string(), &record.times, t_end),
    };
    Ok(Recorded { warning, signals })
}

/// A warning when the record starts after 0 or ends before `t_end` (its end values then hold), or starts before 0
/// (the run does not replay what comes before its start).
fn coverage_warning(place: &str, times: &[f64], t_end: f64) -> Option<String> {
    let (&first, &last) = (times.first()?, times.last()?);
    let mut held = Vec::new();
    if first > 0.0 {
        held.push(format!("its first values hold from t = 0 to {first}"));
    }
    if first < 0.0 {
        // `bgc fit` starts its states at the record's first time; a run starts at t = 0.
        held.push(format!(
            "the run starts at t = 0 with the initial states, so the samples before it are not replayed (`bgc fit` \
             starts at the record's first time, t = {first})"
        ));
    }
    if last < t_end {
        held.push(format!(
            "its last values hold from t = {last} to --t-end {t_end}"
        ));
    }
    (!held.is_empty()).then(|| {
        format!(
            "the record {place} covers t = {first} to {last} s: {}",
            held.join(", and ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::coverage_warning;

    #[test]
    fn a_record_shorter_than_the_run_is_named() {
        assert_eq!(coverage_warning("r.csv", &[0.0, 1.0], 1.0), None);
        // A record that starts before the run: what comes before t = 0 is not replayed, unlike in `bgc fit`.
        assert_eq!(
            coverage_warning("r.csv", &[-1.0, 2.0], 1.0).as_deref(),
            Some(
                "the record r.csv covers t = -1 to 2 s: the run starts at t = 0 with the initial states, so the \
                 samples before it are not replayed (`bgc fit` starts at the record's first time, t = -1)"
            )
        );
        assert_eq!(
            coverage_warning("r.csv", &[0.5, 1.0], 2.0).as_deref(),
            Some(
                "the record r.csv covers t = 0.5 to 1 s: its first values hold from t = 0 to 0.5, and its last \
                 values hold from t = 1 to --t-end 2"
            )
        );
    }
}
