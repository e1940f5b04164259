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

use nalgebra::SVector;

use super::error::SimError;
use super::integrate::{Segment, SolverOptions, integrate_segment};
use super::open_loop::check_initial;
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
    /// The number of sample intervals `N`; the run ends at `t0 + N T`.
    pub samples: usize,
    pub x0: SVector<f64, NX>,
    /// The input assumed before the first controller update (used in the first measurement only).
    pub initial_input: SVector<f64, NU>,
    /// Whole samples by which measurements reach the controller late.
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
        if let Some(v) = self.initial_input.iter().find(|v| !v.is_finite()) {
            return Err(SimError::BadSetting {
                name: "initial_input",
                value: *v,
                reason: "the initial input must be finite",
            });
        }
        Ok(())
    }
}

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

/// Runs the sampled-data loop described in the module documentation.
pub fn simulate_sampled_loop<Mdl, Ctl, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    controller: &mut Ctl,
    cfg: &SampledLoopConfig<NX, NU, NY>,
) -> Result<SampledTrajectory<NX, NU, NY>, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    Ctl: SampledController<NY, NU>,
{
    cfg.check()?;
    let n = cfg.samples;
    let mut rng = Rng::new(cfg.seed);
    let mut out = SampledTrajectory {
        times: Vec::with_capacity(n + 1),
        states: Vec::with_capacity(n + 1),
        measurements: Vec::with_capacity(n + 1),
        inputs: Vec::with_capacity(n),
    };
    let mut x = cfg.x0;
    let mut u_prev = cfg.initial_input;
    let mut scratch = Vec::new();
    for k in 0..=n {
        let t = cfg.t0 + k as f64 * cfg.sample_time;
        let mut y = SVector::<f64, NY>::zeros();
        model.outputs(t, &x, &u_prev, &mut y);
        if let Some(index) = y.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFiniteOutput { time: t, index });
        }
        for (yi, &s) in y.iter_mut().zip(cfg.measurement_noise_std.iter()) {
            if s > 0.0 {
                *yi += rng.gaussian(0.0, s);
            }
        }
        out.times.push(t);
        out.states.push(x);
        out.measurements.push(y);
        if k == n {
            break;
        }
        let delivered = out.measurements[k.saturating_sub(cfg.measurement_delay)];
        let u = controller.update(k, t, &delivered);
        if let Some(index) = u.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFiniteInput { time: t, index });
        }
        let mut w = SVector::<f64, NX>::zeros();
        for (wi, &s) in w.iter_mut().zip(cfg.process_noise_std.iter()) {
            if s > 0.0 {
                *wi = rng.gaussian(0.0, s);
            }
        }
        let seg = Segment {
            t0: t,
            t_end: cfg.t0 + (k + 1) as f64 * cfg.sample_time,
            x0: &x,
            disturbance: &w,
            output_times: &[],
        };
        x = integrate_segment::<Mdl, _, NX, NU, NY>(
            model,
            |_t| u,
            &seg,
            &cfg.solver,
            &mut scratch,
        )?;
        out.inputs.push(u);
        u_prev = u;
    }
    Ok(out)
}
