//! `bgc simulate`: integrate a model's equations and print CSV.

use super::io::{stderrln, stdout};
use super::model::derive_one;
use super::params::{Assignment, assign, param_values};
use super::{Solver, Status};
use bgc::simulate::System;
use bgc::simulate::input::Signal;
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
    // Inputs not given are zero.
    let mut signals = vec![Signal::Num(0.0); eqs.inputs.len()];
    for a in args.inputs {
        let Some(i) = eqs.inputs.iter().position(|n| *n == a.name) else {
            return Err(format!(
                "unknown input `{}`; the model has {}",
                a.name,
                if eqs.inputs.is_empty() {
                    "no inputs".to_string()
                } else {
                    eqs.inputs.join(", ")
                }
            ));
        };
        let s = Signal::parse(&a.value)
            .map_err(|e| format!("input `{}` = `{}`: {e}", a.name, a.value))?;
        if let Some(slot) = signals.get_mut(i) {
            *slot = s;
        }
    }
    let (system, warnings) = System::new(eqs, params, signals).map_err(|e| e.to_string())?;
    for w in warnings {
        stderrln(&format!("warning: {w}"));
    }
    let mut x0 = vec![0.0; system.state_count()];
    assign("state", &system.states, &mut x0, args.x0)?;
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
    out.push('t');
    for c in &traj.columns {
        out.push(',');
        out.push_str(c);
    }
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
