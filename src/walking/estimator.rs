//! The dual UKF of Sado et al. (2018), Eqs. 6–27, on the runtime's [`DualUkf`] with separate observations
//! for its two filters ([`DualUkf::step_separate`]).
//!
//! - **State filter** (Eqs. 6–22): `x = [q, q̇]`, observed through the joint position sensors
//!   (`y = q + n`). The time update integrates Eq. (8) with the current mass estimate `ŵ` over one filter
//!   period, in sub-steps of classical Runge–Kutta that each hold one joint-torque reading of the elapsed
//!   period (`u = τ_a + τ_h − Jᵀ F` as the joint torque sensors and insoles give it).
//! - **Parameter filter** (Eqs. 23–27): `w = [m₁, m₂, m₃]` (foot, shank, thigh), a random walk whose
//!   process-noise covariance is the RLS-forgetting choice of Eq. (27), `P_r = (λ⁻¹ − 1) P_w`, so the time
//!   update is `P_w⁻ = P_w / λ`. Its observation is the torque output of Eqs. (24)–(25):
//!   `d = Y(x, w) + e = M(q; w) q̈ + C(q, q̇; w) q̇ + G(q; w) + τ̄_f + e` ([`TorqueObservation`]): the
//!   mean generalised torque on the exoskeleton's links over the period (actuators, braces and the ground
//!   reaction's `Jᵀ R`), with their kinematics at mid-period and the mean acceleration, read from the torque
//!   sensors, insoles, encoders and motor rpm. The friction `τ̄_f` of Eq. (3) does not depend on the masses;
//!   it is averaged over the period at the measured joint speeds (its Coulomb term changes within a few
//!   milliseconds around a speed reversal, so evaluating it once at the mid-period speed leaves a bias
//!   that the parameter filter reads as mass: 0.4 kg on m₃ in stance in a noise-free run).
//!
//! Why not the state filter's own `x̂` and `q̈̂` in `Y`: the state filter's velocity is dominated by its model
//! (the paper's `P_v` trusts the model far more than the 0.9° position sensors), so its acceleration is the
//! model's own `M(ŵ)⁻¹(u − …)` and `Y(x̂, q̈̂, ŵ) ≈ u` at whatever `ŵ` is: the torque residual carries almost
//! no information about the masses. With the noise-free gait the masses settled 8 kg off that way. The
//! information about `w` is in measured kinematics, so `Y` is evaluated on them (the runtime's `Y(x̂, u, w)`
//! is given them and ignores `x̂`).
//!
//! The two filters alternate as in the paper's Fig. 5: the state step uses the latest `ŵ`, the parameter
//! step follows it.
//!
//! Masses below `min_mass_fraction` of their initial values are clamped when the state filter uses them,
//! so that `M(q)` stays positive definite whatever the parameter filter does; the estimate itself is not
//! altered.

use super::anthropometry::{LegFriction, LegSegments};
use super::plant::{LegModel, join, split};
use bgc_runtime::estimation::dual_ukf::{DualUkf, ParameterObservation};
use bgc_runtime::estimation::{EstimationError, SigmaPoints, UnscentedKalmanFilter, UpdateOutcome};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

const DEG: f64 = std::f64::consts::PI / 180.0;

/// Settings of the dual UKF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualUkfConfig {
    /// Filter period `T` (s).
    pub sample_time: f64,
    /// Sigma-point spread `α`, prior weight `β`, secondary scaling `κ` (Eqs. 13, 20).
    pub alpha: f64,
    pub beta: f64,
    pub kappa: f64,
    /// Diagonal of the state process noise `P_v` per period: deg² for `q`, (deg/s)² for `q̇`.
    pub process_noise: [f64; 6],
    /// Diagonal of the position measurement noise `P_n` (deg²).
    pub measurement_noise: [f64; 3],
    /// Initial state `[q; q̇]` (deg, deg/s).
    pub initial_state: [f64; 6],
    /// Diagonal of the initial state covariance: deg², (deg/s)².
    pub initial_covariance: [f64; 6],
    /// Initial mass estimate `[m₁, m₂, m₃]` (kg).
    pub initial_masses: [f64; 3],
    /// Initial mass standard deviations (kg).
    pub initial_mass_std: [f64; 3],
    /// RLS forgetting factor `λ_RLS ∈ (0, 1]` (Eq. 27).
    pub forgetting: f64,
    /// Standard deviation of the torque observation error `e` per joint (N m): the torque sensor noise and
    /// the joint's inertia times the noise of the measured acceleration.
    pub torque_error_std: [f64; 3],
    /// Smallest fraction of the initial masses the state filter will use.
    pub min_mass_fraction: f64,
}

/// The torque output of Eq. (24) with the kinematics it belongs to, over one filter period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorqueObservation {
    /// Mean joint torque over the period (N m).
    pub torque: Vector3<f64>,
    /// Joint angles and speeds at mid-period (rad, rad/s).
    pub q: Vector3<f64>,
    pub qd: Vector3<f64>,
    /// Mean acceleration over the period (rad/s²).
    pub qdd: Vector3<f64>,
    /// Mean friction torque `τ_f` of Eq. (3) over the period at the measured joint angles and speeds (N m).
    pub friction: Vector3<f64>,
}

/// One step's outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualStep {
    /// Position innovation `y − ŷ⁻` (rad).
    pub innovation: Vector3<f64>,
    /// Its covariance.
    pub innovation_covariance: Matrix3<f64>,
    /// Normalised innovation squared of the state filter.
    pub nis: Option<f64>,
}

/// The dual UKF.
#[derive(Clone, Debug)]
pub struct DualEstimator {
    filter: DualUkf<6, 3, 3, 3, 13, 7>,
    segments: LegSegments,
    friction: LegFriction,
    cfg: DualUkfConfig,
    acceleration: Vector3<f64>,
}

fn torque_noise(cfg: &DualUkfConfig) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::from(cfg.torque_error_std.map(|s| s * s)))
}

/// The masses clamped from below at `min_mass_fraction` of the initial ones.
fn clamp_masses(cfg: &DualUkfConfig, w: &Vector3<f64>) -> Vector3<f64> {
    let floor = Vector3::from(cfg.initial_masses) * cfg.min_mass_fraction;
    w.zip_map(&floor, f64::max)
}

fn diag6(d: &[f64; 6], scale: [f64; 6]) -> Matrix6<f64> {
    Matrix6::from_diagonal(&Vector6::from_fn(|i, _| d[i] * scale[i]))
}

impl DualEstimator {
    /// A dual UKF for a leg of the given geometry (`segments` supplies lengths, centres of mass and radii of
    /// gyration; its masses are replaced by the estimates) and friction model.
    pub fn new(
        segments: LegSegments,
        friction: LegFriction,
        cfg: DualUkfConfig,
    ) -> Result<Self, EstimationError> {
        if !(cfg.sample_time.is_finite() && cfg.sample_time > 0.0) {
            return Err(EstimationError::InvalidSetting {
                name: "sample_time",
                value: cfg.sample_time,
                reason: "the filter period must be finite and positive",
            });
        }
        if !(cfg.forgetting > 0.0 && cfg.forgetting <= 1.0) {
            return Err(EstimationError::InvalidSetting {
                name: "lambda_RLS",
                value: cfg.forgetting,
                reason: "the forgetting factor must lie in (0, 1]",
            });
        }
        if let Some(&v) = cfg
            .torque_error_std
            .iter()
            .find(|v| !(v.is_finite() && **v > 0.0))
        {
            return Err(EstimationError::InvalidSetting {
                name: "torque_error_std",
                value: v,
                reason: "the torque observation error must be finite and positive",
            });
        }
        if let Some(&m) = cfg
            .initial_masses
            .iter()
            .find(|m| !(m.is_finite() && **m > 0.0))
        {
            return Err(EstimationError::InvalidSetting {
                name: "initial_masses",
                value: m,
                reason: "link masses must be finite and positive",
            });
        }
        if !(cfg.min_mass_fraction > 0.0 && cfg.min_mass_fraction <= 1.0) {
            return Err(EstimationError::InvalidSetting {
                name: "min_mass_fraction",
                value: cfg.min_mass_fraction,
                reason: "the mass floor must be a fraction in (0, 1] of the initial masses",
            });
        }
        let d2 = DEG * DEG;
        let units = [d2, d2, d2, d2, d2, d2];
        let q = diag6(&cfg.process_noise, units);
        let r = Matrix3::from_diagonal(&Vector3::from(cfg.measurement_noise)) * d2;
        let x0 = Vector6::from(cfg.initial_state) * DEG;
        let p0 = diag6(&cfg.initial_covariance, units);
        let state = UnscentedKalmanFilter::new(
            SigmaPoints::new(cfg.alpha, cfg.beta, cfg.kappa)?,
            q,
            r,
            x0,
            p0,
        )?;
        let w0 = Vector3::from(cfg.initial_masses);
        let pw0 = Matrix3::from_diagonal(&Vector3::from(cfg.initial_mass_std).map(|s| s * s));
        let filter = DualUkf::new(
            state,
            SigmaPoints::new(cfg.alpha, cfg.beta, cfg.kappa)?,
            w0,
            pw0,
            cfg.forgetting,
        )?;
        Ok(DualEstimator {
            filter,
            segments,
            friction,
            cfg,
            acceleration: Vector3::zeros(),
        })
    }

    /// The masses the state filter and the controller use: the estimate, clamped from below.
    pub fn usable_masses(&self) -> Vector3<f64> {
        clamp_masses(&self.cfg, self.filter.parameters())
    }

    /// The leg model at the usable masses.
    pub fn estimated_model(&self) -> LegModel {
        let w = self.usable_masses();
        LegModel::new(self.segments.with_masses([w[0], w[1], w[2]]), self.friction)
    }

    /// One filter period: `torques` are the joint-torque readings of the elapsed period, in order (at least
    /// one), `y` the joint positions (rad) at its end, `torque` the parameter filter's observation (`None`:
    /// the masses are held, e.g. while the state estimate converges from its initial guess). A step that
    /// fails leaves the filter unchanged.
    pub fn step(
        &mut self,
        torques: &[Vector3<f64>],
        y: &Vector3<f64>,
        torque: Option<&TorqueObservation>,
    ) -> Result<DualStep, EstimationError> {
        let n = torques.len();
        if n == 0 {
            return Err(EstimationError::InvalidSetting {
                name: "torque readings",
                value: 0.0,
                reason: "a filter period needs at least one joint-torque reading",
            });
        }
        if let Some(i) = torques
            .iter()
            .position(|t| t.iter().any(|v| !v.is_finite()))
        {
            return Err(EstimationError::NonFiniteInput { index: i });
        }
        if let Some(obs) = torque {
            let values = [obs.q, obs.qd, obs.qdd, obs.friction];
            if let Some(index) = values
                .iter()
                .flat_map(|v| v.iter())
                .position(|v| !v.is_finite())
            {
                return Err(EstimationError::NonFiniteInput { index });
            }
        }
        let mean_torque = torques.iter().sum::<Vector3<f64>>() / n as f64;
        let h = self.cfg.sample_time / n as f64;
        let (segments, friction, cfg) = (self.segments, self.friction, self.cfg);
        let model =
            |w: &Vector3<f64>| LegModel::new(segments.with_masses([w[0], w[1], w[2]]), friction);
        let observation = torque.map(|obs| ParameterObservation {
            d: obs.torque,
            noise: torque_noise(&cfg),
        });
        let outcome = self.filter.step_separate(
            &mean_torque,
            y,
            observation.as_ref(),
            |x, _, w| {
                let leg = model(&clamp_masses(&cfg, w));
                torques.iter().fold(*x, |x, tau| leg.rk4_step(&x, tau, h))
            },
            |x, _, _| x.fixed_rows::<3>(0).into_owned(),
            |_, _, w| match torque {
                Some(obs) => model(w).dynamics.inverse(&obs.q, &obs.qd, &obs.qdd) + obs.friction,
                None => Vector3::zeros(),
            },
        )?;
        let nis = match outcome.state {
            UpdateOutcome::Accepted { nis, .. } => Some(nis),
            UpdateOutcome::Rejected { .. } => None,
        };
        // The model's acceleration at the new estimate under the latest torque reading: the filter's
        // prediction of q̈ at this instant (a difference of successive velocity estimates would lag by half
        // a period and carry the velocity corrections).
        let latest = torques.last().copied().unwrap_or(mean_torque);
        self.acceleration = split(&self.estimated_model().derivative(&self.state(), &latest)).1;
        Ok(DualStep {
            innovation: *self.filter.innovation(),
            innovation_covariance: *self.filter.innovation_covariance(),
            nis,
        })
    }

    /// `x̂ = [q̂, q̂̇]` (rad, rad/s).
    pub fn state(&self) -> Vector6<f64> {
        *self.filter.state()
    }

    /// The state covariance.
    pub fn covariance(&self) -> Matrix6<f64> {
        *self.filter.state_covariance()
    }

    /// The estimated acceleration of the last period (rad/s²).
    pub fn acceleration(&self) -> Vector3<f64> {
        self.acceleration
    }

    /// The mass estimate `[m₁, m₂, m₃]` (kg).
    pub fn masses(&self) -> Vector3<f64> {
        *self.filter.parameters()
    }

    /// The mass covariance.
    pub fn mass_covariance(&self) -> Matrix3<f64> {
        *self.filter.parameter_covariance()
    }

    /// The filter period (s).
    pub fn sample_time(&self) -> f64 {
        self.cfg.sample_time
    }

    /// Re-initialises the state estimate (rad, rad/s) keeping the masses.
    pub fn set_state(
        &mut self,
        q: &Vector3<f64>,
        qd: &Vector3<f64>,
    ) -> Result<(), EstimationError> {
        let p = *self.filter.state_covariance();
        self.filter.state_filter_mut().set_state(join(q, qd), p)
    }
}
