//! `bgc fit`: identify parameters (and initial states) of a model from a measured CSV record.

use super::fit_model::Interpreted;
use super::io::stderrln;
use super::model::derive_one;
use super::params::{
    Assignment, assign, check_divisors, check_physical, reject_repeats, unknown_name,
    values_or_zero,
};
use super::quantities::{self, Declared};
use super::{ReportFormat, Status};
use bgc::equations::Equations;
use bgc::ir::{Domain, Model};
use bgc::syntax::ast::ElementKind;
use bgc::units::{Dim, Unit, storage_parameter_unit};
use bgc_runtime::fit::{FitReport, FitSpec, FreeParam, FreeState, Interp, Record, fit};
use std::path::{Path, PathBuf};

/// The options of `bgc fit`.
pub struct FitArgs<'a> {
    pub data: &'a Path,
    pub free: &'a [String],
    pub params: &'a [Assignment],
    pub x0: &'a [Assignment],
    pub free_x0: bool,
    pub weights: &'a [Assignment],
    pub bounds: &'a [Assignment],
    pub format: ReportFormat,
    pub plot: Option<&'a PathBuf>,
    pub interp: Interp,
}

/// `bgc fit FILE --data LOG.csv --free NAMES`
pub fn run(path: &Path, wanted: Option<&str>, args: &FitArgs<'_>, color: bool) -> Status {
    if let Err(status) = super::io::stdin_once([path, args.data]) {
        return status;
    }
    let (d, _) = match derive_one(path, wanted, color, true) {
        Ok(x) => x,
        Err(s) => return s,
    };
    if let Some(plot) = args.plot
        && super::io::refuse_overwrite(plot, &d.loaded.sources, &[args.data]).is_err()
    {
        return Status::UsageOrIo;
    }
    let text = match super::io::read_record(args.data) {
        Ok(t) => t,
        Err(e) => {
            stderrln(&format!("error: cannot read {}: {e}", args.data.display()));
            return Status::UsageOrIo;
        }
    };
    match fit_record(&d.loaded.model, &d.eqs, &text, args) {
        Ok(done) => done,
        Err(msg) => {
            stderrln(&format!("error: {msg}"));
            Status::InputErrors
        }
    }
}

fn fit_record(
    model: &Model,
    eqs: &Equations,
    text: &str,
    args: &FitArgs<'_>,
) -> Result<Status, String> {
    let declared = quantities::params(model);
    let mut given: Vec<Option<f64>> = vec![None; declared.len()];
    for (i, v) in assign("parameter", "--param", &declared, args.params)? {
        given[i] = Some(v * declared[i].unit.scale);
    }
    let start = eqs.param_values(&given);
    check_physical(model, &start)?;
    check_divisors(model, eqs, &start)?;
    let outputs: Vec<&str> = eqs.outputs.iter().map(|o| o.name.as_str()).collect();
    let record = super::fit_record::read(model, eqs, text)
        .map_err(|e| format!("{}: {e}", args.data.display()))?;
    let free = free_params(model, eqs, &declared, &start, args)?;
    let states = quantities::states(model, eqs);
    let x0 = values_or_zero("state", "--x0", &states, args.x0)?;
    let mut spec = FitSpec::new(free, record.outputs.len());
    spec.interp = args.interp;
    spec.weights = weights(&record, &outputs, args.weights)?;
    if args.free_x0 {
        spec.x0 = free_states(&states, args.x0);
    }
    let free_indices: Vec<usize> = spec.params.iter().map(|p| p.index).collect();
    let mut interpreted = Interpreted::new(eqs, given, free_indices);
    let report = fit(&mut interpreted, &record, &start, &x0, &spec).map_err(|e| e.to_string())?;
    let units = Units::new(model, &declared, &states, &spec);
    super::fit_report::print(model, &record, &report, &units, args.format);
    if let Some(out) = args.plot {
        let names: Vec<String> = record
            .outputs
            .iter()
            .map(|&o| outputs[o].to_string())
            .collect();
        // The report is printed; a plot that cannot be written is an I/O error (status 2), as for every command.
        if let Err(e) = super::fit_plot::write(out, &record, &report, &names) {
            stderrln(&format!(
                "error: cannot write the plot {}: {e}",
                out.display()
            ));
            return Ok(Status::UsageOrIo);
        }
    }
    if !report.convergence.converged() {
        stderrln(&format!(
            "error: the fit {}: {} after {} iterations with the Gauss–Newton step still {:.3} standard errors \
             long; the estimates above are not a minimum",
            report.convergence.describe(),
            report.stop.describe(),
            report.iterations,
            report.optimality
        ));
        return Ok(Status::NotConverged);
    }
    Ok(Status::Ok)
}

/// The units in which the report writes each fitted quantity: `(text, scale from SI)`.
pub struct Units {
    pub of: Vec<(String, f64)>,
}

impl Units {
    fn new(_model: &Model, declared: &[Declared], states: &[Declared], spec: &FitSpec) -> Units {
        let mut of: Vec<(String, f64)> = spec
            .params
            .iter()
            .map(|p| (declared[p.index].text.clone(), declared[p.index].unit.scale))
            .collect();
        // Initial states are in the units of the CSV header already.
        of.extend(spec.x0.iter().map(|s| (states[s.index].text.clone(), 1.0)));
        Units { of }
    }
}

/// The `--free` parameters with their log-space flag and `--bound`s (in the declared unit, converted to SI).
fn free_params(
    model: &Model,
    eqs: &Equations,
    declared: &[Declared],
    start: &[f64],
    args: &FitArgs<'_>,
) -> Result<Vec<FreeParam>, String> {
    for (k, name) in args.free.iter().enumerate() {
        if let Some(first) = args.free[..k].iter().position(|n| n == name) {
            return Err(format!(
                "--free names parameter `{name}` twice (at places {} and {}); give each name once",
                first + 1,
                k + 1
            ));
        }
    }
    let mut out = Vec::with_capacity(args.free.len());
    for name in args.free {
        let Some(index) = declared.iter().position(|d| &d.name == name) else {
            if eqs.states.iter().any(|s| &s.name == name) {
                return Err(format!(
                    "--free: `{name}` is a state, not a parameter; its initial value is fitted with --free-x0 \
                     (with `--x0 {name}=START`, only the states given there)"
                ));
            }
            let other = if eqs.inputs.contains(name) {
                Some("an input")
            } else if eqs.outputs.iter().any(|o| &o.name == name) {
                Some("an output")
            } else {
                None
            };
            if let Some(kind) = other {
                return Err(format!(
                    "--free: `{name}` is {kind} of the model, not a parameter; --free takes parameters"
                ));
            }
            let known = super::params::names(declared);
            return Err(format!(
                "--free: {}",
                unknown_name("parameter", name, &known)
            ));
        };
        let log = start[index] > 0.0 && positive_by_unit(model, declared[index].unit);
        out.push(FreeParam::new(index, name, log));
    }
    reject_repeats("parameter", "--bound", args.bounds)?;
    for b in args.bounds {
        let Some(p) = out.iter_mut().find(|p| p.name == b.name) else {
            return Err(format!(
                "--bound `{}`: bounds apply to fitted parameters; name it with --free",
                b.name
            ));
        };
        let (lo, hi) = parse_bounds(&b.value).map_err(|e| format!("--bound `{}`: {e}", b.name))?;
        let scale = declared[p.index].unit.scale;
        p.lower = lo * scale;
        p.upper = hi * scale;
    }
    Ok(out)
}

/// `LO..HI` (either side may be empty for no bound), in the parameter's declared unit.
fn parse_bounds(text: &str) -> Result<(f64, f64), String> {
    let Some((lo, hi)) = text.split_once("..") else {
        return Err(format!("`{text}` is not of the form LO..HI"));
    };
    let side = |s: &str, none: f64| -> Result<f64, String> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(none);
        }
        s.parse::<f64>()
            .ok()
            .filter(|v| !v.is_nan())
            .ok_or_else(|| format!("`{s}` is not a number"))
    };
    let (lo, hi) = (side(lo, f64::NEG_INFINITY)?, side(hi, f64::INFINITY)?);
    if lo < hi {
        Ok((lo, hi))
    } else {
        Err(format!(
            "the lower bound {lo} is not below the upper bound {hi}"
        ))
    }
}

/// True when the unit is that of a quantity positive by its nature: the coefficient of an inertia, a
/// compliance or a resistance in any domain, a stiffness (the inverse of a compliance), a mass, a length or a
/// time.
fn positive_by_unit(_model: &Model, unit: Unit) -> bool {
    let mut dims: Vec<Dim> = vec![
        Dim::new(0, 1, 0, 0, 0, 0, 0),
        Dim::new(1, 0, 0, 0, 0, 0, 0),
        Dim::new(0, 0, 1, 0, 0, 0, 0),
    ];
    for domain in Domain::ALL {
        for kind in [ElementKind::I, ElementKind::C, ElementKind::R] {
            if let Some((d, _)) = storage_parameter_unit(kind, domain) {
                dims.push(d);
                if kind == ElementKind::C
                    && let Some(k) = Dim::NONE.checked_div(d)
                {
                    dims.push(k);
                }
            }
        }
    }
    !unit.dim.is_dimensionless() && dims.contains(&unit.dim)
}

/// One weight per measured column: `--weight OUT=W`, 1 where not given.
fn weights(record: &Record, outputs: &[&str], given: &[Assignment]) -> Result<Vec<f64>, String> {
    reject_repeats("output", "--weight", given)?;
    let mut w = vec![1.0; record.outputs.len()];
    for a in given {
        let Some(o) = outputs.iter().position(|n| *n == a.name) else {
            return Err(format!(
                "--weight: {}",
                unknown_name("output", &a.name, outputs)
            ));
        };
        let Some(c) = record.outputs.iter().position(|&m| m == o) else {
            return Err(format!(
                "--weight `{}`: the record has no column for this output",
                a.name
            ));
        };
        let v: f64 = a
            .value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0)
            .ok_or_else(|| {
                format!(
                    "--weight `{}={}`: a weight is a finite positive number",
                    a.name, a.value
                )
            })?;
        w[c] = v;
    }
    Ok(w)
}

/// The initial states to fit: those named with `--x0`, or all when none is.
fn free_states(states: &[Declared], given: &[Assignment]) -> Vec<FreeState> {
    states
        .iter()
        .enumerate()
        .filter(|(_, s)| given.is_empty() || given.iter().any(|a| a.name == s.name))
        .map(|(index, s)| FreeState {
            index,
            name: format!("{}(0)", s.name),
        })
        .collect()
}

/// The report's view of the fit, for the printers.
pub fn estimates_in_units(
    report: &FitReport,
    units: &Units,
) -> Vec<(String, f64, f64, f64, String, bool)> {
    report
        .estimates
        .iter()
        .zip(&units.of)
        .map(|(e, (text, scale))| {
            (
                e.name.clone(),
                e.value / scale,
                e.std_error / scale,
                e.start / scale,
                text.clone(),
                e.determined,
            )
        })
        .collect()
}
