//! Settings of the walking scenario and its errors.

use super::anthropometry::{LegFriction, LegSegments};
use super::estimator::DualUkfConfig;
use super::plant::{LegModel, MOTOR_PEAK_TORQUE, WalkingPlant};
use super::wearer::{Wearer, WearerConfig};
use bgc_runtime::control::{ControlError, GaitThresholds};
use bgc_runtime::estimation::EstimationError;
use bgc_runtime::sim::SimError;
use serde::Serialize;
use std::fmt;

pub(super) const DEG: f64 = std::f64::consts::PI / 180.0;
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
    /// Bandwidth `ω_r` (rad/s) of the reference filter between the dual UKF's predictions and Eq. (29)
    /// (see [`super::reference`]).
    pub reference_bandwidth: f64,
    /// Feed the control-rate prediction's acceleration forward through the reference filter (see
    /// [`super::reference`]); without it the reference lags the gait by about `2/ω_r`.
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
    ///
    /// Control settings the paper does not print: the impedance target of Eq. (29) is critically damped at
    /// 10 Hz (`M_r = I`, so the error dynamics are `ë + 2ω ė + ω² e = 0` per joint; a bandwidth for a
    /// 1 kHz joint loop that leaves the motors below their ratings in nearly every period), the reference
    /// filter at 2 Hz (fast enough to follow the prediction's drift between corrections, slow enough to keep
    /// the corrections' jitter out of the motors). The wearer leaves to the exoskeleton the share of the gait
    /// torque its motors can deliver ([`sized_assistance`]) from 0.5 s on.
    pub fn paper(duration: f64) -> Self {
        let segments = LegSegments::paper_subject();
        let mass_error = 0.2;
        let m = segments.masses();
        let assist_from = 0.5;
        let mut wearer = WearerConfig {
            duration: duration + 1.0,
            assistance_onset: assist_from,
            ..WearerConfig::default()
        };
        wearer.assistance = sized_assistance(&segments, &wearer);
        WalkingConfig {
            duration,
            control_period: 1e-3,
            filter_decimation: 10,
            warmup: 1.0,
            mass_error,
            learn_from: 0.5,
            assist_from,
            wearer,
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
            impedance_frequency: 2.0 * std::f64::consts::PI * 10.0,
            impedance_damping_ratio: 1.0,
            reference_bandwidth: 2.0 * std::f64::consts::PI * 2.0,
            acceleration_feedforward: true,
            supervisor: GaitThresholds::default(),
            seed: 7,
        }
    }
}

/// Fraction of a motor's rating that the assisted share of the nominal gait's peak torque may take; the
/// rest is headroom for the controller's corrections and the cycle-to-cycle variation.
pub const ASSISTANCE_MARGIN: f64 = 0.8;

/// The share of the gait torque each motor can take along the nominal gait (no cycle-to-cycle variation):
/// `a_j = min(1, ASSISTANCE_MARGIN · rated_j / peak_j |τ_gait,j|)`, zero at the passive ankle.
pub fn sized_assistance(segments: &LegSegments, wearer: &WearerConfig) -> [f64; 3] {
    let nominal = WalkingPlant {
        leg: LegModel::new(*segments, LegFriction::table8_right()),
        wearer: Wearer::new(&WearerConfig {
            rate_variation: 0.0,
            amplitude_variation: 0.0,
            duration: 2.0,
            ..*wearer
        }),
    };
    let peak = nominal.peak_joint_torque_demand(0.0, 1.0, 1001);
    std::array::from_fn(|j| {
        if MOTOR_PEAK_TORQUE[j] > 0.0 && peak[j] > 0.0 {
            (ASSISTANCE_MARGIN * MOTOR_PEAK_TORQUE[j] / peak[j]).min(1.0)
        } else {
            0.0
        }
    })
}
