//! `bgc simulate`: integrate a model's equations and print CSV.

use super::io::{stderr, stderrln, stdout};
use super::model::derive_one;
use super::params::{Assignment, input_signals, param_values, values_or_zero, zero_inputs_warning};
use super::quantities;
use super::{Solver, Status};
use bgc::simulate::System;
use bgc::simulate::integrate::{Method, RunOptions, run};
use std::fmt::Write as _;
use std::path::Path;

/// The options of `bgc simulate`.
pub struct SimulateArgs<'a> {
    pub t_end: f64,
    pub dt_out: Option<f64>,
    pub params: &'a [Assignment],
    pub inputs: &'a [Assignment],
    pub x0: &'a [Assignment],
    pub solver: Solver,
    pub rtol: f64,
    pub atol: f64,
    /// Print the effective parameter values and initial state on standard error.
    pub verbose: bool,
}

/// The number of sample intervals when `--dt-out` is not given.
const DEFAULT_INTERVALS: f64 = 1000.0;

/// `bgc simulate FILE --t-end T`
pub fn simulate(path: &Path, wanted: Option<&str>, args: &SimulateArgs<'_>, color: bool) -> Status {
    let (d, _) = match derive_one(path, wanted, color, true) {
        Ok(x) => x,
        Err(s) => return s,
    };
    match csv(&d.loaded.model, &d.eqs, args) {
        Ok(text) => {
            stdout(&text);
            Status::Ok
        }
        Err(msg) => {
            stderrln(&format!("error: {msg}"));
            Status::InputErrors
        }
    }
}

fn csv(
    model: &bgc::ir::Model,
    eqs: &bgc::equations::Equations,
    args: &SimulateArgs<'_>,
) -> Result<String, String> {
    let params = param_values(model, eqs, args.params)?;
    let (signals, held_at_zero) = input_signals(model, args.inputs)?;
    if let Some(w) = zero_inputs_warning(&held_at_zero) {
        stderrln(&w);
    }
    let (system, warnings) =
        System::new(eqs, params.clone(), signals).map_err(|e| e.to_string())?;
    for w in warnings {
        stderrln(&format!("warning: {w}"));
    }
    let states = quantities::states(model, eqs);
    let x0 = values_or_zero("state", "--x0", &states, args.x0)?;
    if args.verbose {
        stderr(&quantities::describe_params(
            model,
            eqs,
            &params,
            args.params,
        ));
        stderr(&quantities::describe_values(
            "initial state",
            &states,
            &x0,
            args.x0,
        ));
    }
    let opts = RunOptions {
        t_end: args.t_end,
        dt_out: args.dt_out.unwrap_or(args.t_end / DEFAULT_INTERVALS),
        method: match args.solver {
            Solver::Bdf => Method::Bdf,
            Solver::Esdirk34 => Method::Esdirk34,
            Solver::TrBdf2 => Method::TrBdf2,
            Solver::Tsit45 => Method::Tsit45,
        },
        rtol: args.rtol,
        atol: args.atol,
        max_steps: 10_000_000,
    };
    let traj = run(&system, &x0, &opts).map_err(|e| e.to_string())?;
    let mut out = String::new();
    out.push_str(&quantities::csv_header(model, eqs, &traj.columns));
    out.push('\n');
    for (t, row) in traj.times.iter().zip(&traj.rows) {
        let _ = write!(out, "{t}");
        for v in row {
            // Shortest round-trip form: the printed numbers read back exactly.
            let _ = write!(out, ",{v:e}");
        }
        out.push('\n');
    }
    Ok(out)
}
