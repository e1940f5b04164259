//! One integration segment of a [`ContinuousModel`] on diffsol.
//!
//! The segment solves `ẋ = f(t, x, u(t)) + w` from `(t0, x0)` to `t_end` with the chosen method, reporting the
//! state at requested times inside the segment by the solver's own dense output (Hermite/Nordsieck
//! interpolation of the accepted steps, of the method's order). The Jacobian handed to the implicit methods
//! is the model's `jac_x`, evaluated once per point at which the solver assembles it. A fresh solver is started for each segment, so an input that jumps at the segment
//! boundary (a zero-order hold) never enters an implicit method's step history.

use std::cell::{Cell, RefCell};

use diffsol::error::DiffsolError;
use diffsol::{
    NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeEquations, OdeSolverMethod,
    OdeSolverStopReason,
};
use nalgebra::{SMatrix, SVector};

use super::error::SimError;
pub use super::options::{Method, SolverOptions};
use crate::model::ContinuousModel;

type M = NalgebraMat<f64>;
type Ls = NalgebraLU<f64>;

/// The model's Jacobian `∂f/∂x` and the point `(t, x)` it was evaluated at, kept for the next column product.
struct JacobianAt<const NX: usize> {
    at: Option<(f64, SVector<f64, NX>)>,
    matrix: Box<SMatrix<f64, NX, NX>>,
}

/// `jv = J v`. diffsol asks for the columns of a dense Jacobian one at a time (`v` a unit vector): then the
/// product is the column itself, `NX` copies instead of `NX²` multiply-adds per column.
fn jacobian_product<const NX: usize>(j: &SMatrix<f64, NX, NX>, v: &[f64], jv: &mut [f64]) {
    let mut nonzero = v.iter().enumerate().filter(|(_, c)| **c != 0.0);
    if let (Some((col, &1.0)), None) = (nonzero.next(), nonzero.next()) {
        jv.copy_from_slice(j.column(col).as_slice());
        return;
    }
    jv.copy_from_slice((j * SVector::<f64, NX>::from_column_slice(v)).as_slice());
}

/// A segment to integrate.
pub(crate) struct Segment<'a, const NX: usize> {
    pub t0: f64,
    pub t_end: f64,
    pub x0: &'a SVector<f64, NX>,
    /// Added to the model's derivative over the whole segment (a held process disturbance).
    pub disturbance: &'a SVector<f64, NX>,
    /// Times in `(t0, t_end]`, increasing, at which the state is wanted.
    pub output_times: &'a [f64],
}

/// Integrates one segment; returns the state at `t_end` and pushes the states at `output_times` to `out`.
///
/// Only the model's side is generic: the rates and the Jacobian-vector product are handed on as trait objects
/// over slices, so diffsol's four solvers are compiled once, in this crate, and not again for every model type
/// and input closure of every crate that simulates.
pub(crate) fn integrate_segment<Mdl, U, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    input: U,
    seg: &Segment<'_, NX>,
    opts: &SolverOptions,
    out: &mut Vec<SVector<f64, NX>>,
) -> Result<SVector<f64, NX>, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    U: Fn(f64) -> SVector<f64, NU>,
{
    if NX == 0 {
        // Nothing to integrate: a model without states only maps inputs to outputs.
        out.extend(seg.output_times.iter().map(|_| *seg.x0));
        return Ok(*seg.x0);
    }
    // The first non-finite derivative seen by the solver, reported if the solver then fails.
    let bad_derivative: Cell<Option<(f64, usize)>> = Cell::new(None);
    let rhs = |x: &[f64], t: f64, dx: &mut [f64]| {
        let xs = SVector::<f64, NX>::from_column_slice(x);
        let mut d = SVector::<f64, NX>::zeros();
        model.rhs(t, &xs, &input(t), &mut d);
        d += seg.disturbance;
        if bad_derivative.get().is_none()
            && let Some(i) = d.iter().position(|v| !v.is_finite())
        {
            bad_derivative.set(Some((t, i)));
        }
        dx.copy_from_slice(d.as_slice());
    };
    // diffsol assembles its Jacobian from one product per column, all at the same point: the model's
    // Jacobian is evaluated once per point, in place, and reused for the other columns. It lives on the heap
    // (allocated zeroed, never built on the stack): an `NX × NX` matrix takes 8 MB at 1,000 states.
    let cached: RefCell<JacobianAt<NX>> = RefCell::new(JacobianAt {
        at: None,
        matrix: bytemuck::zeroed_box(),
    });
    let jac = |x: &[f64], t: f64, v: &[f64], jv: &mut [f64]| {
        let xs = SVector::<f64, NX>::from_column_slice(x);
        let mut cache = cached.borrow_mut();
        let cache = &mut *cache;
        if cache.at.as_ref() != Some(&(t, xs)) {
            model.jac_x(t, &xs, &input(t), &mut cache.matrix);
            cache.at = Some((t, xs));
        }
        jacobian_product(&cache.matrix, v, jv);
    };
    let erased = ErasedSegment {
        t0: seg.t0,
        t_end: seg.t_end,
        x0: seg.x0.as_slice(),
        output_times: seg.output_times,
    };
    let mut push = |y: &[f64]| out.push(SVector::<f64, NX>::from_column_slice(y));
    let end = integrate_erased(&rhs, &jac, &erased, opts, &bad_derivative, &mut push)?;
    Ok(SVector::<f64, NX>::from_column_slice(&end))
}

/// `ẋ = f(x, t)` written into the last argument.
type Rates<'a> = dyn Fn(&[f64], f64, &mut [f64]) + 'a;
/// `(∂f/∂x) v` at `(x, t)` written into the last argument.
type JacobianProduct<'a> = dyn Fn(&[f64], f64, &[f64], &mut [f64]) + 'a;
/// Receives the state at each output time.
type Sink<'a> = dyn FnMut(&[f64]) + 'a;

/// [`Segment`] as slices.
struct ErasedSegment<'a> {
    t0: f64,
    t_end: f64,
    x0: &'a [f64],
    output_times: &'a [f64],
}

/// The segment on diffsol, for any model: see [`integrate_segment`].
fn integrate_erased(
    rhs: &Rates<'_>,
    jac: &JacobianProduct<'_>,
    seg: &ErasedSegment<'_>,
    opts: &SolverOptions,
    bad_derivative: &Cell<Option<(f64, usize)>>,
    out: &mut Sink<'_>,
) -> Result<Vec<f64>, SimError> {
    let n = seg.x0.len();
    let problem = OdeBuilder::<M>::new()
        .t0(seg.t0)
        .rtol(opts.rtol)
        .atol([opts.atol])
        .rhs_implicit(
            |x: &[f64], _p: &[f64], t: f64, dx: &mut [f64]| rhs(x, t, dx),
            |x: &[f64], _p: &[f64], t: f64, v: &[f64], jv: &mut [f64]| jac(x, t, v, jv),
        )
        .init(
            |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(seg.x0),
            n,
        )
        .build()
        .map_err(|e| solver_error(seg.t0, e))?;
    let failure = |time: f64, e: DiffsolError| failure_cause(bad_derivative, time, e);
    match opts.method {
        Method::Bdf => {
            let solver = problem.bdf::<Ls>().map_err(|e| failure(seg.t0, e))?;
            drive(solver, seg, opts, out, bad_derivative)
        }
        Method::Esdirk34 => {
            let solver = problem.esdirk34::<Ls>().map_err(|e| failure(seg.t0, e))?;
            drive(solver, seg, opts, out, bad_derivative)
        }
        Method::TrBdf2 => {
            let solver = problem.tr_bdf2::<Ls>().map_err(|e| failure(seg.t0, e))?;
            drive(solver, seg, opts, out, bad_derivative)
        }
        Method::Tsit45 => {
            let solver = problem.tsit45().map_err(|e| failure(seg.t0, e))?;
            drive(solver, seg, opts, out, bad_derivative)
        }
    }
}

fn drive<'a, Eqn, S>(
    mut solver: S,
    seg: &ErasedSegment<'_>,
    opts: &SolverOptions,
    out: &mut Sink<'_>,
    bad_derivative: &Cell<Option<(f64, usize)>>,
) -> Result<Vec<f64>, SimError>
where
    Eqn: OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    let failure = |time: f64, e: DiffsolError| failure_cause(bad_derivative, time, e);
    solver
        .set_stop_time(seg.t_end)
        .map_err(|e| failure(seg.t0, e))?;
    let mut next_output = 0;
    for _ in 0..opts.max_steps {
        let reason = solver.step().map_err(|e| failure(solver.state().t, e))?;
        let t_now = solver.state().t;
        // An unbatched vector is its batch 0.
        let y = solver.state().y.batch_as_slice(0);
        if let Some(index) = y.iter().position(|v| !v.is_finite()) {
            // Prefer the cause (the first non-finite derivative) over the symptom when it is known.
            return Err(match bad_derivative.get() {
                Some((time, index)) => SimError::NonFiniteDerivative { time, index },
                None => SimError::NonFiniteState { time: t_now, index },
            });
        }
        let reached = matches!(reason, OdeSolverStopReason::TstopReached);
        while let Some(&t) = seg.output_times.get(next_output) {
            if reached && t >= seg.t_end {
                out(y);
            } else if t <= t_now {
                let v = solver.interpolate(t).map_err(|e| failure(t, e))?;
                out(v.batch_as_slice(0));
            } else {
                break;
            }
            next_output += 1;
        }
        if reached {
            return Ok(y.to_vec());
        }
    }
    Err(SimError::TooManySteps {
        from: seg.t0,
        to: seg.t_end,
        time: solver.state().t,
        max_steps: opts.max_steps,
    })
}

/// A solver error, attributed to the model when it had returned a non-finite derivative.
fn failure_cause(
    bad_derivative: &Cell<Option<(f64, usize)>>,
    time: f64,
    e: DiffsolError,
) -> SimError {
    match bad_derivative.get() {
        Some((time, index)) => SimError::NonFiniteDerivative { time, index },
        None => solver_error(time, e),
    }
}

fn solver_error(time: f64, e: DiffsolError) -> SimError {
    SimError::Solver {
        time,
        message: e.to_string(),
    }
}
