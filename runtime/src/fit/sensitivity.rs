//! The simulated outputs of a model over a record and their derivatives with respect to the fitted quantities,
//! by forward sensitivities.
//!
//! With `S = ∂x/∂θ`, the sensitivities obey `Ṡ = ∂f/∂x S + ∂f/∂θ` with `S(0) = ∂x₀/∂θ` (zero for a parameter, a
//! unit column for a fitted initial state), and the outputs' derivatives are `∂y/∂θ = ∂h/∂x S + ∂h/∂θ`. The states
//! and the sensitivities are integrated together, so the solver's error control covers both. Each column `j` is
//! integrated scaled by `scale[j]` (the derivative of the quantity with respect to the optimiser's coordinate:
//! the quantity itself for one fitted in log space), which keeps the columns of similar size. A held input
//! that changes ends an integration segment; the next starts a fresh solver.

use std::cell::RefCell;

use diffsol::error::DiffsolError;
use diffsol::{
    NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeEquations, OdeSolverMethod,
    OdeSolverStopReason, Vector,
};
use nalgebra::DMatrix;

use super::record::{Interp, Record};
use crate::sim::{Method, SolverOptions};

type M = NalgebraMat<f64>;
type Ls = NalgebraLU<f64>;

/// `∂f/∂x` at `(t, x)`, kept for the other column products diffsol takes at the same point.
type JacobianAt = (f64, Vec<f64>, DMatrix<f64>);

/// A model the fit can simulate: sizes known at run time, parameters set by index, and the Jacobians with
/// respect to the states and the parameters. The interpreted models of the `bgc` CLI and the generated models
/// (through [`super::generated::Generated`]) implement it.
pub trait FitModel {
    fn state_count(&self) -> usize;
    fn input_count(&self) -> usize;
    fn output_count(&self) -> usize;
    fn param_count(&self) -> usize;
    /// Sets all parameter values (in the model's order); a refused value is an error naming it.
    fn set_params(&mut self, p: &[f64]) -> Result<(), String>;
    /// The rates `f(t, x, u)` at the current parameters.
    fn rhs(&self, t: f64, x: &[f64], u: &[f64], dx: &mut [f64]) -> Result<(), String>;
    /// The outputs `h(t, x, u)`.
    fn outputs(&self, t: f64, x: &[f64], u: &[f64], y: &mut [f64]) -> Result<(), String>;
    /// `(∂f/∂x, ∂f/∂p)` with the columns of `∂f/∂p` for the parameters `free` (indices into the parameters).
    fn rate_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String>;
    /// `(∂h/∂x, ∂h/∂p)` likewise.
    fn output_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String>;

    /// True when the rates are affine in the states and inputs with constant coefficients (a linear
    /// time-invariant model): a fit with held inputs then takes the exact discretisation of
    /// [`super::linear`] instead of the ODE solver. The declaration is checked at a probe point.
    fn is_linear(&self) -> bool {
        false
    }
}

/// What is fitted: parameter indices, then initial-state indices, each with its column scale.
#[derive(Clone, Debug)]
pub struct Fitted<'a> {
    pub params: &'a [usize],
    pub x0: &'a [usize],
    /// One per fitted quantity (parameters first).
    pub scale: &'a [f64],
}

/// The simulated outputs at the record's samples and, per sample, `∂y/∂θ` (outputs × fitted, scaled columns).
#[derive(Clone, Debug)]
pub struct Simulated {
    pub outputs: Vec<Vec<f64>>,
    pub jacobians: Vec<DMatrix<f64>>,
}

/// Why a simulation over the record failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    #[error("the model failed at t = {time:?}: {message}")]
    Model { time: f64, message: String },
    #[error("the ODE solver failed at t = {time:?}: {message}")]
    Solver { time: f64, message: String },
    #[error("the simulation became non-finite at t = {time:?}")]
    NonFinite { time: f64 },
    #[error("more than {max_steps} solver steps before t = {time:?}")]
    TooManySteps { time: f64, max_steps: usize },
}

/// Integrates states and sensitivities from `x0` at the record's first time and samples the outputs.
pub fn simulate(
    model: &dyn FitModel,
    record: &Record,
    interp: Interp,
    x0: &[f64],
    fitted: &Fitted<'_>,
    opts: &SolverOptions,
) -> Result<Simulated, SensitivityError> {
    let nx = model.state_count();
    let m = fitted.params.len() + fitted.x0.len();
    let mut y = vec![0.0; nx * (1 + m)];
    y[..nx].copy_from_slice(x0);
    for (k, &i) in fitted.x0.iter().enumerate() {
        let j = fitted.params.len() + k;
        y[nx * (1 + j) + i] = fitted.scale[j];
    }
    let mut states = vec![y.clone()];
    let mut start = 0;
    for end in record.segment_ends(interp) {
        let seg = Segment {
            model,
            record,
            interp,
            fitted,
            from: start,
            to: end,
        };
        y = seg.integrate(&y, opts, &mut states)?;
        start = end;
    }
    sample_outputs(model, record, interp, fitted, &states)
}

/// The outputs and their sensitivities from the augmented states at each sample.
pub(super) fn sample_outputs(
    model: &dyn FitModel,
    record: &Record,
    interp: Interp,
    fitted: &Fitted<'_>,
    states: &[Vec<f64>],
) -> Result<Simulated, SensitivityError> {
    let (nx, ny) = (model.state_count(), model.output_count());
    let np = fitted.params.len();
    let m = np + fitted.x0.len();
    let mut u = vec![0.0; model.input_count()];
    let mut out = Simulated {
        outputs: Vec::with_capacity(states.len()),
        jacobians: Vec::with_capacity(states.len()),
    };
    for (&t, y) in record.times.iter().zip(states) {
        if !record.input_at(interp, t, &mut u) {
            // Not reached: `fit` checks the record's width against the model, and its times are finite.
            u.fill(f64::NAN);
        }
        let x = &y[..nx];
        let mut h = vec![0.0; ny];
        let fail = |message| SensitivityError::Model { time: t, message };
        model.outputs(t, x, &u, &mut h).map_err(fail)?;
        let (hx, hp) = model
            .output_jacobians(t, x, &u, fitted.params)
            .map_err(fail)?;
        let s = DMatrix::from_column_slice(nx, m, &y[nx..]);
        let mut jac = hx * s;
        for j in 0..np {
            let mut col = jac.column_mut(j);
            col.axpy(fitted.scale[j], &hp.column(j), 1.0);
        }
        if h.iter().chain(jac.iter()).any(|v| !v.is_finite()) {
            return Err(SensitivityError::NonFinite { time: t });
        }
        out.outputs.push(h);
        out.jacobians.push(jac);
    }
    Ok(out)
}

/// The samples `from..=to` of the record, integrated with one solver.
struct Segment<'a> {
    model: &'a dyn FitModel,
    record: &'a Record,
    interp: Interp,
    fitted: &'a Fitted<'a>,
    from: usize,
    to: usize,
}

impl Segment<'_> {
    /// The augmented rate `[f, ∂f/∂x S + ∂f/∂θ]` at `(t, y)`; the input is that of the segment's start for a hold.
    fn rate(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), String> {
        let model = self.model;
        let nx = model.state_count();
        let np = self.fitted.params.len();
        let m = np + self.fitted.x0.len();
        let u = self.input(t);
        let x = &y[..nx];
        model.rhs(t, x, &u, &mut dy[..nx])?;
        let (fx, fp) = model.rate_jacobians(t, x, &u, self.fitted.params)?;
        let s = DMatrix::from_column_slice(nx, m, &y[nx..]);
        let mut ds = &fx * s;
        for j in 0..np {
            ds.column_mut(j)
                .axpy(self.fitted.scale[j], &fp.column(j), 1.0);
        }
        dy[nx..].copy_from_slice(ds.as_slice());
        Ok(())
    }

    fn input(&self, t: f64) -> Vec<f64> {
        let mut u = vec![0.0; self.model.input_count()];
        match self.interp {
            // Within a segment the held input is that of its first sample (times just before its end included).
            Interp::Zoh => u.copy_from_slice(&self.record.inputs[self.from]),
            Interp::Linear => {
                if !self.record.input_at(self.interp, t, &mut u) {
                    // Not reached (as above); a NaN input fails the step with a located error.
                    u.fill(f64::NAN);
                }
            }
        }
        u
    }

    /// Integrates from the state `y0` at sample `from` to sample `to`, pushing the states at the samples after
    /// `from`.
    fn integrate(
        &self,
        y0: &[f64],
        opts: &SolverOptions,
        out: &mut Vec<Vec<f64>>,
    ) -> Result<Vec<f64>, SensitivityError> {
        let times = &self.record.times[self.from + 1..=self.to];
        let t0 = self.record.times[self.from];
        let t_end = self.record.times[self.to];
        let n = y0.len();
        let nx = self.model.state_count();
        let error: RefCell<Option<SensitivityError>> = RefCell::new(None);
        let rhs = |y: &[f64], _p: &[f64], t: f64, dy: &mut [f64]| {
            if let Err(message) = self.rate(t, y, dy) {
                dy.iter_mut().for_each(|v| *v = f64::NAN);
                error
                    .borrow_mut()
                    .get_or_insert(SensitivityError::Model { time: t, message });
            }
        };
        // Newton's matrix: ∂f/∂x on the diagonal blocks (the sensitivities' dependence on x through ∂f/∂x is
        // left out; it only slows the corrector's convergence, not the accuracy of accepted steps).
        let cache: RefCell<Option<JacobianAt>> = RefCell::new(None);
        let jac = |y: &[f64], _p: &[f64], t: f64, v: &[f64], jv: &mut [f64]| {
            let mut c = cache.borrow_mut();
            let fresh = !matches!(&*c, Some((tc, xc, _)) if *tc == t && xc[..] == y[..nx]);
            if fresh {
                let u = self.input(t);
                match self.model.rate_jacobians(t, &y[..nx], &u, &[]) {
                    Ok((fx, _)) => *c = Some((t, y[..nx].to_vec(), fx)),
                    Err(_) => {
                        jv.iter_mut().for_each(|v| *v = f64::NAN);
                        return;
                    }
                }
            }
            if let Some((_, _, fx)) = &*c {
                for (block, out) in v.chunks(nx).zip(jv.chunks_mut(nx)) {
                    let prod = fx * nalgebra::DVector::from_column_slice(block);
                    out.copy_from_slice(prod.as_slice());
                }
            }
        };
        let start = y0.to_vec();
        let init = move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&start);
        let problem = OdeBuilder::<M>::new()
            .t0(t0)
            .rtol(opts.rtol)
            .atol([opts.atol])
            .rhs_implicit(rhs, jac)
            .init(init, n)
            .build()
            .map_err(|e| solver_error(t0, e))?;
        let failed = |time: f64, e: DiffsolError| {
            error
                .borrow_mut()
                .take()
                .unwrap_or_else(|| solver_error(time, e))
        };
        match opts.method {
            Method::Bdf => {
                let s = problem.bdf::<Ls>().map_err(|e| failed(t0, e))?;
                drive(s, t_end, times, opts, out, &failed)
            }
            Method::Esdirk34 => {
                let s = problem.esdirk34::<Ls>().map_err(|e| failed(t0, e))?;
                drive(s, t_end, times, opts, out, &failed)
            }
            Method::TrBdf2 => {
                let s = problem.tr_bdf2::<Ls>().map_err(|e| failed(t0, e))?;
                drive(s, t_end, times, opts, out, &failed)
            }
            Method::Tsit45 => {
                let s = problem.tsit45().map_err(|e| failed(t0, e))?;
                drive(s, t_end, times, opts, out, &failed)
            }
        }
    }
}

/// Steps `solver` to `t_end`, pushing the interpolated states at `times`.
fn drive<'a, Eqn, S>(
    mut solver: S,
    t_end: f64,
    times: &[f64],
    opts: &SolverOptions,
    out: &mut Vec<Vec<f64>>,
    failed: &dyn Fn(f64, DiffsolError) -> SensitivityError,
) -> Result<Vec<f64>, SensitivityError>
where
    Eqn: OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    let t0 = solver.state().t;
    solver.set_stop_time(t_end).map_err(|e| failed(t0, e))?;
    let mut next = 0;
    for _ in 0..opts.max_steps {
        let reason = solver.step().map_err(|e| failed(solver.state().t, e))?;
        let t_now = solver.state().t;
        let y: Vec<f64> = solver.state().y.clone_as_vec();
        if y.iter().any(|v| !v.is_finite()) {
            return Err(SensitivityError::NonFinite { time: t_now });
        }
        let reached = matches!(reason, OdeSolverStopReason::TstopReached);
        while let Some(&t) = times.get(next) {
            if reached && t >= t_end {
                out.push(y.clone());
            } else if t <= t_now {
                let v = solver.interpolate(t).map_err(|e| failed(t, e))?;
                out.push(v.clone_as_vec());
            } else {
                break;
            }
            next += 1;
        }
        if reached {
            return Ok(y);
        }
    }
    Err(SensitivityError::TooManySteps {
        time: solver.state().t,
        max_steps: opts.max_steps,
    })
}

fn solver_error(time: f64, e: DiffsolError) -> SensitivityError {
    SensitivityError::Solver {
        time,
        message: e.to_string(),
    }
}
