//! The closed-loop walking scenario: the synthetic wearer in the exoskeleton, the dual UKF generating the
//! reference from the position sensors, the impedance controller (Eqs. 28–29) tracking it on the simulated
//! leg, and the gait supervisor (Eq. 30, Tables 2–3) switching swing and stance from the insoles.
//!
//! Rates: the plant is integrated by the runtime's sampled-data simulator with a 1 ms zero-order hold; the
//! impedance controller and the supervisor run every 1 ms, the dual UKF every `filter_decimation` samples
//! (10 ms by default). Between filter steps the filter's model runs on at the control rate from its last
//! posterior with the torque readings as they arrive, and the reference follows that prediction through
//! the second-order reference filter of [`super::reference`].
//!
//! The controller is Eq. (28) with the estimated masses, the friction of Eq. (3) compensated, the measured
//! brace torque `τ_h` subtracted and, while the right insole reads a load, the stance term of Eq. (2): the
//! ground reaction from the insole total (its vertical component) directed along the leg
//! ([`super::plant::axial_reaction`]) at the encoders' posture. Eq. (28) also asks for an ankle torque,
//! which no motor delivers; the knee and hip torques absorb the passive ankle's own motion instead
//! ([`super::plant::passive_ankle_torque`]). The motors deliver at most their rated torques; the run
//! counts the control periods in which the command exceeded them.
//!
//! Figures of merit, computed after a warm-up (default 1 s, while the filter converges from the paper's
//! initial guess):
//!
//! - Table 7: per joint, the mean position innovation (residual), the mean of its normalised
//!   autocorrelation over lags 1–20 (the runtime's `FilterHealth`), the mean state error `x − x̂` (with `x`
//!   the wearer's joint angles and speeds, which the filter estimates) for position and velocity and the
//!   percentage of filter steps on which it exceeded `√P_ii`;
//! - Table 9: per joint, the RMS difference between the reference (the filter's prediction at the control
//!   rate) and the leg's actual position and velocity, over all 1 ms samples.

pub use super::config::{
    ASSISTANCE_MARGIN, AUTOCORRELATION_LAGS, JOINTS, SensorNoise, WalkingConfig, WalkingError,
    sized_assistance,
};
pub use super::records::{
    ActuatorSummary, ControlSample, FilterSample, JointHealth, JointTracking, MassSummary,
    TransitionRecord, WalkingRun,
};

use super::anthropometry::{LegFriction, LegSegments};
use super::config::DEG;
use super::estimator::DualEstimator;
use super::estimator::TorqueObservation;
use super::plant::{
    ComputedTorqueModel, LegModel, PLANT_OUTPUTS, WalkingPlant, axial_reaction, join,
    passive_ankle_torque,
};
use super::records::{
    PendingControl, PendingFilter, control_records, filter_records, summarize_masses,
    transition_label,
};
use super::reference::{ControlRatePredictor, ReferenceFilter};
use super::wearer::{Wearer, WearerConfig};
use bgc_runtime::control::{
    ControlError, GaitSupervisor, GrfSample, ImpedanceController, ImpedanceGains, JointState, Leg,
    LegMode,
};
use bgc_runtime::estimation::EstimationError;
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{Method, SampledLoopConfig, SolverOptions, simulate_sampled_loop};
use nalgebra::{Matrix3, SVector, Vector3};

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
    // The wearer hands the assisted share over when the exoskeleton starts assisting.
    let wearer = Wearer::new(&WearerConfig {
        assistance_onset: cfg.assist_from,
        ..cfg.wearer
    });
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
    let mut reference_filter = ReferenceFilter::new(cfg.reference_bandwidth, cfg.control_period)?;
    let mut torque_buffer: Vec<Vector3<f64>> = Vec::with_capacity(cfg.filter_decimation);
    let mut predictor = ControlRatePredictor {
        model: estimator.estimated_model(),
        state: estimator.state(),
    };
    let mut failure: Option<WalkingError> = None;
    let mut last_link_torque = Vector3::<f64>::zeros();
    let mut link_torque_sum = Vector3::<f64>::zeros();
    let mut period_start = JointState {
        q: start.q,
        qd: start.qd,
    };
    let mut pending_filter: Vec<PendingFilter> =
        Vec::with_capacity(samples / cfg.filter_decimation);
    let mut pending_control: Vec<PendingControl> = Vec::with_capacity(samples + 1);
    let mut transitions = Vec::new();
    // What the controller knows of the leg besides the masses: its geometry and the friction of Table 8.
    let known_leg = plant.leg;
    let mut last_friction = Vector3::<f64>::zeros();
    let mut friction_sum = Vector3::<f64>::zeros();

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
        // The stance term of Eq. (2) while the right insole reads a load (P of Eq. 30 is defined).
        let ground_reaction = if step.right_index.is_some() {
            axial_reaction(
                right.heel + right.ball,
                &known_leg.dynamics.ankle_position(&state.q),
            )
        } else {
            nalgebra::Vector2::zeros()
        };
        let ground_torque =
            known_leg.dynamics.ankle_jacobian(&state.q).transpose() * ground_reaction;
        let friction = known_leg.friction_torque(&state.q, &state.qd);
        if k > 0 {
            torque_buffer.push(Vector3::new(y[3], y[4], y[5]));
            // Generalised torque on the links over the elapsed control period: the held actuator torque,
            // the brace torque and the ground reaction (trapezoidal means of their two readings).
            link_torque_sum += last_link_torque + (human_torque + ground_torque) * 0.5;
            friction_sum += (last_friction + friction) * 0.5;
        }
        last_friction = friction;
        if k > 0 && k.is_multiple_of(cfg.filter_decimation) {
            let observation = TorqueObservation {
                torque: link_torque_sum / cfg.filter_decimation as f64,
                q: (period_start.q + state.q) * 0.5,
                qd: (period_start.qd + state.qd) * 0.5,
                qdd: (state.qd - period_start.qd) / estimator.sample_time(),
                friction: friction_sum / cfg.filter_decimation as f64,
            };
            let learn = (t >= cfg.learn_from).then_some(&observation);
            link_torque_sum = Vector3::zeros();
            friction_sum = Vector3::zeros();
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
                    predictor.restart(estimator.estimated_model(), estimator.state());
                }
                Err(source) => {
                    failure = Some(WalkingError::Estimation { time: t, source });
                    return Vector3::zeros();
                }
            }
            torque_buffer.clear();
        }
        let Some(mut target) =
            predictor.advance(&Vector3::new(y[3], y[4], y[5]), cfg.control_period)
        else {
            failure = Some(WalkingError::Estimation {
                time: t,
                source: EstimationError::NonFiniteModelOutput {
                    function: "control-rate prediction",
                    sigma_point: 0,
                },
            });
            return Vector3::zeros();
        };
        if !cfg.acceleration_feedforward {
            target.qdd = Vector3::zeros();
        }
        let reference = reference_filter.next(&target);
        let dynamics = ComputedTorqueModel {
            leg: estimator.estimated_model(),
            ground_torque,
        };
        let command = match controller.torque(&dynamics, &state, &reference, &human_torque) {
            Ok(c) => c,
            Err(source) => {
                failure = Some(WalkingError::Control { time: t, source });
                return Vector3::zeros();
            }
        };
        let Some(deliverable) = passive_ankle_torque(
            &dynamics.leg.dynamics.mass_matrix(&state.q),
            &command.unlimited_torque,
        ) else {
            failure = Some(WalkingError::Control {
                time: t,
                source: ControlError::NonFiniteModel { term: "M(q)" },
            });
            return Vector3::zeros();
        };
        let assisting = t >= cfg.assist_from;
        let (actuator, demanded) = if assisting {
            (WalkingPlant::actuator(&deliverable), deliverable)
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        last_link_torque = actuator + (human_torque + ground_torque) * 0.5;
        if k == 0 {
            period_start = state;
        }
        pending_control.push(PendingControl {
            k,
            reference,
            actuator,
            demanded,
            human_torque,
            ground_reaction,
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
    let filtered = filter_records(&pending_filter, cfg, &wearer, &segments)?;
    let (filter, table7, mean_nis) = (filtered.samples, filtered.table7, filtered.mean_nis);
    let control_summary = control_records(&pending_control, &trajectory.states, cfg, &wearer);
    let masses = summarize_masses(&filter, cfg, &segments, &wearer);
    Ok(WalkingRun {
        table7,
        table9: control_summary.table9,
        masses,
        mean_nis,
        actuators: control_summary.actuators,
        assistance: wearer.assistance.into(),
        peak_joint_torque_demand: plant
            .peak_joint_torque_demand(cfg.warmup, cfg.duration, samples + 1)
            .into(),
        transitions,
        supervisor_faults,
        filter,
        control: control_summary.samples,
    })
}
