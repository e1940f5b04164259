//! What a walking run records, and the figures of Tables 7 and 9 computed from it once the ground truth is
//! known.

use super::anthropometry::LegSegments;
use super::config::{AUTOCORRELATION_LAGS, DEG, JOINTS, WalkingConfig, WalkingError};
use super::plant::MOTOR_PEAK_TORQUE;
use super::plant::join;
use super::wearer::Wearer;
use bgc_runtime::control::JointReference;
use bgc_runtime::estimation::health::FilterHealth;
use nalgebra::{Matrix3, Matrix6, Vector2, Vector3, Vector6};
use serde::Serialize;

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
    /// Actuator torque delivered (N m).
    pub actuator_torque: [f64; 3],
    /// Torque the controller commanded before the motors' limits (N m).
    pub commanded_torque: [f64; 3],
    /// Ground reaction on the right foot the controller used, `(R_x, R_y)` (N).
    pub ground_reaction: [f64; 2],
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

/// What the motors did after the warm-up.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ActuatorSummary {
    /// Largest delivered torque per joint (N m).
    pub peak_torque: [f64; 3],
    /// Largest commanded torque per joint, before the limits (N m).
    pub peak_command: [f64; 3],
    /// RMS of the delivered torque per joint (N m).
    pub rms_torque: [f64; 3],
    /// Percentage of control periods in which the command exceeded the joint's rating (the passive ankle:
    /// not counted, 0).
    pub saturated_percent: [f64; 3],
}

/// Everything a walking run produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WalkingRun {
    pub table7: Vec<JointHealth>,
    pub table9: Vec<JointTracking>,
    pub masses: MassSummary,
    pub mean_nis: Option<f64>,
    pub actuators: ActuatorSummary,
    /// Share of the gait torque the wearer left to the exoskeleton, per joint.
    pub assistance: [f64; 3],
    /// Largest joint torque the gait needed (muscles and motors together) after the warm-up, per joint
    /// (N m).
    pub peak_joint_torque_demand: [f64; 3],
    pub transitions: Vec<TransitionRecord>,
    pub supervisor_faults: u64,
    #[serde(skip)]
    pub filter: Vec<FilterSample>,
    #[serde(skip)]
    pub control: Vec<ControlSample>,
}

pub(super) fn deg3(v: &Vector3<f64>) -> [f64; 3] {
    [v[0] / DEG, v[1] / DEG, v[2] / DEG]
}

pub(super) fn transition_label(t: bgc_runtime::control::Transition) -> &'static str {
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
pub(super) struct PendingFilter {
    pub(super) k: usize,
    pub(super) measured: Vector3<f64>,
    pub(super) estimate: Vector6<f64>,
    pub(super) covariance: Matrix6<f64>,
    pub(super) residual: Vector3<f64>,
    pub(super) residual_covariance: Matrix3<f64>,
    pub(super) masses: Vector3<f64>,
    pub(super) mass_covariance: Matrix3<f64>,
}

pub(super) struct PendingControl {
    pub(super) k: usize,
    pub(super) reference: JointReference<3>,
    pub(super) actuator: Vector3<f64>,
    pub(super) demanded: Vector3<f64>,
    pub(super) human_torque: Vector3<f64>,
    pub(super) ground_reaction: Vector2<f64>,
    pub(super) state: &'static str,
    pub(super) right_mode: &'static str,
    pub(super) right_index: Option<f64>,
    pub(super) left_index: Option<f64>,
}

/// The filter's records with their ground truth, Table 7 and the mean NIS.
pub(super) struct FilterSummary {
    pub(super) samples: Vec<FilterSample>,
    pub(super) table7: Vec<JointHealth>,
    pub(super) mean_nis: Option<f64>,
}

/// The filter's records with the ground truth (the wearer's motion, which the filter estimates), Table 7
/// and the mean NIS.
pub(super) fn filter_records(
    pending: &[PendingFilter],
    cfg: &WalkingConfig,
    wearer: &Wearer,
    segments: &LegSegments,
) -> Result<FilterSummary, WalkingError> {
    let true_masses = |t: f64| {
        let m = segments.masses();
        [m[0], m[1], m[2] + wearer.torso_load(t) * wearer.torso_mass]
    };
    let mut health = FilterHealth::<6, 3, AUTOCORRELATION_LAGS>::new();
    let scale6 = Matrix6::from_diagonal_element(1.0 / (DEG * DEG));
    let mut filter = Vec::with_capacity(pending.len());
    for p in pending {
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

    Ok(FilterSummary {
        samples: filter,
        table7,
        mean_nis: report.mean_nis,
    })
}

/// The control records with the leg's true states, Table 9 and what the motors did.
pub(super) struct ControlSummary {
    pub(super) samples: Vec<ControlSample>,
    pub(super) table9: Vec<JointTracking>,
    pub(super) actuators: ActuatorSummary,
}

/// The control records with the leg's true states, Table 9 and the actuator figures.
pub(super) fn control_records(
    pending: &[PendingControl],
    states: &[Vector6<f64>],
    cfg: &WalkingConfig,
    wearer: &Wearer,
) -> ControlSummary {
    let truth = |k: usize| -> Option<Vector6<f64>> { states.get(k).copied() };
    let mut control_samples = Vec::with_capacity(pending.len());
    let mut sq_pos = [0.0; 3];
    let mut sq_vel = [0.0; 3];
    let mut sq_pos_w = [0.0; 3];
    let mut sq_vel_w = [0.0; 3];
    let mut sq_torque = [0.0; 3];
    let mut saturated = [0usize; 3];
    let mut counted = 0usize;
    let mut peak = [0.0f64; 3];
    let mut peak_command = [0.0f64; 3];
    for p in pending {
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
                sq_torque[j] += p.actuator[j].powi(2);
                peak[j] = peak[j].max(p.actuator[j].abs());
                if MOTOR_PEAK_TORQUE[j] > 0.0 {
                    peak_command[j] = peak_command[j].max(p.demanded[j].abs());
                    saturated[j] += usize::from(p.demanded[j].abs() > MOTOR_PEAK_TORQUE[j]);
                }
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
            commanded_torque: [p.demanded[0], p.demanded[1], p.demanded[2]],
            ground_reaction: [p.ground_reaction[0], p.ground_reaction[1]],
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
    ControlSummary {
        samples: control_samples,
        table9,
        actuators: ActuatorSummary {
            peak_torque: peak,
            peak_command,
            rms_torque: sq_torque.map(|s| (s / denominator).sqrt()),
            saturated_percent: saturated.map(|c| 100.0 * c as f64 / denominator),
        },
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

pub(super) fn summarize_masses(
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
