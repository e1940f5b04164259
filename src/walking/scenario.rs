//! The closed-loop walking scenario: the synthetic wearer in the exoskeleton, the dual UKF generating the
//! reference from the position sensors, the impedance controller (Eqs. 28–29) tracking it on the simulated
//! leg, and the gait supervisor (Eq. 30, Tables 2–3) switching swing and stance from the insoles.
//!
//! Rates: the plant is integrated by the runtime's sampled-data simulator with a 1 ms zero-order hold; the
//! impedance controller and the supervisor run every 1 ms, the dual UKF every `filter_decimation` samples
//! (10 ms by default). Between filter steps the reference is the filter's prediction
//! `q_d(t) = q̂ + q̂̇ τ + ½ q̈̂ τ²`, `q̇_d = q̂̇ + q̈̂ τ`, `q̈_d = q̈̂` (`τ` since the last filter step).
//!
//! Figures of merit, computed after a warm-up (default 1 s, while the filter converges from the paper's
//! initial guess):
//!
//! - Table 7: per joint, the mean position innovation (residual), the mean of its normalised
//!   autocorrelation over lags 1–20 (the runtime's `FilterHealth`), the mean state error `x − x̂` (with `x`
//!   the wearer's joint angles and speeds, which the filter estimates) for position and velocity and the
//!   percentage of filter steps on which it exceeded `√P_ii`;
//! - Table 9: per joint, the RMS difference between the reference (the filter's prediction) and the leg's
//!   actual position and velocity, over all 1 ms samples.

use super::anthropometry::{LegFriction, LegSegments};
use super::estimator::{DualEstimator, DualUkfConfig, TorqueObservation};
use super::plant::{FrictionCompensated, LegModel, PLANT_OUTPUTS, WalkingPlant, join};
use super::wearer::{Wearer, WearerConfig};
use bgc_runtime::control::{
    ControlError, GaitSupervisor, GaitThresholds, GrfSample, ImpedanceController, ImpedanceGains,
    JointReference, JointState, Leg, LegMode,
};
use bgc_runtime::estimation::EstimationError;
use bgc_runtime::estimation::health::FilterHealth;
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{Method, SampledLoopConfig, SimError, SolverOptions, simulate_sampled_loop};
use nalgebra::{Matrix3, Matrix6, SVector, Vector3, Vector6};
use serde::Serialize;
use std::fmt;

const DEG: f64 = std::f64::consts::PI / 180.0;
/// Joint names in state order.
pub const JOINTS: [&str; 3] = ["ankle", "knee", "hip"];
/// Lags of the residual autocorrelation averaged for Table 7.
pub const AUTOCORRELATION_LAGS: usize = 20;

/// Why a walking run failed.
#[derive(Clone, Debug, PartialEq)]
pub enum WalkingError {
    /// The dual UKF refused a setting or failed a step.
    Estimation { time: f64, source: EstimationError },
    /// The impedance controller or the supervisor refused a setting or an input.
    Control { time: f64, source: ControlError },
    /// The plant simulation failed.
    Simulation(SimError),
    /// A scenario setting is out of its domain.
    Setting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}

impl fmt::Display for WalkingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WalkingError::Estimation { time, source } => {
                write!(f, "dual UKF failed at t = {time:.3} s: {source}")
            }
            WalkingError::Control { time, source } => {
                write!(f, "controller failed at t = {time:.3} s: {source}")
            }
            WalkingError::Simulation(e) => write!(f, "plant simulation failed: {e}"),
            WalkingError::Setting {
                name,
                value,
                reason,
            } => write!(f, "setting {name} = {value} is invalid: {reason}"),
        }
    }
}

impl std::error::Error for WalkingError {}

/// Standard deviations of the simulated sensors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SensorNoise {
    /// Joint position sensors read by the filter (deg).
    pub position_deg: f64,
    /// Joint torque sensors (N m).
    pub torque: f64,
    /// Motor encoders (deg).
    pub encoder_deg: f64,
    /// Joint speed from motor rpm (deg/s).
    pub rpm_deg_s: f64,
    /// Insole force sensors (N).
    pub insole: f64,
}

impl SensorNoise {
    /// The paper's position noise (`P_n = 0.8 deg²`); the paper gives none for the other sensors: 0.1 N m
    /// for the torque sensors, 0.01° for the motor encoders and 0.1°/s for the joint speed from motor rpm
    /// (joint side of a geared motor), 5 N for the insoles.
    pub fn paper() -> Self {
        SensorNoise {
            position_deg: 0.8f64.sqrt(),
            torque: 0.1,
            encoder_deg: 0.01,
            rpm_deg_s: 0.1,
            insole: 5.0,
        }
    }

    /// No noise anywhere.
    pub fn none() -> Self {
        SensorNoise {
            position_deg: 0.0,
            torque: 0.0,
            encoder_deg: 0.0,
            rpm_deg_s: 0.0,
            insole: 0.0,
        }
    }
}

/// Settings of a walking run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkingConfig {
    /// Simulated time (s).
    pub duration: f64,
    /// Control and supervisor period (s).
    pub control_period: f64,
    /// Control periods per dual UKF step.
    pub filter_decimation: usize,
    /// Time excluded from the statistics (s).
    pub warmup: f64,
    /// Relative error of the initial mass estimate (0.2: 20 % too heavy).
    pub mass_error: f64,
    /// Time from which the parameter filter learns (s); before, the state filter converges alone.
    pub learn_from: f64,
    /// Time from which the exoskeleton assists (s); before, it applies no torque.
    pub assist_from: f64,
    pub wearer: WearerConfig,
    pub noise: SensorNoise,
    pub estimator: DualUkfConfig,
    /// Impedance target `M_r = I`, `B_r = 2 ζ ω I`, `K_r = ω² I`: `ω` (rad/s) and `ζ`.
    pub impedance_frequency: f64,
    pub impedance_damping_ratio: f64,
    /// Feed the filter's acceleration estimate forward as `q̈_d` of Eq. (29) (see the module docs).
    pub acceleration_feedforward: bool,
    pub supervisor: GaitThresholds,
    /// Seed of the sensor noise.
    pub seed: u64,
}

impl WalkingConfig {
    /// The paper's filter settings: initial state `[84, −175, 0]°` in the paper's sensor convention (hip
    /// from the horizontal, knee as a negative included angle), which is hip 6° and knee 5° of flexion and
    /// the ankle neutral in ours; `P_v = diag(0.8, 1, 1, 1, 1, 1)`, `P_n = diag(0.8, …)` (deg², (deg/s)²
    /// per filter period, in our state order ankle, knee, hip); `α = 10⁻³`, `β = 2`, `κ = 0`. The paper gives no
    /// initial covariance; ours covers the initial guess's error (20° in position, 100°/s in velocity, one
    /// standard deviation). The masses start `mass_error` too heavy; `λ_RLS = 0.8` per 10 ms step (a memory
    /// of about 50 ms, short enough to follow the torso load on and off within a stance phase; the paper
    /// does not print its value). The sensor noise is [`SensorNoise::paper`].
    pub fn paper(duration: f64) -> Self {
        let segments = LegSegments::paper_subject();
        let mass_error = 0.2;
        let m = segments.masses();
        WalkingConfig {
            duration,
            control_period: 1e-3,
            filter_decimation: 10,
            warmup: 1.0,
            mass_error,
            learn_from: 0.5,
            assist_from: 0.5,
            wearer: WearerConfig {
                duration: duration + 1.0,
                ..WearerConfig::default()
            },
            noise: SensorNoise::paper(),
            estimator: DualUkfConfig {
                sample_time: 1e-2,
                alpha: 1e-3,
                beta: 2.0,
                kappa: 0.0,
                process_noise: [0.8, 1.0, 1.0, 1.0, 1.0, 1.0],
                measurement_noise: [0.8; 3],
                initial_state: [0.0, 5.0, 6.0, 0.0, 0.0, 0.0],
                initial_covariance: [400.0, 400.0, 400.0, 1e4, 1e4, 1e4],
                initial_masses: m.map(|v| v * (1.0 + mass_error)),
                initial_mass_std: m.map(|v| v * 0.3),
                forgetting: 0.8,
                torque_error_std: [0.05, 0.3, 1.0],
                min_mass_fraction: 0.1,
            },
            impedance_frequency: 2.0 * std::f64::consts::PI * 4.0,
            impedance_damping_ratio: 1.0,
            acceleration_feedforward: true,
            supervisor: GaitThresholds::default(),
            seed: 7,
        }
    }
}

/// One dual UKF step, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FilterSample {
    pub t: f64,
    /// The wearer's joint angles and speeds, which the filter estimates.
    pub q_true: [f64; 3],
    pub qd_true: [f64; 3],
    pub q_measured: [f64; 3],
    pub q_estimate: [f64; 3],
    pub qd_estimate: [f64; 3],
    /// `√P_ii` for the positions (deg) and velocities (deg/s).
    pub q_sigma: [f64; 3],
    pub qd_sigma: [f64; 3],
    pub residual: [f64; 3],
    /// Mass estimate `[m₁, m₂, m₃]` and its standard deviations (kg).
    pub masses: [f64; 3],
    pub mass_sigma: [f64; 3],
    /// The masses the plant has at this instant (m₃ includes the torso load).
    pub masses_true: [f64; 3],
    /// Right leg in stance (ground truth).
    pub stance: bool,
}

/// One control sample, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ControlSample {
    pub t: f64,
    pub q_reference: [f64; 3],
    pub qd_reference: [f64; 3],
    pub q: [f64; 3],
    pub qd: [f64; 3],
    pub q_intended: [f64; 3],
    /// Actuator torque (N m).
    pub actuator_torque: [f64; 3],
    /// Human torque read by the brace torque sensors (N m).
    pub human_torque: [f64; 3],
    /// Supervisor state S1–S4.
    pub state: &'static str,
    /// Mode of the right leg the supervisor enables.
    pub right_mode: &'static str,
    /// `P` of Eq. (30) per foot (`None`: unloaded).
    pub right_index: Option<f64>,
    pub left_index: Option<f64>,
}

/// One supervisor transition.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TransitionRecord {
    pub t: f64,
    /// `p1` … `p4`.
    pub event: &'static str,
    /// The state entered.
    pub state: &'static str,
    /// Where the right foot was in its cycle (0: heel strike, 0.62: toe-off).
    pub right_cycle_fraction: f64,
}

/// Table 7 row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JointHealth {
    pub joint: &'static str,
    pub mean_residual_deg: f64,
    pub mean_residual_autocorrelation: f64,
    pub mean_position_error_deg: f64,
    pub mean_velocity_error_deg_s: f64,
    pub position_outside_one_sigma_percent: f64,
    pub velocity_outside_one_sigma_percent: f64,
}

/// Table 9 row: the reference (filter prediction) against the exoskeleton, and, for context, the
/// exoskeleton against the wearer's own motion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JointTracking {
    pub joint: &'static str,
    pub position_rmse_deg: f64,
    pub velocity_rmse_deg_s: f64,
    pub wearer_position_rmse_deg: f64,
    pub wearer_velocity_rmse_deg_s: f64,
}

/// How the masses came out.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MassSummary {
    pub initial: [f64; 3],
    /// The leg's masses without the torso load.
    pub true_swing: [f64; 3],
    /// Mean estimate over the last quarter of the run.
    pub final_mean: [f64; 3],
    /// Mean m₃ estimate while the torso load is fully on (single support) / fully off (swing), in the
    /// second half of the run.
    pub m3_stance_mean: f64,
    pub m3_swing_mean: f64,
    pub m3_true_stance: f64,
    pub m3_true_swing: f64,
}

/// Everything a walking run produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WalkingRun {
    pub table7: Vec<JointHealth>,
    pub table9: Vec<JointTracking>,
    pub masses: MassSummary,
    pub mean_nis: Option<f64>,
    pub peak_actuator_torque: [f64; 3],
    pub transitions: Vec<TransitionRecord>,
    pub supervisor_faults: u64,
    #[serde(skip)]
    pub filter: Vec<FilterSample>,
    #[serde(skip)]
    pub control: Vec<ControlSample>,
}

fn deg3(v: &Vector3<f64>) -> [f64; 3] {
    [v[0] / DEG, v[1] / DEG, v[2] / DEG]
}

fn transition_label(t: bgc_runtime::control::Transition) -> &'static str {
    use bgc_runtime::control::Transition::*;
    match t {
        P0 => "p0",
        P1 => "p1",
        P2 => "p2",
        P3 => "p3",
        P4 => "p4",
    }
}

/// A filter step as recorded inside the loop, before the ground truth is attached.
struct PendingFilter {
    k: usize,
    measured: Vector3<f64>,
    estimate: Vector6<f64>,
    covariance: Matrix6<f64>,
    residual: Vector3<f64>,
    residual_covariance: Matrix3<f64>,
    masses: Vector3<f64>,
    mass_covariance: Matrix3<f64>,
}

struct PendingControl {
    k: usize,
    reference: JointReference<3>,
    actuator: Vector3<f64>,
    human_torque: Vector3<f64>,
    state: &'static str,
    right_mode: &'static str,
    right_index: Option<f64>,
    left_index: Option<f64>,
}

/// Runs the closed loop described in the module docs.
pub fn run(cfg: &WalkingConfig) -> Result<WalkingRun, WalkingError> {
    if !(cfg.control_period.is_finite() && cfg.control_period > 0.0) {
        return Err(WalkingError::Setting {
            name: "control_period",
            value: cfg.control_period,
            reason: "the control period must be finite and positive",
        });
    }
    if cfg.filter_decimation == 0 {
        return Err(WalkingError::Setting {
            name: "filter_decimation",
            value: 0.0,
            reason: "the filter must run every so many control periods, at least one",
        });
    }
    if !(cfg.duration.is_finite() && cfg.duration > cfg.warmup && cfg.warmup >= 0.0) {
        return Err(WalkingError::Setting {
            name: "duration",
            value: cfg.duration,
            reason: "the run must be finite and longer than the warm-up",
        });
    }
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !(positive(cfg.impedance_frequency) && positive(cfg.impedance_damping_ratio)) {
        return Err(WalkingError::Setting {
            name: "impedance_frequency",
            value: cfg.impedance_frequency,
            reason: "the impedance target needs a positive natural frequency and damping ratio",
        });
    }
    let segments = LegSegments::paper_subject();
    let friction = LegFriction::table8_right();
    let wearer = Wearer::new(&cfg.wearer);
    let plant = WalkingPlant {
        leg: LegModel::new(segments, friction),
        wearer: wearer.clone(),
    };
    let mut estimator_cfg = cfg.estimator;
    estimator_cfg.sample_time = cfg.control_period * cfg.filter_decimation as f64;
    let mut estimator = DualEstimator::new(segments, friction, estimator_cfg)
        .map_err(|source| WalkingError::Estimation { time: 0.0, source })?;
    let w = cfg.impedance_frequency;
    let controller = ImpedanceController::new(ImpedanceGains {
        inertia: Matrix3::identity(),
        damping: Matrix3::identity() * (2.0 * cfg.impedance_damping_ratio * w),
        stiffness: Matrix3::identity() * (w * w),
    })
    .map_err(|source| WalkingError::Control { time: 0.0, source })?;
    let mut supervisor = GaitSupervisor::new(cfg.supervisor)
        .map_err(|source| WalkingError::Control { time: 0.0, source })?;

    let start = wearer.intended(0.0);
    let samples = (cfg.duration / cfg.control_period).round() as usize;
    let mut sim = SampledLoopConfig::<6, 3, PLANT_OUTPUTS>::new(
        cfg.control_period,
        samples,
        join(&start.q, &start.qd),
    );
    let n = &cfg.noise;
    sim.measurement_noise_std = SVector::<f64, PLANT_OUTPUTS>::from_fn(|i, _| match i / 3 {
        0 => n.position_deg * DEG,
        1 | 2 => n.torque,
        3 => n.encoder_deg * DEG,
        _ => n.rpm_deg_s * DEG,
    });
    sim.seed = cfg.seed;
    sim.solver = SolverOptions {
        method: Method::Tsit45,
        rtol: 1e-7,
        atol: 1e-9,
        max_steps: 100_000,
    };

    let mut insole_rng = Rng::new(cfg.seed ^ 0x5eed_1a5e);
    let mut torque_buffer: Vec<Vector3<f64>> = Vec::with_capacity(cfg.filter_decimation);
    let x0 = estimator.state();
    let mut anchor = (0.0, x0, Vector3::<f64>::zeros());
    let mut failure: Option<WalkingError> = None;
    let mut last_actuator = Vector3::<f64>::zeros();
    let mut last_human = Vector3::<f64>::zeros();
    let mut link_torque_sum = Vector3::<f64>::zeros();
    let mut period_start = JointState {
        q: start.q,
        qd: start.qd,
    };
    let mut pending_filter: Vec<PendingFilter> =
        Vec::with_capacity(samples / cfg.filter_decimation);
    let mut pending_control: Vec<PendingControl> = Vec::with_capacity(samples + 1);
    let mut transitions = Vec::new();

    let mut control = |k: usize, t: f64, y: &SVector<f64, PLANT_OUTPUTS>| -> Vector3<f64> {
        if failure.is_some() {
            return Vector3::zeros();
        }
        let q_sensor = Vector3::new(y[0], y[1], y[2]);
        let human_torque = Vector3::new(y[6], y[7], y[8]);
        let state = JointState {
            q: Vector3::new(y[9], y[10], y[11]),
            qd: Vector3::new(y[12], y[13], y[14]),
        };
        if k > 0 {
            torque_buffer.push(Vector3::new(y[3], y[4], y[5]));
            // Torque on the links over the elapsed control period: the held actuator torque and the brace
            // torque (trapezoidal mean of its two readings).
            link_torque_sum += last_actuator + (last_human + human_torque) * 0.5;
        }
        if k > 0 && k.is_multiple_of(cfg.filter_decimation) {
            let observation = TorqueObservation {
                torque: link_torque_sum / cfg.filter_decimation as f64,
                q: (period_start.q + state.q) * 0.5,
                qd: (period_start.qd + state.qd) * 0.5,
                qdd: (state.qd - period_start.qd) / estimator.sample_time(),
            };
            let learn = (t >= cfg.learn_from).then_some(&observation);
            link_torque_sum = Vector3::zeros();
            period_start = state;
            match estimator.step(&torque_buffer, &q_sensor, learn) {
                Ok(step) => {
                    pending_filter.push(PendingFilter {
                        k,
                        measured: q_sensor,
                        estimate: estimator.state(),
                        covariance: estimator.covariance(),
                        residual: step.innovation,
                        residual_covariance: step.innovation_covariance,
                        masses: estimator.masses(),
                        mass_covariance: estimator.mass_covariance(),
                    });
                    let qdd = if cfg.acceleration_feedforward {
                        estimator.acceleration()
                    } else {
                        Vector3::zeros()
                    };
                    anchor = (t, estimator.state(), qdd);
                }
                Err(source) => {
                    failure = Some(WalkingError::Estimation { time: t, source });
                    return Vector3::zeros();
                }
            }
            torque_buffer.clear();
        }
        let (right, left) = wearer.insoles(t);
        // Force-sensing insoles read no negative force.
        let mut noisy = |g: GrfSample| GrfSample {
            heel: (g.heel + n.insole * insole_rng.normal()).max(0.0),
            ball: (g.ball + n.insole * insole_rng.normal()).max(0.0),
        };
        let (right, left) = (noisy(right), noisy(left));
        let step = supervisor.update(right, left);
        if let Some(tr) = step.transition {
            transitions.push(TransitionRecord {
                t,
                event: transition_label(tr),
                state: step.state.label(),
                right_cycle_fraction: wearer.cycle_fraction(t, false),
            });
        }
        let tau = t - anchor.0;
        let (x, qdd) = (anchor.1, anchor.2);
        let q_hat = x.fixed_rows::<3>(0).into_owned();
        let qd_hat = x.fixed_rows::<3>(3).into_owned();
        let reference = JointReference {
            q: q_hat + qd_hat * tau + qdd * (0.5 * tau * tau),
            qd: qd_hat + qdd * tau,
            qdd,
        };
        let dynamics = FrictionCompensated(estimator.estimated_model());
        let command = match controller.torque(&dynamics, &state, &reference, &human_torque) {
            Ok(c) => c,
            Err(source) => {
                failure = Some(WalkingError::Control { time: t, source });
                return Vector3::zeros();
            }
        };
        let actuator = if t >= cfg.assist_from {
            WalkingPlant::actuator(&command.torque)
        } else {
            Vector3::zeros()
        };
        last_actuator = actuator;
        last_human = human_torque;
        if k == 0 {
            period_start = state;
        }
        pending_control.push(PendingControl {
            k,
            reference,
            actuator,
            human_torque,
            state: step.state.label(),
            right_mode: match step.state.mode(Leg::Right) {
                LegMode::Swing => "swing",
                LegMode::Stance => "stance",
            },
            right_index: step.right_index,
            left_index: step.left_index,
        });
        actuator
    };
    let trajectory =
        simulate_sampled_loop(&plant, &mut control, &sim).map_err(WalkingError::Simulation)?;
    if let Some(e) = failure {
        return Err(e);
    }
    let supervisor_faults = supervisor.fault_count();

    // Attach the ground truth and compute the tables.
    let truth = |k: usize| -> Option<Vector6<f64>> { trajectory.states.get(k).copied() };
    let true_masses = |t: f64| {
        let m = segments.masses();
        [m[0], m[1], m[2] + wearer.torso_load(t) * wearer.torso_mass]
    };
    let mut health = FilterHealth::<6, 3, AUTOCORRELATION_LAGS>::new();
    let scale6 = Matrix6::from_diagonal_element(1.0 / (DEG * DEG));
    let mut filter = Vec::with_capacity(pending_filter.len());
    for p in &pending_filter {
        let t = p.k as f64 * cfg.control_period;
        // The filter estimates the wearer's motion (it reads the wearer's joint angles and the gait torque).
        let w = wearer.intended(t);
        let x = join(&w.q, &w.qd);
        let err = (x - p.estimate) / DEG;
        if t >= cfg.warmup {
            health
                .record_innovation(&(p.residual / DEG), &(p.residual_covariance / (DEG * DEG)))
                .map_err(|source| WalkingError::Estimation { time: t, source })?;
            health
                .record_state_error(&err, &(p.covariance.component_mul(&scale6)))
                .map_err(|source| WalkingError::Estimation { time: t, source })?;
        }
        let sd = |i: usize| p.covariance[(i, i)].max(0.0).sqrt() / DEG;
        let q_true = x.fixed_rows::<3>(0).into_owned();
        let qd_true = x.fixed_rows::<3>(3).into_owned();
        filter.push(FilterSample {
            t,
            q_true: deg3(&q_true),
            qd_true: deg3(&qd_true),
            q_measured: deg3(&p.measured),
            q_estimate: deg3(&p.estimate.fixed_rows::<3>(0).into_owned()),
            qd_estimate: deg3(&p.estimate.fixed_rows::<3>(3).into_owned()),
            q_sigma: [sd(0), sd(1), sd(2)],
            qd_sigma: [sd(3), sd(4), sd(5)],
            residual: deg3(&p.residual),
            masses: [p.masses[0], p.masses[1], p.masses[2]],
            mass_sigma: std::array::from_fn(|i| p.mass_covariance[(i, i)].max(0.0).sqrt()),
            masses_true: true_masses(t),
            stance: wearer.right_in_stance(t),
        });
    }
    let report = health.report();
    let table7 = (0..3)
        .map(|j| JointHealth {
            joint: JOINTS[j],
            mean_residual_deg: report.innovation_mean[j],
            mean_residual_autocorrelation: report.mean_innovation_autocorrelation[j],
            mean_position_error_deg: report.state_error_mean[j],
            mean_velocity_error_deg_s: report.state_error_mean[3 + j],
            position_outside_one_sigma_percent: 100.0 * report.fraction_outside_one_sigma[j],
            velocity_outside_one_sigma_percent: 100.0 * report.fraction_outside_one_sigma[3 + j],
        })
        .collect();

    let mut control_samples = Vec::with_capacity(pending_control.len());
    let mut sq_pos = [0.0; 3];
    let mut sq_vel = [0.0; 3];
    let mut sq_pos_w = [0.0; 3];
    let mut sq_vel_w = [0.0; 3];
    let mut counted = 0usize;
    let mut peak = [0.0f64; 3];
    for p in &pending_control {
        let t = p.k as f64 * cfg.control_period;
        let Some(x) = truth(p.k) else { continue };
        let q = x.fixed_rows::<3>(0).into_owned();
        let qd = x.fixed_rows::<3>(3).into_owned();
        let intended = wearer.intended(t);
        if t >= cfg.warmup {
            for j in 0..3 {
                sq_pos[j] += ((p.reference.q[j] - q[j]) / DEG).powi(2);
                sq_vel[j] += ((p.reference.qd[j] - qd[j]) / DEG).powi(2);
                sq_pos_w[j] += ((intended.q[j] - q[j]) / DEG).powi(2);
                sq_vel_w[j] += ((intended.qd[j] - qd[j]) / DEG).powi(2);
                peak[j] = peak[j].max(p.actuator[j].abs());
            }
            counted += 1;
        }
        control_samples.push(ControlSample {
            t,
            q_reference: deg3(&p.reference.q),
            qd_reference: deg3(&p.reference.qd),
            q: deg3(&q),
            qd: deg3(&qd),
            q_intended: deg3(&intended.q),
            actuator_torque: [p.actuator[0], p.actuator[1], p.actuator[2]],
            human_torque: [p.human_torque[0], p.human_torque[1], p.human_torque[2]],
            state: p.state,
            right_mode: p.right_mode,
            right_index: p.right_index,
            left_index: p.left_index,
        });
    }
    let denominator = counted.max(1) as f64;
    let table9 = (0..3)
        .map(|j| JointTracking {
            joint: JOINTS[j],
            position_rmse_deg: (sq_pos[j] / denominator).sqrt(),
            velocity_rmse_deg_s: (sq_vel[j] / denominator).sqrt(),
            wearer_position_rmse_deg: (sq_pos_w[j] / denominator).sqrt(),
            wearer_velocity_rmse_deg_s: (sq_vel_w[j] / denominator).sqrt(),
        })
        .collect();

    let masses = summarize_masses(&filter, cfg, &segments, &wearer);
    Ok(WalkingRun {
        table7,
        table9,
        masses,
        mean_nis: report.mean_nis.map(|v| v / 1.0),
        peak_actuator_torque: peak,
        transitions,
        supervisor_faults,
        filter,
        control: control_samples,
    })
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

fn summarize_masses(
    filter: &[FilterSample],
    cfg: &WalkingConfig,
    segments: &LegSegments,
    wearer: &Wearer,
) -> MassSummary {
    let m = segments.masses();
    let last_quarter = 0.75 * cfg.duration;
    let half = 0.5 * cfg.duration;
    let final_mean = std::array::from_fn(|i| {
        mean(
            filter
                .iter()
                .filter(|s| s.t >= last_quarter)
                .map(|s| s.masses[i]),
        )
    });
    let m3_when = |load: f64| {
        mean(
            filter
                .iter()
                .filter(|s| s.t >= half && (wearer.torso_load(s.t) - load).abs() < 1e-12)
                .map(|s| s.masses[2]),
        )
    };
    MassSummary {
        initial: cfg.estimator.initial_masses,
        true_swing: m,
        final_mean,
        m3_stance_mean: m3_when(1.0),
        m3_swing_mean: m3_when(0.0),
        m3_true_stance: m[2] + wearer.torso_mass,
        m3_true_swing: m[2],
    }
}
