//! Bench identification of the parameters the paper does not print (J_g, k_g, k_s, J_sint were fitted to its
//! reported LQR gains, see `models/back_support.bg`): a simulated lab test with the trunk held (`θ̇_h = 0`) and a
//! chirp of motor torque, measured by the motor encoder and the torque sensor with bounded noise at the paper's
//! bounds (Sec. 5: `|v_v| ≤ 0.1·10⁻⁶ rad/s`, `|v_t| ≤ 35·10⁻³ N m`), and the fit of `bgc_runtime::fit` on the
//! generated model.
//!
//! **Why a direct fit fails, and how the fit is made.** With the trunk held the plant has a lightly damped high
//! mode, the external sensor ring between `k_s` and `k_eh` with `d_s = d_eh = 0` (`√((k_s + k_eh)/J_sext)/2π ≈
//! 862 Hz`), which every held step of the 1 kHz command excites and the 1 kHz sampling aliases; the internal ring's
//! mode (`J_sint` between `k_g` and `k_s`) is overdamped by `d_g` (damping ratio ≈ 1.2). What was measured:
//! - the fitted quantities are well behaved separately: from the paper's start, `J_g, k_g, k_s` (with `J_sint`
//!   at its true value) converge in 26 iterations over the whole record, and `k_s, J_sint` (with `J_g, k_g` true)
//!   in 10, both to the noise level;
//! - `J_sint` enters the low-frequency response only as `J_g + J_sint/r_g²`: fitting `J_g, k_g, k_s` with `J_sint`
//!   50 % off moves `J_g` by the 4.5·10⁻⁵ of it that this sum predicts. At the paper's encoder bound the
//!   four-parameter objective is therefore a valley 6·10⁷ times narrower than long (condition of the weighted
//!   Jacobian), curved in the logarithms, and its cost along the Gauss–Newton step from that point rises 30-fold at
//!   a tenth of the step instead of falling (the phase of the 862 Hz ringing over a second is what the valley's
//!   walls are made of). A direct fit of all four from the start drives `J_sint` towards zero.
//!
//! [`identify`] therefore fits as an identification engineer would: (1) the well-excited `J_g`, `k_g`, `k_s` with
//! `J_sint` at its datasheet guess over the whole record; (2) all four over windows that grow from 50 samples to
//! 700 (continuation: over a short window the ringing's phase has not drifted, and each window starts where the
//! last converged one ended); (3) all four over the whole record, restarted up to three times if it does not
//! converge. The plant is linear, so every fit takes the exact zero-order-hold path of `bgc_runtime::fit::linear`
//! (one matrix exponential per parameter set instead of an ODE solve: the example runs both identifications
//! below and the rest of its study in 6.5 s in a release build, where one bounded ODE fit took 707 s).
//!
//! **What the data determine** (`cargo run --release --example back_support`, seed 2020, start factors 1.1, 0.9,
//! 1.1, 1.5):
//! - At the paper's bounds (`|v_v| ≤ 10⁻⁷ rad/s`, a velocity resolution no encoder has: it resolves the sensor
//!   ring) all four are determined: J_g 4.000004e-5 ± 8.2e-11, k_g 26399.99 ± 0.0098, k_s 33800.01 ± 0.016, J_sint
//!   9.890e-5 ± 2.3e-6 (2.3 %), each within 0.7 standard errors of the truth, weighted residual variance 0.978.
//!   The last stage **stalls** 1.44 standard errors (Gauss–Newton step) short of the minimum of the narrow valley,
//!   and restarts do not move it (every trial step raises the cost); the report says so. The cause is not found.
//!   It is not the central-difference parameter Jacobians: their error, about 10⁻¹⁰ of a column (≈ 0.3 on the
//!   largest, 4·10⁹), is far below the smallest singular value of the weighted Jacobian (≈ 65); nor, by estimate,
//!   the curvature of the logarithms or the drift of the ringing's phase over one standard error (both orders of
//!   magnitude below it); nor the matrix exponential (discretising each interval as eight eighths, one
//!   exponential squared three times, gives the same estimates and the same stall to the digits printed).
//! - With a realistic encoder ([`BenchConfig::realistic`]: a 17-bit encoder differentiated at 1 kHz, velocity
//!   quantum `2π/2¹⁷/1 ms ≈ 0.048 rad/s`, so `|v_v| ≤ 0.048 rad/s`) the record no longer sees what separates
//!   `J_sint` from `J_g`: the identifiability analysis flags `J_sint` (relative standard error 103 %), holds it at
//!   its start, and J_g (3.9986e-5 ± 1.8e-8), k_g (25747 ± 1666) and k_s (34890 ± 3017) are identified within 0.8
//!   standard errors; the fit converges. This is the form the "flags J_sint" takes: the flag comes from
//!   the statistics of a realistic sensor, never forced, and at the paper's (unrealistic) bound J_sint is
//!   determined.
//!
//! A fit that does not explain the record down to its noise (weighted residual variance above
//! [`MAX_RESIDUAL_VARIANCE`]) is refused with [`IdentificationError::NotAtNoiseLevel`]; whether the last stage
//! converged is in the report (`report.convergence`).

use bgc_models::back_support::{self as generated, Model, Params};
use bgc_runtime::fit::{
    FitError, FitReport, FitSpec, FreeParam, Generated, Record, RecordError, fit,
};
use bgc_runtime::model::ParamError;
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{Method, SampledLoopConfig, SimError, SolverOptions, simulate_sampled_loop};
use nalgebra::SVector;

/// The paper's noise bounds: motor encoder (rad/s) and torque sensor (N m).
pub const ENCODER_BOUND: f64 = 0.1e-6;

/// A realistic velocity bound of a 17-bit motor encoder differentiated at 1 kHz: one count, `2π/2¹⁷` rad, per
/// millisecond (rad/s).
pub const REALISTIC_ENCODER_BOUND: f64 = 2.0 * std::f64::consts::PI / 131_072.0 / 1e-3;

/// Restarts of the last stage that did not converge.
const RESTARTS: usize = 3;

/// The record lengths (samples) of the continuation stage; the whole record follows.
const WINDOWS: [usize; 5] = [50, 100, 200, 400, 700];
pub const TORQUE_SENSOR_BOUND: f64 = 35e-3;

/// The weighted residual variance above which a fit has not explained the record down to its noise (with
/// weights `1/σ²` a correct fit ends near 1).
pub const MAX_RESIDUAL_VARIANCE: f64 = 2.0;

/// The fitted parameters, in the order of the report.
pub const FITTED: [&str; 4] = ["J_g", "k_g", "k_s", "J_sint"];

/// The lab test.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchConfig {
    /// Logger sample time (s); the torque command is held between samples.
    pub sample_time: f64,
    pub samples: usize,
    /// Chirp amplitude (N m) and its start and end frequencies (Hz).
    pub amplitude: f64,
    pub f0: f64,
    pub f1: f64,
    pub seed: u64,
    /// Factors applied to the true values to start the fit.
    pub start_factors: [f64; 4],
    /// The bound of the encoder's velocity noise (rad/s).
    pub encoder_bound: f64,
}

impl BenchConfig {
    /// One second logged at 1 kHz, a 0.2 N m chirp from 1 Hz to 40 Hz, the fit started 10–50 % off.
    pub fn paper() -> BenchConfig {
        BenchConfig {
            sample_time: 1e-3,
            samples: 1000,
            amplitude: 0.2,
            f0: 1.0,
            f1: 40.0,
            seed: 2020,
            start_factors: [1.1, 0.9, 1.1, 1.5],
            encoder_bound: ENCODER_BOUND,
        }
    }

    /// The same test with a realistic encoder ([`REALISTIC_ENCODER_BOUND`]).
    pub fn realistic() -> BenchConfig {
        BenchConfig {
            encoder_bound: REALISTIC_ENCODER_BOUND,
            ..BenchConfig::paper()
        }
    }
}

/// One identified parameter with the truth it was simulated with.
#[derive(Clone, Debug, PartialEq)]
pub struct Identified {
    pub name: &'static str,
    pub truth: f64,
    pub estimate: f64,
    /// `NaN` when not determined.
    pub std_error: f64,
    pub determined: bool,
}

impl Identified {
    /// `|estimate − truth|` in standard errors.
    pub fn error_in_std_errors(&self) -> f64 {
        (self.estimate - self.truth).abs() / self.std_error
    }
}

/// The result of the bench identification.
#[derive(Clone, Debug)]
pub struct BenchIdentification {
    pub parameters: Vec<Identified>,
    pub report: FitReport,
}

/// Why the identification could not run.
#[derive(Debug, thiserror::Error)]
pub enum IdentificationError {
    #[error("the bench simulation failed: {0}")]
    Simulation(#[from] SimError),
    #[error("the record is not valid: {0}")]
    Record(#[from] RecordError),
    #[error("the fit failed: {0}")]
    Fit(#[from] FitError),
    #[error("a parameter was refused: {0}")]
    Parameter(#[from] ParamError),
    #[error(
        "the fit stopped ({stop}) at a weighted residual variance of {variance:.3e} (1 at the noise level): the \
         estimates are not an identification"
    )]
    NotAtNoiseLevel { stop: &'static str, variance: f64 },
}

fn index(name: &str) -> usize {
    generated::PARAM_NAMES
        .iter()
        .position(|n| *n == name)
        .unwrap_or(usize::MAX)
}

/// The chirp torque command at `t` (linear frequency sweep over the record).
fn chirp(cfg: &BenchConfig, t: f64) -> f64 {
    let duration = cfg.sample_time * cfg.samples as f64;
    let rate = (cfg.f1 - cfg.f0) / duration;
    cfg.amplitude * (2.0 * std::f64::consts::PI * (cfg.f0 * t + 0.5 * rate * t * t)).sin()
}

/// The noise-free lab test: sample times, the held commands and the true `omega_m`, `tau_s` at each sample.
#[derive(Clone, Debug, PartialEq)]
pub struct CleanBench {
    pub times: Vec<f64>,
    pub inputs: Vec<Vec<f64>>,
    pub outputs: Vec<[f64; 2]>,
}

/// Simulates the lab test with the paper's parameters, without noise.
pub fn bench_clean(cfg: &BenchConfig) -> Result<CleanBench, IdentificationError> {
    let model = Model::default();
    let mut run = SampledLoopConfig::new(cfg.sample_time, cfg.samples, SVector::zeros());
    run.solver = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-12,
        atol: 1e-14,
        max_steps: 1_000_000,
    };
    let mut command =
        |_k: usize, t: f64, _y: &SVector<f64, 3>| SVector::<f64, 2>::new(chirp(cfg, t), 0.0);
    let traj = simulate_sampled_loop(&model, &mut command, &run)?;
    // The logger records the command held from each sample; the last sample holds the last command.
    let mut inputs: Vec<Vec<f64>> = traj.inputs.iter().map(|u| vec![u[0], u[1]]).collect();
    inputs.push(inputs.last().cloned().unwrap_or_else(|| vec![0.0, 0.0]));
    Ok(CleanBench {
        times: traj.times,
        inputs,
        outputs: traj.measurements.iter().map(|y| [y[0], y[1]]).collect(),
    })
}

/// `clean` as measured: uniform noise within the encoder bound of `cfg` and the torque sensor's bound, drawn
/// from `seed`.
pub fn with_noise(
    clean: &CleanBench,
    cfg: &BenchConfig,
    seed: u64,
) -> Result<Record, IdentificationError> {
    let mut rng = Rng::new(seed);
    let mut uniform = |bound: f64| bound * (2.0 * rng.uniform() - 1.0);
    let measured: Vec<Vec<f64>> = clean
        .outputs
        .iter()
        .map(|y| {
            vec![
                y[0] + uniform(cfg.encoder_bound),
                y[1] + uniform(TORQUE_SENSOR_BOUND),
            ]
        })
        .collect();
    Ok(Record::new(
        clean.times.clone(),
        clean.inputs.clone(),
        vec![0, 1],
        measured,
    )?)
}

/// Simulates the lab test with the paper's parameters and returns the noisy record of `omega_m` and `tau_s`.
pub fn bench_record(cfg: &BenchConfig) -> Result<Record, IdentificationError> {
    with_noise(&bench_clean(cfg)?, cfg, cfg.seed)
}

/// The first `n` samples of a record.
fn window(record: &Record, n: usize) -> Result<Record, RecordError> {
    let n = n.min(record.times.len());
    Record::new(
        record.times[..n].to_vec(),
        record.inputs[..n].to_vec(),
        record.outputs.clone(),
        record.measured[..n].to_vec(),
    )
}

/// Fits the `free` names of [`FITTED`] to `record` from the parameter values `start`.
fn fit_stage(
    cfg: &BenchConfig,
    record: &Record,
    start: &[f64],
    free: &[&str],
) -> Result<FitReport, IdentificationError> {
    let params = free
        .iter()
        .map(|name| FreeParam::new(index(name), name, true))
        .collect();
    let mut spec = FitSpec::new(params, 2);
    // Uniform noise on ±b has the variance b²/3.
    spec.weights = vec![
        3.0 / cfg.encoder_bound.powi(2),
        3.0 / TORQUE_SENSOR_BOUND.powi(2),
    ];
    let mut model = Generated::exact(Model::default()).declared_linear();
    Ok(fit(
        &mut model,
        record,
        start,
        &[0.0; generated::N_STATES],
        &spec,
    )?)
}

/// Fits J_g, k_g, k_s and J_sint to a bench record, from the true values times `cfg.start_factors`: first
/// J_g, k_g, k_s with J_sint at its start over the whole record, then all four over growing windows.
pub fn identify(
    cfg: &BenchConfig,
    record: &Record,
) -> Result<BenchIdentification, IdentificationError> {
    let truth = Params::default();
    let mut start: Vec<f64> = (0..generated::N_PARAMS)
        .map(|k| truth.get(k).unwrap_or(f64::NAN))
        .collect();
    for (name, factor) in FITTED.iter().zip(cfg.start_factors) {
        start[index(name)] *= factor;
    }
    let first = fit_stage(cfg, record, &start, &FITTED[..3])?;
    let mut params = first.params.clone();
    for n in WINDOWS.into_iter().filter(|&n| n < record.times.len()) {
        let part = fit_stage(cfg, &window(record, n)?, &params, &FITTED)?;
        // A window that did not converge says nothing reliable: the next one starts where this one started.
        if part.convergence.converged() {
            params = part.params;
        }
    }
    // In the narrow valley the damping that let the last steps through can end the iteration short of the
    // minimum; a restart from there (fresh damping) goes on. The report says whether it got there.
    let mut report = fit_stage(cfg, record, &params, &FITTED)?;
    for _ in 0..RESTARTS {
        if report.convergence.converged() {
            break;
        }
        report = fit_stage(cfg, record, &report.params, &FITTED)?;
    }
    if report.residual_variance.is_nan() || report.residual_variance > MAX_RESIDUAL_VARIANCE {
        return Err(IdentificationError::NotAtNoiseLevel {
            stop: report.stop.describe(),
            variance: report.residual_variance,
        });
    }
    let parameters = FITTED
        .iter()
        .zip(&report.estimates)
        .map(|(name, e)| Identified {
            name,
            truth: truth.get(index(name)).unwrap_or(f64::NAN),
            estimate: e.value,
            std_error: e.std_error,
            determined: e.determined,
        })
        .collect();
    Ok(BenchIdentification { parameters, report })
}
