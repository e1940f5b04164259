//! Integration of a [`System`] with diffsol on dynamic (nalgebra) vectors.
//!
//! The run is split at the inputs' breakpoints (the times of `step` and `ramp`): a fresh solver starts at each,
//! so a jump never enters an implicit method's step history, and within a segment `[a, b)` the inputs are
//! evaluated at times strictly before `b`, as the solver's last stage at `b` would otherwise see the jump. States
//! are reported at the sample times by the solver's dense output (interpolation of the accepted steps, of the
//! method's order). At a breakpoint the states are continuous but a jump of an input may change the stored energy
//! (a flow source imposing an inertia's velocity): that jump, [`System::stored_jump`], is added to the `supplied`
//! quadrature there, so `energy + dissipated − supplied` stays constant across steps. The Jacobian handed to the
//! implicit methods is the symbolic one of the equations (through nonlinear algebraic loops, from the sparse path
//! on), or finite differences when a rate uses a function without a derivative.
//!
//! BDF's orders 3 to 5 are not A-stable: a lightly damped fast mode that the tolerances resolve holds its steps at a
//! fraction of that mode's period. When BDF advances so slowly that the rest of a segment would exceed the step
//! budget, the segment goes on with TR-BDF2 (A- and L-stable) from the last accepted step, and
//! [`run_streaming_noted`] returns a note that says so.

use std::cell::RefCell;
use std::ops::ControlFlow;

use diffsol::error::{DiffsolError, OdeSolverError};
use diffsol::{
    FaerSparseLU, FaerSparseMat, NalgebraLU, NalgebraMat, OdeBuilder, OdeEquations,
    OdeSolverMethod, OdeSolverStopReason, Vector,
};

use super::sparse_ode::SparseOde;
use super::{SimError, System};

type M = NalgebraMat<f64>;
type Ls = NalgebraLU<f64>;

pub use super::SPARSE_FROM;

/// The integration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Variable-order variable-step BDF: for stiff models. The default.
    #[default]
    Bdf,
    /// ESDIRK3(4): stiff, one-step.
    Esdirk34,
    /// TR-BDF2: stiff, robust, low order.
    TrBdf2,
    /// Tsitouras 5(4) explicit Runge–Kutta: for non-stiff models.
    Tsit45,
}

/// The settings of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    pub t_end: f64,
    /// The sampling interval of the rows.
    pub dt_out: f64,
    pub method: Method,
    pub rtol: f64,
    pub atol: f64,
    /// Upper bound on internal steps per segment.
    pub max_steps: usize,
    /// The longest step the solver may take, or none. The error estimate of a step sees the model only at the
    /// points the step evaluates: a forcing whose effect lasts a short window (a diode conducting near each peak of
    /// a sine) can fall between them, and then nothing makes the step shorter.
    pub max_step: Option<f64>,
}

/// The smallest relative tolerance: 100 machine epsilons, as MATLAB's ODE solvers also raise `RelTol` to. Below
/// it a step's error test compares rounding errors.
pub const MIN_RTOL: f64 = 100.0 * f64::EPSILON;

/// The most rows a run produces.
pub const MAX_ROWS: usize = 10_000_000;

impl RunOptions {
    /// Refuses options no run can have (a non-finite or non-positive time, step or tolerance, too many rows); a
    /// run checks them first.
    pub fn check(&self) -> Result<(), SimError> {
        let positive: [(&'static str, f64); 4] = [
            ("t_end", self.t_end),
            ("dt_out", self.dt_out),
            ("rtol", self.rtol),
            ("atol", self.atol),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(SimError::BadSetting {
                    name,
                    value,
                    reason: "it must be finite and positive",
                });
            }
        }
        if let Some(h) = self.max_step {
            if !(h.is_finite() && h > 0.0) {
                return Err(SimError::BadSetting {
                    name: "max_step",
                    value: h,
                    reason: "it must be finite and positive",
                });
            }
            if self.t_end / h > self.max_steps as f64 {
                return Err(SimError::BadSetting {
                    name: "max_step",
                    value: h,
                    reason: "the run would take more steps than its budget allows (t_end / max_step above \
                             max_steps, 10,000,000 for the CLI)",
                });
            }
        }
        if self.rtol < MIN_RTOL {
            return Err(SimError::BadSetting {
                name: "rtol",
                value: self.rtol,
                reason: "it is below 100 times the machine epsilon (2.2e-14), the smallest relative error to which \
                         f64 arithmetic can hold a step: the solver could only fail or stall on rounding errors",
            });
        }
        if self.rtol >= 1.0 {
            return Err(SimError::BadSetting {
                name: "rtol",
                value: self.rtol,
                reason: "a relative error of 100 % or more bounds nothing (and the energy balance, checked to 1000 \
                         times rtol, could never be reported off)",
            });
        }
        let rows = (self.t_end / self.dt_out).floor() + 2.0;
        if rows > MAX_ROWS as f64 {
            return Err(SimError::TooManyRows {
                rows,
                limit: MAX_ROWS,
            });
        }
        Ok(())
    }

    /// The sample times: `0, dt, 2 dt, …` up to `t_end`, and `t_end` itself.
    pub fn sample_times(&self) -> Vec<f64> {
        let s = Samples::new(self);
        (0..s.count).filter_map(|k| s.get(k)).collect()
    }
}

/// The sample times, computed one at a time so that a run's memory does not grow with its number of rows.
#[derive(Clone, Copy, Debug)]
struct Samples {
    dt: f64,
    t_end: f64,
    count: usize,
}

impl Samples {
    fn new(opts: &RunOptions) -> Samples {
        let n = (opts.t_end / opts.dt_out * (1.0 + 1e-12)).floor() as usize;
        // `n dt` is the last multiple; `t_end` replaces it when it is that close, else follows it.
        let close = (opts.t_end - n as f64 * opts.dt_out) <= 1e-9 * opts.t_end;
        Samples {
            dt: opts.dt_out,
            t_end: opts.t_end,
            count: if close { n + 1 } else { n + 2 },
        }
    }

    fn get(&self, k: usize) -> Option<f64> {
        match k.cmp(&(self.count - 1)) {
            std::cmp::Ordering::Less => Some(k as f64 * self.dt),
            std::cmp::Ordering::Equal => Some(self.t_end),
            std::cmp::Ordering::Greater => None,
        }
    }
}

/// A run's result: the sample times and, per time, the row of [`System::row`].
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    pub columns: Vec<String>,
    pub times: Vec<f64>,
    pub rows: Vec<Vec<f64>>,
}

/// How a streamed run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finish {
    /// Every row up to `t_end` was handed over.
    Done,
    /// The receiver asked to stop (its output was closed).
    Stopped,
}

/// Integrates `system` from the model state `x0` at `t = 0` (the energy quadratures start at zero) and collects
/// the rows.
pub fn run(system: &System, x0: &[f64], opts: &RunOptions) -> Result<Trajectory, SimError> {
    let mut times = Vec::new();
    let mut rows = Vec::new();
    run_streaming(system, x0, opts, &mut |t, row| {
        times.push(t);
        rows.push(row.to_vec());
        ControlFlow::Continue(())
    })?;
    Ok(Trajectory {
        columns: system.columns(),
        times,
        rows,
    })
}

/// Integrates as [`run`] does, handing each row (of [`System::row`]) to `sink` as soon as it is computed; `sink`
/// breaks to stop the run. Memory does not depend on the number of rows.
pub fn run_streaming(
    system: &System,
    x0: &[f64],
    opts: &RunOptions,
    sink: &mut dyn FnMut(f64, &[f64]) -> ControlFlow<()>,
) -> Result<Finish, SimError> {
    run_streaming_noted(system, x0, opts, sink, &mut Vec::new())
}

/// [`run_streaming`], with the notes about how the run went (a change of method, see [`Method::Bdf`]) pushed onto
/// `notes` for the caller to show.
pub fn run_streaming_noted(
    system: &System,
    x0: &[f64],
    opts: &RunOptions,
    sink: &mut dyn FnMut(f64, &[f64]) -> ControlFlow<()>,
    notes: &mut Vec<String>,
) -> Result<Finish, SimError> {
    opts.check()?;
    let n = system.state_count();
    if x0.len() != n {
        return Err(SimError::Dimension {
            what: "initial state",
            expected: n,
            got: x0.len(),
        });
    }
    let mut y: Vec<f64> = x0.iter().copied().chain([0.0, 0.0]).collect();
    let samples = Samples::new(opts);
    let mut u = Vec::new();
    let mut stack = Vec::new();
    let first = system.row(&y, 0.0, &mut u, &mut stack)?;
    if let Some(i) = first.iter().position(|v| !v.is_finite()) {
        if let Some(input) = system.non_finite_input(0.0) {
            return Err(input);
        }
        let columns = system.columns();
        // The stored energy is the third column from the end (see `System::columns`).
        let what = if i + 3 == columns.len() {
            system.stored_energy_fault(&y, 0.0, &u, &mut stack)
        } else {
            None
        };
        return Err(SimError::NonFiniteStart {
            what: what.unwrap_or_else(|| columns.get(i).cloned().unwrap_or_default()),
        });
    }
    if sink(0.0, &first).is_break() {
        return Ok(Finish::Stopped);
    }
    let mut bounds = vec![0.0];
    bounds.extend(system.breakpoints(opts.t_end));
    bounds.push(opts.t_end);
    let mut next = 1;
    for w in bounds.windows(2) {
        let (a, b) = match w {
            [a, b] => (*a, *b),
            _ => continue,
        };
        let start = next;
        while samples.get(next).is_some_and(|t| t <= b) {
            next += 1;
        }
        let last = b >= opts.t_end;
        // Rows before `b` go out as they come; those at `b` of a segment that is not the last wait for the jump.
        // The loops' solution at `a` (in the tear slots of the last row's inputs) starts the segment's first solve.
        let warm = u.clone();
        let mut held: Vec<(f64, Vec<f64>)> = Vec::new();
        let mut deliver = |t: f64, ys: &[f64]| -> Result<ControlFlow<()>, SimError> {
            if !last && t >= b {
                held.push((t, ys.to_vec()));
                return Ok(ControlFlow::Continue(()));
            }
            let row = system.row(ys, t, &mut u, &mut stack)?;
            Ok(sink(t, &row))
        };
        let wanted = Wanted {
            samples,
            range: start..next,
        };
        let end = segment(
            system,
            &y,
            a,
            b,
            last,
            &wanted,
            opts,
            &mut deliver,
            notes,
            &warm,
        )?;
        let Some(end) = end else {
            return Ok(Finish::Stopped);
        };
        y = end;
        if !last {
            // The row at `b` itself shows the inputs after their jump, so it gets the jump's energy too.
            let jump = system.stored_jump(&y, just_before(b), b, &mut stack)?;
            if let Some(sup) = y.get_mut(n + 1) {
                *sup += jump;
            }
            for (t, mut ys) in held {
                if let Some(sup) = ys.get_mut(n + 1) {
                    *sup += jump;
                }
                let row = system.row(&ys, t, &mut u, &mut stack)?;
                if sink(t, &row).is_break() {
                    return Ok(Finish::Stopped);
                }
            }
        }
    }
    Ok(Finish::Done)
}

/// The sample times a segment reports.
struct Wanted {
    samples: Samples,
    range: std::ops::Range<usize>,
}

impl Wanted {
    /// The times after the first `delivered`.
    fn after(&self, delivered: usize) -> Wanted {
        let start = (self.range.start + delivered).min(self.range.end);
        Wanted {
            samples: self.samples,
            range: start..self.range.end,
        }
    }

    fn get(&self, i: usize) -> Option<f64> {
        let k = self.range.start.checked_add(i)?;
        if k < self.range.end {
            self.samples.get(k)
        } else {
            None
        }
    }
}

/// Where a segment's extended states at the sample times go; breaks to stop the run.
type Deliver<'d> = dyn FnMut(f64, &[f64]) -> Result<ControlFlow<()>, SimError> + 'd;

/// Integrates `[a, b]` from `y0`, delivering the extended state at the `wanted` times; returns the state at `b`, or
/// `None` when the receiver stopped the run. When BDF stalls ([`Outcome::Stalled`]) the rest of the segment is
/// integrated by TR-BDF2 from the last accepted step, and a note says so.
#[allow(clippy::too_many_arguments)]
fn segment(
    system: &System,
    y0: &[f64],
    a: f64,
    b: f64,
    last: bool,
    wanted: &Wanted,
    opts: &RunOptions,
    out: &mut Deliver<'_>,
    notes: &mut Vec<String>,
    warm: &[f64],
) -> Result<Option<Vec<f64>>, SimError> {
    match segment_once(system, y0, a, b, last, wanted, opts, out, warm)? {
        Outcome::Reached(y) => Ok(Some(y)),
        Outcome::Unresolved(y) => {
            // Breakpoints a few units in the last place apart are the same time written two ways; a whole run of
            // 1e-30 s is not, and its flat result deserves a word.
            if b - a > UNRESOLVED_ULPS * f64::EPSILON * a.abs() {
                notes.push(format!(
                    "the interval from t = {a:e} to {b:e} s is shorter than the solver resolves at its start, and the \
                     state was carried over it unchanged: its rows show no change (lengthen --t-end)"
                ));
            }
            Ok(Some(y))
        }
        Outcome::Stopped => Ok(None),
        Outcome::Stalled {
            t,
            y,
            delivered,
            steps,
        } => {
            notes.push(format!(
                "BDF stalled at t = {t:e} ({steps} steps from t = {a:e}, too short to reach t = {b:e} in the step \
                 budget), as when a lightly damped fast mode makes its orders above 2, which are not A-stable, \
                 unstable once the tolerances resolve that mode (a law with a near-discontinuity holds the step short \
                 too); the run went on with --solver tr_bdf2 (A- and L-stable) from there"
            ));
            let rest = RunOptions {
                method: Method::TrBdf2,
                max_steps: opts.max_steps.saturating_sub(steps),
                ..*opts
            };
            let rest_of = wanted.after(delivered);
            match segment_once(system, &y, t, b, last, &rest_of, &rest, out, warm)? {
                Outcome::Reached(y) | Outcome::Unresolved(y) => Ok(Some(y)),
                Outcome::Stopped => Ok(None),
                Outcome::Stalled { .. } => Err(SimError::TooManySteps {
                    from: a,
                    to: b,
                    time: t,
                    max_steps: opts.max_steps,
                }),
            }
        }
    }
}

/// How far apart, in units in the last place of their time, two ends of an unresolved segment may be without a
/// note: breakpoints that differ by rounding (`0.3` and `0.1 + 0.2`).
const UNRESOLVED_ULPS: f64 = 1e3;

/// How one solver's integration of a segment ended.
enum Outcome {
    /// At the segment's end, with the extended state there.
    Reached(Vec<f64>),
    /// The segment is shorter than the solver resolves at its start: the state at its end is the state at its
    /// start.
    Unresolved(Vec<f64>),
    /// The receiver stopped the run.
    Stopped,
    /// BDF advanced too slowly to finish within its step budget ([`Drive::stalled`]): at `t` with the state `y`,
    /// after `steps` steps and `delivered` of the wanted rows.
    Stalled {
        t: f64,
        y: Vec<f64>,
        delivered: usize,
        steps: usize,
    },
}

#[allow(clippy::too_many_arguments)]
fn segment_once(
    system: &System,
    y0: &[f64],
    a: f64,
    b: f64,
    last: bool,
    wanted: &Wanted,
    opts: &RunOptions,
    out: &mut Deliver<'_>,
    warm: &[f64],
) -> Result<Outcome, SimError> {
    let dim = y0.len();
    // Inputs are evaluated before a breakpoint `b`, never at it (see the module docs).
    let t_max = if last { f64::INFINITY } else { just_before(b) };
    // The inputs' vector keeps the loops' last solution in its tear slots, from which the next solve starts.
    let scratch = RefCell::new((warm.to_vec(), Vec::new(), vec![0.0; dim], vec![0.0; dim]));
    let bad: RefCell<Option<FirstBad>> = RefCell::new(None);
    // The latest failure of the algebraic loops' solve at a finite state, reported if the solver then gives up (it
    // may recover from a failed trial step; evaluations at the non-finite states a failed step leads to are
    // consequences, not causes).
    let loop_failure: RefCell<Option<SimError>> = RefCell::new(None);
    let evaluate = |y: &[f64], u: &mut Vec<f64>, t: f64, dy: &mut [f64], stack: &mut Vec<f64>| {
        system.inputs_at(t.min(t_max), u);
        if let Err(e) = system.rhs(y, u, t, dy, stack) {
            dy.iter_mut().for_each(|d| *d = f64::NAN);
            if y.iter().all(|v| v.is_finite()) {
                *loop_failure.borrow_mut() = Some(e);
            }
        }
    };
    let rhs = |y: &[f64], _p: &[f64], t: f64, dy: &mut [f64]| {
        let mut s = scratch.borrow_mut();
        let (u, stack, _, _) = &mut *s;
        evaluate(y, u, t, dy, stack);
        if bad.borrow().is_none()
            && let Some(index) = dy.iter().position(|v| !v.is_finite())
        {
            *bad.borrow_mut() = Some(FirstBad {
                time: t,
                index,
                y: y.to_vec(),
            });
        }
    };
    let jac = |y: &[f64], _p: &[f64], t: f64, v: &[f64], jv: &mut [f64]| {
        let mut s = scratch.borrow_mut();
        let (u, stack, f0, f1) = &mut *s;
        system.inputs_at(t.min(t_max), u);
        if system.jacobian_times(y, u, t, v, jv, stack).is_some() {
            return;
        }
        // Finite differences along v.
        let norm_v = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if norm_v == 0.0 {
            jv.iter_mut().for_each(|x| *x = 0.0);
            return;
        }
        let norm_y = y.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let h = f64::EPSILON.sqrt() * (1.0 + norm_y) / norm_v;
        let shifted: Vec<f64> = y.iter().zip(v).map(|(y, v)| y + h * v).collect();
        evaluate(y, u, t, f0, stack);
        evaluate(&shifted, u, t, f1, stack);
        for ((j, a), b) in jv.iter_mut().zip(f0.iter()).zip(f1.iter()) {
            *j = (b - a) / h;
        }
    };
    let ctx = Drive {
        system,
        bad: &bad,
        loop_failure: &loop_failure,
        from: a,
        to: b,
        wanted,
        max_steps: opts.max_steps,
        max_step: opts.max_step,
        method: opts.method,
    };
    if let Some(full) = system.jacobian_pattern().filter(|_| dim >= SPARSE_FROM) {
        // The rows of the energy quadratures (dissipated, supplied) are left out of the sparse Jacobian: a
        // dissipation summed over every resistor is a dense row, and with it the sparse LU fills in (a 20,000-state
        // chain took 205 s instead of 3 s). Nothing reads those states, so Newton's iteration still converges.
        // The pattern runs row by row, so the model's rows are its first entries, and the values are evaluated
        // for those alone.
        let model = system.state_count();
        let pattern: Vec<(usize, usize)> =
            full.into_iter().take_while(|&(r, _)| r < model).collect();
        let rates = |y: &[f64], t: f64, dy: &mut [f64]| rhs(y, &[], t, dy);
        let values = |y: &[f64], t: f64, out: &mut [f64]| {
            let mut s = scratch.borrow_mut();
            let (u, stack, _, _) = &mut *s;
            system.inputs_at(t.min(t_max), u);
            if system.jacobian_values(y, u, t, out, stack).is_none() {
                out.iter_mut().for_each(|v| *v = f64::NAN);
            }
        };
        let ode = SparseOde::new(&rates, &values, y0, &pattern)
            .map_err(|message| SimError::Solver { time: a, message })?;
        let mut problem = OdeBuilder::<FaerSparseMat<f64>>::new()
            .t0(a)
            .rtol(opts.rtol)
            .atol([opts.atol])
            .build_from_eqn(ode)
            .map_err(|e| solver_error(a, e))?;
        problem.ode_options.max_nonlinear_solver_failures = opts.max_steps;
        return run_method!(&problem, FaerSparseLU<f64>, opts.method, &ctx, out);
    }
    let init_state = y0.to_vec();
    let init = move |_p: &[f64], _t: f64, y: &mut [f64]| {
        for (d, s) in y.iter_mut().zip(&init_state) {
            *d = *s;
        }
    };
    let mut problem = OdeBuilder::<M>::new()
        .t0(a)
        .rtol(opts.rtol)
        .atol([opts.atol])
        .rhs_implicit(rhs, jac)
        .init(init, dim)
        .build()
        .map_err(|e| solver_error(a, e))?;
    // diffsol counts the failed Newton iterations of a whole run, not in a row, and gives up after 50 by default:
    // each is a normal event (a stale Jacobian, a step too long) that it recovers from by refreshing the Jacobian
    // or cutting the step, so a long run of a linear oscillator failed at t ≈ 600 (BDF) or 118 (ESDIRK34). A run
    // that really cannot go on still ends: the step becomes too small, or `max_steps` is reached.
    problem.ode_options.max_nonlinear_solver_failures = opts.max_steps;
    run_method!(&problem, Ls, opts.method, &ctx, out)
}

/// Drives `problem` with the chosen method and the linear solver `$ls` of the implicit ones. A macro: the
/// methods' bounds on the problem's vector and matrix types are diffsol's and too many to restate generically.
macro_rules! run_method {
    ($problem:expr, $ls:ty, $method:expr, $ctx:expr, $out:expr) => {{
        let (problem, ctx, a) = ($problem, $ctx, $ctx.from);
        match $method {
            Method::Bdf => {
                let s = problem.bdf::<$ls>().map_err(|e| ctx.failure(a, e))?;
                ctx.drive(s, $out)
            }
            Method::Esdirk34 => {
                let s = problem.esdirk34::<$ls>().map_err(|e| ctx.failure(a, e))?;
                ctx.drive(s, $out)
            }
            Method::TrBdf2 => {
                let s = problem.tr_bdf2::<$ls>().map_err(|e| ctx.failure(a, e))?;
                ctx.drive(s, $out)
            }
            Method::Tsit45 => {
                let s = problem.tsit45().map_err(|e| ctx.failure(a, e))?;
                ctx.drive(s, $out)
            }
        }
    }};
}
use run_method;

/// The latest time before the breakpoint `b` at which the inputs are evaluated in the segment that ends there.
fn just_before(b: f64) -> f64 {
    b - b.abs() * 4.0 * f64::EPSILON
}

/// What to try when the explicit method advances too slowly.
const STIFF_FOR_EXPLICIT: &str =
    "a stiff or fast-forced model: try --solver bdf, or looser tolerances";
/// What to try when an implicit method advances too slowly.
const SMOOTHER_LAW: &str = "a law with a near-discontinuity, such as a friction regularised over a tiny velocity, \
                            or a fast forcing: smooth the law, loosen the tolerances or shorten the run";

/// The first evaluation whose derivative was not finite: its time, the state whose derivative it was, and the
/// point.
struct FirstBad {
    time: f64,
    index: usize,
    y: Vec<f64>,
}

struct Drive<'c> {
    system: &'c System,
    bad: &'c RefCell<Option<FirstBad>>,
    loop_failure: &'c RefCell<Option<SimError>>,
    from: f64,
    to: f64,
    wanted: &'c Wanted,
    max_steps: usize,
    max_step: Option<f64>,
    /// What a stall ([`Drive::stalled`]) does: BDF ends the drive with [`Outcome::Stalled`] and goes on with
    /// TR-BDF2; the explicit method, whose step a stiff mode or a fast forcing holds short for the rest of the run,
    /// ends it with [`SimError::TooSlow`]. An implicit one-step method's slow start may be a transient it leaves
    /// behind (TR-BDF2 after BDF's stall on the stiff oscillator), so its pace is judged over a hundredth of the
    /// budget ([`ONE_STEP_STALL_SHARE`]) before a stall ends it with [`SimError::TooSlow`] too.
    method: Method,
}

/// The steps between two looks at BDF's progress.
const STALL_WINDOW: usize = 10_000;
/// The share of the step budget between two looks at the progress of the implicit one-step methods (100,000 steps
/// of the CLI's 10,000,000): ten times BDF's window there, so that a slow start they leave behind (TR-BDF2 after
/// BDF's stall on a stiff oscillator) is not judged by its first steps.
const ONE_STEP_STALL_SHARE: usize = 100;

impl Drive<'_> {
    fn name(&self, i: usize) -> String {
        match i.checked_sub(self.system.state_count()) {
            None => self.system.states.get(i).cloned().unwrap_or_default(),
            Some(0) => "dissipated".into(),
            Some(_) => "supplied".into(),
        }
    }

    /// Whether the last [`STALL_WINDOW`] steps, from `window_start` to `t_now`, went so slowly that the rest of the
    /// segment at that pace needs more steps than are left of `max_steps`: the run would fail. BDF does so when a
    /// lightly damped fast mode (eigenvalues near the imaginary axis) lies outside the stability region of its
    /// orders 3 to 5 and the tolerances resolve it: the error test holds the spurious growth at the tolerance by
    /// cutting the step to a fraction of that mode's period, for the rest of the run.
    fn stalled(&self, window_start: f64, t_now: f64, steps: usize, window: usize) -> bool {
        let pace = (t_now - window_start) / window as f64;
        let left = self.max_steps.saturating_sub(steps) as f64;
        !(pace > 0.0 && (self.to - t_now) / pace <= left)
    }

    /// A `max_step` shorter than the solver resolves of time where the run is.
    fn step_below_resolution(&self) -> SimError {
        SimError::BadSetting {
            name: "max_step",
            value: self.max_step.unwrap_or(f64::NAN),
            reason: "it is shorter than the solver resolves of time at this point of the run (about 1e-14 of the \
                     time): give a longer one",
        }
    }

    /// The time the solver may step to from `t`: the segment's end, or `t + max_step` when that comes first.
    fn cap_after(&self, t: f64) -> f64 {
        match self.max_step {
            Some(h) if t + h < self.to => t + h,
            _ => self.to,
        }
    }

    fn too_slow(&self, time: f64, steps: usize, hint: &'static str) -> SimError {
        SimError::TooSlow {
            from: self.from,
            to: self.to,
            time,
            steps,
            max_steps: self.max_steps,
            hint,
        }
    }

    /// The first derivative that was not finite: because an input signal was not, or a mass matrix was singular
    /// there, when one was.
    fn non_finite_derivative(&self, bad: &FirstBad) -> SimError {
        let time = bad.time;
        if let Some(input) = self.system.non_finite_input(time) {
            return input;
        }
        if let Some(element) = self.system.singular_mass(&bad.y, time, bad.index) {
            return SimError::SingularMass { time, element };
        }
        SimError::NonFiniteDerivative {
            time,
            state: self.name(bad.index),
        }
    }

    /// A solver error, attributed to the model when its algebraic loops could not be solved or it had returned a
    /// non-finite derivative.
    fn failure(&self, time: f64, e: DiffsolError) -> SimError {
        if let Some(loop_error) = self.loop_failure.borrow().clone() {
            return loop_error;
        }
        match &*self.bad.borrow() {
            Some(bad) => self.non_finite_derivative(bad),
            None => solver_error(time, e),
        }
    }

    fn drive<'a, Eqn, S>(&self, mut solver: S, out: &mut Deliver<'_>) -> Result<Outcome, SimError>
    where
        Eqn: OdeEquations<T = f64> + 'a,
        S: OdeSolverMethod<'a, Eqn>,
    {
        let mut cap = self.cap_after(self.from);
        match solver.set_stop_time(cap) {
            Ok(()) => {}
            Err(DiffsolError::OdeSolverError(OdeSolverError::StopTimeAtCurrentTime))
                if cap < self.to =>
            {
                return Err(self.step_below_resolution());
            }
            // The segment is shorter than the solver's resolution of time at its start: two breakpoints that differ
            // by rounding (`step(0.3) + step(0.1 + 0.2)`) or a run of 1e-20 s. Integrating over it changes nothing
            // to rounding, so the state goes on unchanged (this failed the run before).
            Err(DiffsolError::OdeSolverError(OdeSolverError::StopTimeAtCurrentTime)) => {
                let y = solver.state().y.clone_as_vec();
                let mut next = 0;
                while let Some(t) = self.wanted.get(next) {
                    if out(t, &y)?.is_break() {
                        return Ok(Outcome::Stopped);
                    }
                    next += 1;
                }
                return Ok(Outcome::Unresolved(y));
            }
            Err(e) => return Err(self.failure(self.from, e)),
        }
        let mut next = 0;
        let mut window_start = self.from;
        let mut long_window_start = self.from;
        let long_window = (self.max_steps / ONE_STEP_STALL_SHARE).max(1);
        let one_step = matches!(self.method, Method::TrBdf2 | Method::Esdirk34);
        for step in 0..self.max_steps {
            let mut reason = solver
                .step()
                .map_err(|e| self.failure(solver.state().t, e))?;
            let t_now = solver.state().t;
            if matches!(reason, OdeSolverStopReason::TstopReached) && cap < self.to {
                // A cap of the step, not the segment's end: the next cap, or the end when it is within the
                // solver's resolution of time from here.
                cap = self.cap_after(t_now);
                match solver.set_stop_time(cap) {
                    Ok(()) => reason = OdeSolverStopReason::InternalTimestep,
                    Err(DiffsolError::OdeSolverError(OdeSolverError::StopTimeAtCurrentTime))
                        if cap >= self.to => {}
                    Err(DiffsolError::OdeSolverError(OdeSolverError::StopTimeAtCurrentTime)) => {
                        return Err(self.step_below_resolution());
                    }
                    Err(e) => return Err(self.failure(t_now, e)),
                }
            }
            let y = solver.state().y.clone_as_vec();
            if let Some(i) = y.iter().position(|v| !v.is_finite()) {
                if let Some(loop_error) = self.loop_failure.borrow().clone() {
                    return Err(loop_error);
                }
                return Err(match &*self.bad.borrow() {
                    Some(bad) => self.non_finite_derivative(bad),
                    None => SimError::NonFiniteState {
                        time: t_now,
                        state: self.name(i),
                    },
                });
            }
            let reached = matches!(reason, OdeSolverStopReason::TstopReached);
            while let Some(t) = self.wanted.get(next) {
                let flow = if reached && t >= self.to {
                    out(t, &y)?
                } else if t <= t_now {
                    let v = solver.interpolate(t).map_err(|e| self.failure(t, e))?;
                    out(t, &v.clone_as_vec())?
                } else {
                    break;
                };
                if flow.is_break() {
                    return Ok(Outcome::Stopped);
                }
                next += 1;
            }
            if reached {
                return Ok(Outcome::Reached(y));
            }
            if one_step && (step + 1) % long_window == 0 {
                // A law that is nearly discontinuous (a friction regularised over 1e-9 rad/s) holds every method's
                // step short for good: minutes of work before the budget runs out.
                if self.stalled(long_window_start, t_now, step + 1, long_window) {
                    return Err(self.too_slow(t_now, step + 1, SMOOTHER_LAW));
                }
                long_window_start = t_now;
            }
            if (step + 1) % STALL_WINDOW == 0 {
                let stalled = self.stalled(window_start, t_now, step + 1, STALL_WINDOW);
                match self.method {
                    Method::Bdf if stalled => {
                        return Ok(Outcome::Stalled {
                            t: t_now,
                            y,
                            delivered: next,
                            steps: step + 1,
                        });
                    }
                    // It would spend the whole step budget (minutes) before failing.
                    Method::Tsit45 if stalled => {
                        return Err(self.too_slow(t_now, step + 1, STIFF_FOR_EXPLICIT));
                    }
                    _ => {}
                }
                window_start = t_now;
            }
        }
        Err(SimError::TooManySteps {
            from: self.from,
            to: self.to,
            time: solver.state().t,
            max_steps: self.max_steps,
        })
    }
}

fn solver_error(time: f64, e: DiffsolError) -> SimError {
    SimError::Solver {
        time,
        message: e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(t_end: f64, dt_out: f64) -> RunOptions {
        RunOptions {
            t_end,
            dt_out,
            method: Method::Bdf,
            rtol: 1e-6,
            atol: 1e-9,
            max_steps: 1000,
            max_step: None,
        }
    }

    #[test]
    fn samples_end_exactly_at_t_end() {
        assert_eq!(
            opts(1.0, 0.3).sample_times(),
            [0.0, 0.3, 0.6, 0.8999999999999999, 1.0]
        );
        let t = opts(1.0, 0.1).sample_times();
        assert_eq!(t.len(), 11);
        assert_eq!(t.last(), Some(&1.0));
        assert_eq!(opts(1.0, 5.0).sample_times(), [0.0, 1.0]);
    }

    #[test]
    fn settings_are_checked() {
        assert!(opts(1.0, 0.1).check().is_ok());
        for bad in [
            opts(0.0, 0.1),
            opts(1.0, -0.1),
            opts(f64::NAN, 0.1),
            opts(f64::INFINITY, 0.1),
        ] {
            assert!(
                matches!(bad.check(), Err(SimError::BadSetting { .. })),
                "{bad:?}"
            );
        }
        assert!(matches!(
            opts(1.0, 1e-12).check(),
            Err(SimError::TooManyRows { .. })
        ));
    }
}
