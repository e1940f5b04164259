//! Sampled-data closed loop: a continuous plant, a discrete controller (with its observer) at a fixed
//! sample time, zero-order-hold inputs.
//!
//! With `T` the sample time and `t_k = t0 + k T`, each sample `k = 0, 1, …, N−1`:
//! 1. measures `y_k = h(t_k, x(t_k), u_{k−1}) + v_k`, `v_k ~ N(0, diag(σ_v²))` (with `u_{−1}` the configured
//!    initial input, since `u_k` is not known before the controller has seen `y_k`);
//! 2. hands the controller the measurement `d` samples old, `y_{k−d}` (`y_0` while `k < d`), and receives
//!    `u_k`;
//! 3. integrates `ẋ = f(t, x, u_k) + w_k` over `[t_k, t_{k+1}]`, where `w_k ~ N(0, diag(σ_w²))` is a process
//!    disturbance held constant over the interval like the input. (Over one interval it adds a state
//!    increment of covariance ≈ `T² diag(σ_w²)` for a slow plant.)
//!
//! and a last measurement `y_N` is taken at `t_N`. Noise is drawn from one seeded [`Rng`] in a fixed order —
//! at each sample first the `NY` measurement noises, then the `NX` process noises — so a run is repeatable
//! from its seed. Zero standard deviations draw nothing.
//!
//! Step 3 is an ODE solve of the model for [`simulate_sampled_loop`] (any plant, also nonlinear), and the exact
//! zero-order-hold step of [`super::linear`] for [`simulate_sampled_linear_loop`] (a [`LinearPlant`]). The
//! `_streaming` variants hand each sample to a sink instead of recording it, so a run's memory does not grow
//! with its length; the recording variants refuse runs whose record would exceed [`MAX_RECORD_BYTES`].

use std::collections::VecDeque;
use std::ops::ControlFlow;

use nalgebra::SVector;

use super::check_initial;
use super::error::SimError;
#[cfg(feature = "ode")]
use super::integrate::{Segment, integrate_segment};
use super::linear::{LinearPlant, ZohStep};
use super::options::SolverOptions;
use crate::model::ContinuousModel;
use crate::noise::Rng;

/// A discrete controller (with whatever observer it contains), called once per sample.
pub trait SampledController<const NY: usize, const NU: usize> {
    /// Given the (possibly delayed, noisy) measurement available at sample `k`, time `t`, returns the input
    /// held over `[t, t + T)`.
    fn update(&mut self, k: usize, t: f64, measurement: &SVector<f64, NY>) -> SVector<f64, NU>;
}

impl<F, const NY: usize, const NU: usize> SampledController<NY, NU> for F
where
    F: FnMut(usize, f64, &SVector<f64, NY>) -> SVector<f64, NU>,
{
    fn update(&mut self, k: usize, t: f64, measurement: &SVector<f64, NY>) -> SVector<f64, NU> {
        self(k, t, measurement)
    }
}

/// Settings of a sampled-data run.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledLoopConfig<const NX: usize, const NU: usize, const NY: usize> {
    pub t0: f64,
    /// The sample time `T` (s).
    pub sample_time: f64,
    /// The number of sample intervals `N`; the run ends at `t0 + N T`, which must be finite, with `t_N` and
    /// `t_{N−1}` distinct in floating point.
    pub samples: usize,
    pub x0: SVector<f64, NX>,
    /// The input assumed before the first controller update (used in the first measurement only).
    pub initial_input: SVector<f64, NU>,
    /// Whole samples by which measurements reach the controller late (at most [`MAX_MEASUREMENT_DELAY`]).
    pub measurement_delay: usize,
    /// Standard deviation of the additive measurement noise of each output.
    pub measurement_noise_std: SVector<f64, NY>,
    /// Standard deviation of the held additive derivative disturbance of each state.
    pub process_noise_std: SVector<f64, NX>,
    pub seed: u64,
    pub solver: SolverOptions,
}

impl<const NX: usize, const NU: usize, const NY: usize> SampledLoopConfig<NX, NU, NY> {
    /// A noise-free, delay-free run from `x0` at `t0 = 0` with the default solver (BDF).
    pub fn new(sample_time: f64, samples: usize, x0: SVector<f64, NX>) -> Self {
        SampledLoopConfig {
            t0: 0.0,
            sample_time,
            samples,
            x0,
            initial_input: SVector::zeros(),
            measurement_delay: 0,
            measurement_noise_std: SVector::zeros(),
            process_noise_std: SVector::zeros(),
            seed: 0,
            solver: SolverOptions::default(),
        }
    }

    fn check(&self) -> Result<(), SimError> {
        self.solver.check()?;
        check_initial(self.t0, &self.x0)?;
        if !(self.sample_time.is_finite() && self.sample_time > 0.0) {
            return Err(SimError::BadSetting {
                name: "sample_time",
                value: self.sample_time,
                reason: "the sample time must be finite and positive",
            });
        }
        let stds = self
            .measurement_noise_std
            .iter()
            .chain(self.process_noise_std.iter());
        if let Some(&s) = stds.clone().find(|s| !(s.is_finite() && **s >= 0.0)) {
            return Err(SimError::BadSetting {
                name: "noise standard deviation",
                value: s,
                reason: "noise standard deviations must be finite and non-negative",
            });
        }
        let end = self.t0 + self.samples as f64 * self.sample_time;
        let before_end = self.t0 + self.samples.saturating_sub(1) as f64 * self.sample_time;
        if !end.is_finite() || (self.samples > 0 && end <= before_end) {
            return Err(SimError::BadSetting {
                name: "samples",
                value: self.samples as f64,
                reason: "the sample instants t0 + k T must stay finite and distinct up to k = samples",
            });
        }
        if self.measurement_delay > MAX_MEASUREMENT_DELAY {
            return Err(SimError::BadSetting {
                name: "measurement_delay",
                value: self.measurement_delay as f64,
                reason: "a measurement delay of more than 2²⁰ samples is not supported",
            });
        }
        if let Some(v) = self.initial_input.iter().find(|v| !v.is_finite()) {
            return Err(SimError::BadSetting {
                name: "initial_input",
                value: *v,
                reason: "the initial input must be finite",
            });
        }
        Ok(())
    }

    /// Refuses a run whose record ([`SampledTrajectory`]) would take more than [`MAX_RECORD_BYTES`].
    fn check_record_size(&self) -> Result<(), SimError> {
        let per_sample = (1 + NX + NU + NY) * std::mem::size_of::<f64>();
        let fits = self
            .samples
            .checked_add(1)
            .and_then(|rows| rows.checked_mul(per_sample))
            .is_some_and(|bytes| bytes <= MAX_RECORD_BYTES);
        if fits {
            Ok(())
        } else {
            Err(SimError::BadSetting {
                name: "samples",
                value: self.samples as f64,
                reason: "recording every sample would take more than 1 GiB; use a _streaming variant, which hands each sample to a sink",
            })
        }
    }
}

/// The largest record [`simulate_sampled_loop`] and [`simulate_sampled_linear_loop`] build (1 GiB).
pub const MAX_RECORD_BYTES: usize = 1 << 30;

/// The largest [`SampledLoopConfig::measurement_delay`] in samples (the delay line holds that many
/// measurements).
pub const MAX_MEASUREMENT_DELAY: usize = 1 << 20;

/// The record of a sampled-data run.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledTrajectory<const NX: usize, const NU: usize, const NY: usize> {
    /// Sample instants `t_0 … t_N` (`N + 1` entries).
    pub times: Vec<f64>,
    /// `x(t_k)` for `k = 0 … N`.
    pub states: Vec<SVector<f64, NX>>,
    /// Noisy measurements `y_k` taken at `t_k`, `k = 0 … N` (before any delay).
    pub measurements: Vec<SVector<f64, NY>>,
    /// Inputs `u_k` held over `[t_k, t_{k+1})`, `k = 0 … N−1` (`N` entries).
    pub inputs: Vec<SVector<f64, NU>>,
}

/// One sample of a run as handed to the sink of a `_streaming` variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const NX: usize, const NU: usize, const NY: usize> {
    pub k: usize,
    /// `t_k`.
    pub time: f64,
    /// `x(t_k)`.
    pub state: SVector<f64, NX>,
    /// The noisy measurement `y_k` taken at `t_k` (before any delay).
    pub measurement: SVector<f64, NY>,
    /// The input `u_k` held over `[t_k, t_{k+1})`; `None` at the last sample `k = N`.
    pub input: Option<SVector<f64, NU>>,
}

/// Runs the sampled-data loop described in the module documentation, integrating the model by ODE solves.
#[cfg(feature = "ode")]
pub fn simulate_sampled_loop<Mdl, Ctl, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
) -> Result<SampledTrajectory<NX, NU, NY>, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    Ctl: SampledController<NY, NU>,
{
    cfg.check_record_size()?;
    record(cfg, |sink| {
        simulate_sampled_loop_streaming(model, controller, cfg, sink)
    })
}

/// [`simulate_sampled_loop`] handing each sample to `sink` (in order, `k = 0 … N`) instead of recording it;
/// the run stops early when `sink` breaks. Returns the number of samples handed over.
#[cfg(feature = "ode")]
pub fn simulate_sampled_loop_streaming<
    Mdl,
    Ctl,
    const NX: usize,
    const NU: usize,
    const NY: usize,
>(
    model: &Mdl,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
    sink: impl FnMut(&Sample<NX, NU, NY>) -> ControlFlow<()>,
) -> Result<usize, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    Ctl: SampledController<NY, NU>,
{
    cfg.check()?;
    let mut scratch = Vec::new();
    let advance = |k: usize, x: &SVector<f64, NX>, u: &SVector<f64, NU>, w: &SVector<f64, NX>| {
        let seg = Segment {
            t0: cfg.t0 + k as f64 * cfg.sample_time,
            t_end: cfg.t0 + (k + 1) as f64 * cfg.sample_time,
            x0: x,
            disturbance: w,
            output_times: &[],
        };
        integrate_segment::<Mdl, _, NX, NU, NY>(model, |_t| *u, &seg, &cfg.solver, &mut scratch)
    };
    run(model, controller, cfg, advance, sink)
}

/// The sampled-data loop of a linear plant with the exact zero-order-hold step (see [`super::linear`]);
/// the same record as [`simulate_sampled_loop`] up to the ODE solver's error. `cfg.solver` is not used.
pub fn simulate_sampled_linear_loop<Ctl, const NX: usize, const NU: usize, const NY: usize>(
    plant: &LinearPlant<NX, NU, NY>,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
) -> Result<SampledTrajectory<NX, NU, NY>, SimError>
where
    Ctl: SampledController<NY, NU>,
{
    cfg.check_record_size()?;
    record(cfg, |sink| {
        simulate_sampled_linear_loop_streaming(plant, controller, cfg, sink)
    })
}

/// [`simulate_sampled_linear_loop`] handing each sample to `sink` instead of recording it (see
/// [`simulate_sampled_loop_streaming`]).
pub fn simulate_sampled_linear_loop_streaming<
    Ctl,
    const NX: usize,
    const NU: usize,
    const NY: usize,
>(
    plant: &LinearPlant<NX, NU, NY>,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
    sink: impl FnMut(&Sample<NX, NU, NY>) -> ControlFlow<()>,
) -> Result<usize, SimError>
where
    Ctl: SampledController<NY, NU>,
{
    cfg.check()?;
    let step = ZohStep::new(plant, cfg.sample_time)?;
    let advance = |k: usize, x: &SVector<f64, NX>, u: &SVector<f64, NU>, w: &SVector<f64, NX>| {
        let next = step.advance(x, u, w);
        match next.iter().position(|v| !v.is_finite()) {
            Some(index) => Err(SimError::NonFiniteState {
                time: cfg.t0 + (k + 1) as f64 * cfg.sample_time,
                index,
            }),
            None => Ok(next),
        }
    };
    run(plant, controller, cfg, advance, sink)
}

/// Collects the samples that `stream` hands to its sink into a [`SampledTrajectory`].
fn record<const NX: usize, const NU: usize, const NY: usize>(
    cfg: &SampledLoopConfig<NX, NU, NY>,
    stream: impl FnOnce(
        &mut dyn FnMut(&Sample<NX, NU, NY>) -> ControlFlow<()>,
    ) -> Result<usize, SimError>,
) -> Result<SampledTrajectory<NX, NU, NY>, SimError> {
    // check_record_size bounds `samples`, so the reservation is at most MAX_RECORD_BYTES.
    let n = cfg.samples;
    let mut out = SampledTrajectory {
        times: Vec::with_capacity(n + 1),
        states: Vec::with_capacity(n + 1),
        measurements: Vec::with_capacity(n + 1),
        inputs: Vec::with_capacity(n),
    };
    stream(&mut |s: &Sample<NX, NU, NY>| {
        out.times.push(s.time);
        out.states.push(s.state);
        out.measurements.push(s.measurement);
        if let Some(u) = s.input {
            out.inputs.push(u);
        }
        ControlFlow::Continue(())
    })?;
    Ok(out)
}

/// The loop of the module docs with `advance(k, x_k, u_k, w_k) = x_{k+1}`.
fn run<Mdl, Ctl, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
    mut advance: impl FnMut(
        usize,
        &SVector<f64, NX>,
        &SVector<f64, NU>,
        &SVector<f64, NX>,
    ) -> Result<SVector<f64, NX>, SimError>,
    mut sink: impl FnMut(&Sample<NX, NU, NY>) -> ControlFlow<()>,
) -> Result<usize, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    Ctl: SampledController<NY, NU>,
{
    let n = cfg.samples;
    let mut rng = Rng::new(cfg.seed);
    // The last `measurement_delay + 1` measurements; the front is the one delivered, y_{max(k − d, 0)}.
    let mut delay_line = VecDeque::with_capacity(cfg.measurement_delay.min(n) + 1);
    let mut x = cfg.x0;
    let mut u_prev = cfg.initial_input;
    for k in 0..=n {
        let t = cfg.t0 + k as f64 * cfg.sample_time;
        let y = measure(model, cfg, &mut rng, t, &x, &u_prev)?;
        let mut sample = Sample {
            k,
            time: t,
            state: x,
            measurement: y,
            input: None,
        };
        if k == n {
            let _ = sink(&sample);
            return Ok(n + 1);
        }
        delay_line.push_back(y);
        if delay_line.len() > cfg.measurement_delay + 1 {
            delay_line.pop_front();
        }
        let delivered = delay_line.front().copied().unwrap_or(y);
        let u = controller.update(k, t, &delivered);
        if let Some(index) = u.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFiniteInput { time: t, index });
        }
        sample.input = Some(u);
        if sink(&sample).is_break() {
            return Ok(k + 1);
        }
        let mut w = SVector::<f64, NX>::zeros();
        for (wi, &s) in w.iter_mut().zip(cfg.process_noise_std.iter()) {
            if s > 0.0 {
                *wi = rng.gaussian(0.0, s);
            }
        }
        x = advance(k, &x, &u, &w)?;
        u_prev = u;
    }
    Ok(n + 1)
}

/// `y_k = h(t_k, x_k, u_{k−1}) + v_k`, refusing a non-finite model output.
fn measure<Mdl, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
    rng: &mut Rng,
    t: f64,
    x: &SVector<f64, NX>,
    u_prev: &SVector<f64, NU>,
) -> Result<SVector<f64, NY>, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
{
    let mut y = SVector::<f64, NY>::zeros();
    model.outputs(t, x, u_prev, &mut y);
    if let Some(index) = y.iter().position(|v| !v.is_finite()) {
        return Err(SimError::NonFiniteOutput { time: t, index });
    }
    for (yi, &s) in y.iter_mut().zip(cfg.measurement_noise_std.iter()) {
        if s > 0.0 {
            *yi += rng.gaussian(0.0, s);
        }
    }
    Ok(y)
}
