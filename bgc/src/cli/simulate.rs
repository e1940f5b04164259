//! `bgc simulate`: integrate a model's equations and print CSV.

use super::io::{output_failed, stderr, stderrln};
use super::model::derive_one;
use super::params::{Assignment, input_signals, param_values, values_or_zero, zero_inputs_warning};
use super::quantities;
pub use super::replay::RecordArg;
use super::replay::recorded_inputs;
use super::{Solver, Status};
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run_streaming_noted};
use bgc::simulate::{SimError, System};
use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::ControlFlow;
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
    /// `--max-step`.
    pub max_step: Option<f64>,
    /// The record whose inputs are replayed (`--data`, `--interp`).
    pub record: Option<RecordArg<'a>>,
    /// Print the effective parameter values and initial state on standard error.
    pub verbose: bool,
}

/// The number of sample intervals when `--dt-out` is not given.
const DEFAULT_INTERVALS: f64 = 1000.0;

/// `--dt-out`, or `t-end/1000` when it is not given. A `--t-end` so small that a thousandth of it is not a normal
/// number is refused in its own name, not in the name of an option the user did not give.
fn default_dt_out(args: &SimulateArgs<'_>) -> Result<f64, String> {
    if let Some(dt) = args.dt_out {
        return Ok(dt);
    }
    let dt = args.t_end / DEFAULT_INTERVALS;
    if args.t_end > 0.0 && args.t_end.is_finite() && !dt.is_normal() {
        return Err(format!(
            "--t-end {:e} is too small: the default sampling interval t-end/1000 is {dt:e}, below the smallest \
             normal number; give a larger --t-end (and --dt-out)",
            args.t_end
        ));
    }
    Ok(dt)
}

/// `bgc simulate FILE --t-end T`
pub fn simulate(path: &Path, wanted: Option<&str>, args: &SimulateArgs<'_>, color: bool) -> Status {
    if let Err(status) =
        super::io::stdin_once(std::iter::once(path).chain(args.record.map(|r| r.path)))
    {
        return status;
    }
    let (d, _) = match derive_one(path, wanted, color, true) {
        Ok(x) => x,
        Err(s) => return s,
    };
    let read = |path: &Path| super::io::read_record(path).map_err(|e| (path.to_path_buf(), e));
    let text = match args.record.map(|r| read(r.path)).transpose() {
        Ok(text) => text,
        Err((path, e)) => {
            stderrln(&format!("error: cannot read {}: {e}", path.display()));
            return Status::UsageOrIo;
        }
    };
    match csv(
        &d.loaded.model,
        &d.eqs,
        args,
        args.record.zip(text.as_deref()),
    ) {
        Ok(()) => Status::Ok,
        Err(Failure::Input(msg)) => {
            stderrln(&format!("error: {msg}"));
            Status::InputErrors
        }
        Err(Failure::Output(e)) => output_failed(&e),
    }
}

/// Why a run printed no complete table.
enum Failure {
    /// The model, the arguments or the solver (status 1).
    Input(String),
    /// Writing standard output (a closed pipe ends the run quietly; anything else is status 2).
    Output(std::io::Error),
}

impl From<String> for Failure {
    fn from(msg: String) -> Failure {
        Failure::Input(msg)
    }
}

fn csv(
    model: &bgc::ir::Model,
    eqs: &bgc::equations::Equations,
    args: &SimulateArgs<'_>,
    record: Option<(RecordArg<'_>, &str)>,
) -> Result<(), Failure> {
    let opts = RunOptions {
        t_end: args.t_end,
        dt_out: default_dt_out(args)?,
        method: match args.solver {
            Solver::Bdf => Method::Bdf,
            Solver::Esdirk34 => Method::Esdirk34,
            Solver::TrBdf2 => Method::TrBdf2,
            Solver::Tsit45 => Method::Tsit45,
        },
        rtol: args.rtol,
        atol: args.atol,
        max_steps: 10_000_000,
        max_step: args.max_step,
    };
    // The options are checked before anything else is said about the run.
    opts.check().map_err(option_error)?;
    let params = param_values(model, eqs, args.params)?;
    let signals = signals(model, eqs, args, record)?;
    let (system, warnings) =
        System::new(eqs, params.clone(), signals).map_err(|e| e.to_string())?;
    // An energy term without a closed form is left out of its column: the balance cannot be checked then.
    let check_balance = warnings.is_empty();
    for w in warnings {
        stderrln(&format!("warning: {w}"));
    }
    let states = quantities::states(model, eqs);
    let x0 = values_or_zero("state", "--x0", &states, args.x0)?;
    let mut balance = Balance::new(check_balance, &opts, x0.len());
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
    // Rows go out as they are computed (a long run's memory does not grow with its length), and the run stops as
    // soon as the output is closed.
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut header = quantities::csv_header(model, eqs, &system.columns());
    header.push('\n');
    let mut write_error: Option<std::io::Error> = None;
    // The header goes out with the first row, so that a run that cannot start prints nothing.
    let mut line = header;
    let mut printed = 0usize;
    let mut notes = Vec::new();
    let result = run_streaming_noted(
        &system,
        &x0,
        &opts,
        &mut |t, row| {
            balance.see(t, row);
            write_time(&mut line, t);
            for v in row {
                // Shortest round-trip form: the printed numbers read back exactly. A zero is printed `0e0`
                // whatever its sign (`-0.0 + 0.0` is `0.0`): `-0e0` reads as a negative number to most readers.
                let v = v + 0.0;
                let _ = write!(line, ",{v:e}");
            }
            line.push('\n');
            let written = out.write_all(line.as_bytes());
            line.clear();
            match written {
                Ok(()) => {
                    printed += 1;
                    ControlFlow::Continue(())
                }
                Err(e) => {
                    write_error = Some(e);
                    ControlFlow::Break(())
                }
            }
        },
        &mut notes,
    );
    for note in notes {
        stderrln(&format!("warning: {note}"));
    }
    if let Some(e) = write_error {
        return Err(Failure::Output(e));
    }
    // The rows computed before a failure are printed; the error says where the run stopped.
    let flushed = out.flush();
    if let Some(warning) = balance.warning() {
        stderrln(&format!("warning: {warning}"));
    }
    result.map_err(|e| match printed {
        0 => e.to_string(),
        n => format!("{e} (the {n} rows before it were printed)"),
    })?;
    flushed.map_err(Failure::Output)
}

/// The input signals: the expressions of `--input`, the record's samples for the others, 0 for the rest (with a
/// warning that names them).
fn signals(
    model: &bgc::ir::Model,
    eqs: &bgc::equations::Equations,
    args: &SimulateArgs<'_>,
    record: Option<(RecordArg<'_>, &str)>,
) -> Result<Vec<Signal>, String> {
    let (mut signals, mut held_at_zero) = input_signals(model, args.inputs)?;
    if let Some((arg, text)) = record {
        let recorded = recorded_inputs(model, eqs, arg, text, args.inputs, args.t_end)?;
        for (i, signal) in recorded.signals {
            held_at_zero.retain(|n| Some(n) != eqs.inputs.get(i));
            if let Some(slot) = signals.get_mut(i) {
                *slot = signal;
            }
        }
        if let Some(w) = recorded.warning {
            stderrln(&format!("warning: {w}"));
        }
    }
    if let Some(w) = zero_inputs_warning(&held_at_zero) {
        stderrln(&w);
    }
    Ok(signals)
}

/// An option that no run can have, named as the command line spells it (`--t-end`, not the field `t_end`).
fn option_error(e: SimError) -> String {
    match e {
        SimError::BadSetting {
            name,
            value,
            reason,
        } => {
            let mut shown = String::new();
            write_time(&mut shown, value);
            format!(
                "--{} {shown} is not allowed: {reason}",
                name.replace('_', "-")
            )
        }
        other => other.to_string(),
    }
}

/// The time column (and a time or tolerance in a message): decimal (`0.25`, `12.5`) where that is short, else with
/// an exponent (`1e-300`, `1e20`), which Display would write out in hundreds of digits; both are the shortest form
/// that reads back exactly.
fn write_time(line: &mut String, t: f64) {
    let _ = if t == 0.0 || !t.is_finite() || (1e-4..1e16).contains(&t.abs()) {
        write!(line, "{t}")
    } else {
        write!(line, "{t:e}")
    };
}

/// The energy balance of a run: `energy + dissipated − supplied` stays at its initial value in the exact solution,
/// so its drift measures the integration error of the whole run in one number.
///
/// A run whose states all stay within `ε·atol` of zero is the zero solution up to rounding: the error control
/// weighs a state by `1/(atol + rtol·|x|)`, so values that small are below anything it resolves (a loop solved to
/// its tolerance at `u = 0` leaves states of 1e-39 and energies of 1e-52 J). Its energy terms are rounding too, and
/// their drift is not reported however large it is relative to them.
struct Balance {
    check: bool,
    rtol: f64,
    /// The magnitude below which a state is indistinguishable from zero to the error control, and the number of
    /// states at the start of each row.
    zero_band: f64,
    states: usize,
    /// The largest magnitude of a state in the run.
    largest_state: f64,
    start: Option<f64>,
    /// The largest drift, when it happened, and the largest magnitude of the three terms.
    worst: (f64, f64),
    scale: f64,
}

/// The drift, relative to the largest energy term, above which a run is reported: a thousand times `--rtol`.
const BALANCE_FACTOR: f64 = 1e3;

impl Balance {
    fn new(check: bool, opts: &RunOptions, states: usize) -> Balance {
        Balance {
            check,
            rtol: opts.rtol,
            zero_band: f64::EPSILON * opts.atol,
            states,
            largest_state: 0.0,
            start: None,
            worst: (0.0, 0.0),
            scale: 0.0,
        }
    }

    /// A row: its last three values are energy, dissipated and supplied.
    fn see(&mut self, t: f64, row: &[f64]) {
        let [energy, dissipated, supplied] = match row.get(row.len().saturating_sub(3)..) {
            Some(&[e, d, s]) => [e, d, s],
            _ => return,
        };
        if let Some(states) = row.get(..self.states) {
            let largest = states.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            self.largest_state = self.largest_state.max(largest);
        }
        let total = energy + dissipated - supplied;
        let start = *self.start.get_or_insert(total);
        let drift = (total - start).abs();
        self.scale = self
            .scale
            .max(energy.abs())
            .max(dissipated.abs())
            .max(supplied.abs());
        if drift > self.worst.0 {
            self.worst = (drift, t);
        }
    }

    /// The warning when the drift exceeded the bound.
    fn warning(&self) -> Option<String> {
        let (drift, t) = self.worst;
        let relative = drift / self.scale;
        let at_rest = self.states > 0 && self.largest_state <= self.zero_band;
        let drifted = self.scale > 0.0 && relative > BALANCE_FACTOR * self.rtol;
        (self.check && !at_rest && drifted).then(|| {
            format!(
                "the energy balance drifted: energy + dissipated - supplied changed by {drift:.3e} J (largest by t = \
                 {t}), {} % of the largest energy term ({:.3e} J), above the tolerance of {} % ({BALANCE_FACTOR} \
                 times --rtol {:e}); the results are not accurate to the tolerances: give a smaller --rtol, an \
                 --atol well below the smallest state and energy that matter, or another --solver",
                significant(100.0 * relative),
                self.scale,
                significant(100.0 * BALANCE_FACTOR * self.rtol),
                self.rtol
            )
        })
    }
}

/// `x` with four significant digits in positional notation (`46.07`, `0.1000`, `0.00001234`).
fn significant(x: f64) -> String {
    if !(x.is_finite() && x > 0.0) {
        return format!("{x}");
    }
    let decimals = (3.0 - x.log10().floor()).clamp(0.0, 20.0) as usize;
    format!("{x:.decimals$}")
}
