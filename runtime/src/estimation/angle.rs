//! The two-state joint-angle Kalman filter of paper 001 (Eqs. 2–6): a gyro-driven angle with an unknown gyro
//! bias, corrected by the angle the accelerometer sees in the direction of gravity.
//!
//! State `x = [θ, b]ᵀ` (angle, gyro bias), input `u = ω` (gyro rate), measurement `z = θ_acc` (Eq. 2):
//!
//! `x[k+1] = A x[k] + B ω[k]`, `A = [[1, −Δt], [0, 1]]`, `B = [Δt, 0]ᵀ`, `z = H x`, `H = [1, 0]`,
//!
//! and the five recursions of Eq. 6 (prediction, covariance prediction, gain, correction, covariance; the
//! covariance correction here in Joseph form).
//!
//! **Paper inconsistency.** Eq. 5 prints the state as `[θ, θ̇]` with `A = [[1, Δt], [0, 1]]`,
//! `B = [Δt²/2, Δt]ᵀ` and `u(t) = θ(t)`, and Eq. 6 predicts with `x̂⁻ = A x̂` (no input). Taken literally, the
//! gyro never enters the filter, yet the text then says the innovation `z − H x̂⁻` is replaced by `θ − θ̄`,
//! the accelerometer angle (Eq. 2) minus the gyro-integrated angle (Eq. 4). That is exactly the innovation of
//! the filter above, whose prediction integrates the gyro (Eq. 4) and whose second state absorbs the gyro's
//! drift; it is also the standard form for an IMU angle filter. We therefore implement the angle/bias form.
//! The paper's tuning `P(0) = I`, `Q = diag(10, 0.003)` ([`PAPER_P0`], [`PAPER_Q`]) belongs to its
//! `[θ, θ̇]` state in degrees; the paper gives no `R`.
//!
//! Eq. 2 writes `θ = actg(−a_z / √(a_x² + a_y²))`; we read `actg` as the arctangent and evaluate it with
//! `atan2`, which is the same for `√(a_x² + a_y²) > 0` and defined when it is zero ([`accelerometer_angle`]).

use super::fault::{EstimationError, UpdateOutcome};
use super::kalman::{KalmanFilter, LinearDiscreteModel};
use nalgebra::{Matrix1, Matrix1x2, Matrix2, Matrix2x1, Vector1, Vector2};

/// The paper's initial covariance `P(0) = I`.
pub const PAPER_P0: [f64; 2] = [1.0, 1.0];
/// The paper's process noise `Q = diag(10, 0.003)` (its state, degrees).
pub const PAPER_Q: [f64; 2] = [10.0, 0.003];

/// The tilt angle from the accelerometer's gravity components (Eq. 2), in radians.
pub fn accelerometer_angle(acc_x: f64, acc_y: f64, acc_z: f64) -> f64 {
    (-acc_z).atan2(acc_x.hypot(acc_y))
}

/// The angle/gyro-bias Kalman filter.
#[derive(Clone, Debug)]
pub struct AngleKalmanFilter {
    kf: KalmanFilter<2, 1, 1>,
    /// The filter a step works on, a copy of `kf` made by `clone_from` (which allocates nothing), swapped with
    /// `kf` when the step succeeds.
    next: KalmanFilter<2, 1, 1>,
}

impl AngleKalmanFilter {
    /// A filter with sample interval `dt`, process-noise variances per step `q_angle` and `q_bias`, measurement
    /// variance `r` of the accelerometer angle, and initial estimate `(angle0, bias0)` with covariance `p0`.
    pub fn new(
        dt: f64,
        q_angle: f64,
        q_bias: f64,
        r: f64,
        angle0: f64,
        bias0: f64,
        p0: Matrix2<f64>,
    ) -> Result<Self, EstimationError> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(EstimationError::InvalidSetting {
                name: "dt",
                value: dt,
                reason: "the sample interval must be positive and finite",
            });
        }
        let model = LinearDiscreteModel {
            a: Matrix2::new(1.0, -dt, 0.0, 1.0),
            b: Matrix2x1::new(dt, 0.0),
            c: Matrix1x2::new(1.0, 0.0),
            d: Matrix1::zeros(),
        };
        let q = Matrix2::new(q_angle, 0.0, 0.0, q_bias);
        let kf = KalmanFilter::new(model, q, Matrix1::new(r), Vector2::new(angle0, bias0), p0)?;
        Ok(AngleKalmanFilter {
            next: kf.clone(),
            kf,
        })
    }

    /// One sample: predict with the gyro rate, correct with the accelerometer angle. A non-finite gyro rate,
    /// or one so large that the step overflows, is an error and nothing changes (the prediction is not kept
    /// either); a non-finite accelerometer angle is rejected and the prediction kept.
    pub fn step(
        &mut self,
        gyro_rate: f64,
        accel_angle: f64,
    ) -> Result<UpdateOutcome, EstimationError> {
        let u = Vector1::new(gyro_rate);
        let next = &mut self.next;
        next.clone_from(&self.kf);
        next.predict(&u)?;
        let outcome = next.update(&Vector1::new(accel_angle), &u)?;
        std::mem::swap(&mut self.kf, &mut self.next);
        Ok(outcome)
    }

    /// The angle estimate.
    pub fn angle(&self) -> f64 {
        self.kf.state()[0]
    }

    /// The gyro bias estimate.
    pub fn bias(&self) -> f64 {
        self.kf.state()[1]
    }

    /// The underlying Kalman filter (covariance, innovation, fault policy).
    pub fn filter(&self) -> &KalmanFilter<2, 1, 1> {
        &self.kf
    }

    /// Mutable access to the underlying filter, e.g. to set a NIS gate.
    pub fn filter_mut(&mut self) -> &mut KalmanFilter<2, 1, 1> {
        &mut self.kf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::Rng;

    #[test]
    fn accelerometer_angle_of_known_gravity_directions() {
        assert!((accelerometer_angle(1.0, 0.0, 0.0)).abs() < 1e-15);
        assert!((accelerometer_angle(0.0, 1.0, -1.0) - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert!((accelerometer_angle(0.0, 0.0, -9.81) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    }

    /// A pendulum-like swing θ = 0.5 sin(2π·0.5 t) rad sampled at 100 Hz; the gyro has a bias of 0.05 rad/s and
    /// noise σ = 0.02 rad/s, the accelerometer angle noise σ = 0.05 rad. The filter must find the bias and
    /// track the angle far better than the raw accelerometer angle, and without the drift of pure integration
    /// (which accumulates 0.05 rad/s · 20 s = 1 rad).
    #[test]
    fn tracks_synthetic_swing_and_finds_gyro_bias() {
        let dt = 0.01;
        let (bias, sg, sa) = (0.05, 0.02, 0.05);
        let mut f =
            AngleKalmanFilter::new(dt, 1e-6, 1e-8, sa * sa, 0.0, 0.0, Matrix2::identity()).unwrap();
        let mut rng = Rng::new(11);
        let w = 2.0 * std::f64::consts::PI * 0.5;
        let (mut se_kf, mut se_acc, mut n) = (0.0, 0.0, 0);
        let mut integrated = 0.0;
        for k in 0..2000 {
            let t = k as f64 * dt;
            let gyro = 0.5 * w * (w * t).cos() + bias + rng.gaussian(0.0, sg);
            integrated += gyro * dt;
            let theta_next = 0.5 * (w * (t + dt)).sin();
            let acc = theta_next + rng.gaussian(0.0, sa);
            assert!(f.step(gyro, acc).unwrap().is_accepted());
            if k >= 1000 {
                se_kf += (f.angle() - theta_next).powi(2);
                se_acc += (acc - theta_next).powi(2);
                n += 1;
            }
        }
        let (rms_kf, rms_acc) = ((se_kf / n as f64).sqrt(), (se_acc / n as f64).sqrt());
        assert!((f.bias() - bias).abs() < 0.01, "bias {}", f.bias());
        assert!(rms_kf < 0.3 * rms_acc, "kf {rms_kf} acc {rms_acc}");
        let theta_end = 0.5 * (w * 20.0).sin();
        assert!(
            (integrated - theta_end).abs() > 0.8,
            "pure integration drifts"
        );
        assert!((f.angle() - theta_end).abs() < 0.05);
    }

    #[test]
    fn nan_accelerometer_sample_is_rejected_and_prediction_kept() {
        let mut f =
            AngleKalmanFilter::new(0.01, 1e-6, 1e-8, 1e-3, 0.2, 0.0, Matrix2::identity()).unwrap();
        let out = f.step(1.0, f64::NAN).unwrap();
        assert!(!out.is_accepted());
        // Prediction only: θ = 0.2 + 0.01 · (1 − 0).
        assert!((f.angle() - 0.21).abs() < 1e-15);
        assert!(f.step(f64::INFINITY, 0.0).is_err());
        assert!((f.angle() - 0.21).abs() < 1e-15);
    }
}
