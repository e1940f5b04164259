//! The estimation chain of the measurement system, per segment (paper Secs. 2.1.2 and 2.3):
//!
//! 1. **Accelerometer angle** (Eq. 2, [`accelerometer_angle`]) of every IMU sample.
//! 2. **Gyro integration** (Eqs. 3–4): `θ̄[k] = θ̄[k−1] + ω[k−1] Δt`, started at the first accelerometer angle
//!    (the paper starts at 0, which is the rig's starting angle but not the leg's).
//! 3. **IMU angle** from the angle/gyro-bias Kalman filter of Eqs. 5–6 ([`AngleKalmanFilter`]): the gyro
//!    integration of step 2 corrected by the accelerometer angle of step 1.
//! 4. **Vision** synchronised to the IMU samples by a first-order hold (Sec. 2.3.3): at each IMU time the angle is
//!    extrapolated along the line through the last two frames received (by their arrival stamps). A lost frame is
//!    skipped: the hold keeps extrapolating from the last two frames received. When the last frame is older than
//!    `max_vision_age`, vision is absent (NaN) at that sample.
//! 5. **Fusion** with the minimum-variance weights of Eq. 27 (Eq. 24, [`WeightedFusion`]), the variances being
//!    those measured on the rig with Eq. 28; then, optionally, the scalar Kalman estimator of Eqs. 19–21 on the
//!    weighted reading, with measurement variance the fused variance of Eq. 25 and process variance `q` per
//!    sample (a random walk: Eq. 20 predicts with the previous estimate).
//!
//! Faults: an IMU sample with a non-finite value is not an IMU reading (the fusion drops it, Eq. 27 over the
//! remaining source); the filter then predicts with the last finite gyro rate and skips the correction when the
//! accelerometer angle is not finite. When neither source reads, the fused estimate is the Eqs. 19–21 prediction,
//! or the IMU filter's prediction without that stage. Nothing is NaN in the fused output.

use super::error::{RehabError, non_negative, positive};
use super::sensors::{Frame, ImuSample};
use super::truth::Truth;
use bgc_runtime::estimation::angle::{AngleKalmanFilter, accelerometer_angle};
use bgc_runtime::estimation::fusion::{ErrorVariance, WeightedFusion};
use nalgebra::{Matrix2, Vector2};

/// Tuning of the IMU angle filter of Eqs. 5–6 (radians).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImuFilterTuning {
    /// Angle process variance per sample \[rad²\].
    pub q_angle: f64,
    /// Bias process variance per sample [(rad/s)²].
    pub q_bias: f64,
    /// Accelerometer-angle measurement variance \[rad²\]; the experiments measure it on the rig (Eq. 28).
    pub r: f64,
    /// Initial angle variance \[rad²\].
    pub p_angle0: f64,
    /// Initial bias variance [(rad/s)²].
    pub p_bias0: f64,
}

impl ImuFilterTuning {
    /// The paper's tuning (Sec. 2.1.2): `P(0) = I` and `Q = diag(10, 0.003)` in degrees, read for the angle/bias
    /// state as 10 deg² and 0.003 (deg/s)² per sample. The paper gives no `R`; this sets 1 deg², to be replaced
    /// by the accelerometer-angle variance measured on the rig.
    pub fn paper() -> Self {
        let d2 = std::f64::consts::PI.powi(2) / (180.0 * 180.0);
        ImuFilterTuning {
            q_angle: 10.0 * d2,
            q_bias: 0.003 * d2,
            r: d2,
            p_angle0: d2,
            p_bias0: d2,
        }
    }
}

/// Per-sample estimates of one segment at the IMU sample times.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SourceEstimates {
    pub times: Vec<f64>,
    /// True angle \[rad\].
    pub truth: Vec<f64>,
    /// Eq. 2 \[rad\] (NaN when the accelerometer sample is not finite).
    pub accel_angle: Vec<f64>,
    /// Eq. 4 \[rad\].
    pub gyro_angle: Vec<f64>,
    /// Eqs. 5–6 \[rad\], always finite.
    pub imu: Vec<f64>,
    /// Whether the IMU sample was finite, i.e. `imu` is a reading the fusion may use.
    pub imu_valid: Vec<bool>,
    /// First-order-hold vision angle \[rad\] (NaN when no recent frame).
    pub vision: Vec<f64>,
}

/// Runs steps 1–4 on one segment's samples and frames; `dt` is the IMU sample interval and `truth`/`segment`
/// give the reference angle.
pub fn estimate_sources(
    truth: &Truth,
    segment: usize,
    samples: &[ImuSample],
    frames: &[Frame],
    dt: f64,
    tuning: &ImuFilterTuning,
    max_vision_age: f64,
) -> Result<SourceEstimates, RehabError> {
    positive("imu.dt", dt)?;
    positive("filter.q_angle", tuning.q_angle)?;
    non_negative("filter.q_bias", tuning.q_bias)?;
    positive("filter.r", tuning.r)?;
    positive("filter.p_angle0", tuning.p_angle0)?;
    positive("filter.p_bias0", tuning.p_bias0)?;
    positive("max_vision_age", max_vision_age)?;
    let accel: Vec<f64> = samples
        .iter()
        .map(|s| accelerometer_angle(s.acc[0], s.acc[1], s.acc[2]))
        .collect();
    let angle0 = accel.iter().copied().find(|a| a.is_finite()).unwrap_or(0.0);
    let mut kf = AngleKalmanFilter::new(
        dt,
        tuning.q_angle,
        tuning.q_bias,
        tuning.r,
        angle0,
        0.0,
        Matrix2::new(tuning.p_angle0, 0.0, 0.0, tuning.p_bias0),
    )
    .map_err(|source| RehabError::Estimation {
        stage: "the IMU angle filter",
        source,
    })?;
    let mut hold = FirstOrderHold::new(frames, max_vision_age);
    let mut out = SourceEstimates::default();
    let mut last_gyro = 0.0;
    let mut gyro_angle = angle0;
    for (k, s) in samples.iter().enumerate() {
        let reference = truth
            .state(segment, s.t)
            .ok_or(RehabError::BadSetting {
                name: "segment",
                value: segment as f64,
                reason: "no true motion for this segment at an IMU sample time",
            })?
            .angle;
        if k > 0 {
            // Eq. 4 and the prediction of Eq. 6 use the previous sample's rate.
            gyro_angle += last_gyro * dt;
            let z = accel.get(k).copied().unwrap_or(f64::NAN);
            kf.step(last_gyro, z)
                .map_err(|source| RehabError::Estimation {
                    stage: "the IMU angle filter",
                    source,
                })?;
        }
        if s.gyro.is_finite() {
            last_gyro = s.gyro;
        }
        let valid = s.gyro.is_finite() && s.acc.iter().all(|a| a.is_finite());
        out.times.push(s.t);
        out.truth.push(reference);
        out.accel_angle
            .push(accel.get(k).copied().unwrap_or(f64::NAN));
        out.gyro_angle.push(gyro_angle);
        out.imu.push(kf.angle());
        out.imu_valid.push(valid);
        out.vision.push(hold.at(s.t));
    }
    Ok(out)
}

/// The first-order hold of the vision stream (step 4).
struct FirstOrderHold<'a> {
    frames: &'a [Frame],
    next: usize,
    last: Option<(f64, f64)>,
    before_last: Option<(f64, f64)>,
    max_age: f64,
}

impl<'a> FirstOrderHold<'a> {
    fn new(frames: &'a [Frame], max_age: f64) -> Self {
        FirstOrderHold {
            frames,
            next: 0,
            last: None,
            before_last: None,
            max_age,
        }
    }

    /// The held angle at `t` (times must not decrease between calls).
    fn at(&mut self, t: f64) -> f64 {
        while let Some(f) = self.frames.get(self.next) {
            if f.arrival > t {
                break;
            }
            self.next += 1;
            let newer = self.last.is_none_or(|(a, _)| f.arrival > a);
            if f.angle.is_finite() && f.arrival.is_finite() && newer {
                self.before_last = self.last;
                self.last = Some((f.arrival, f.angle));
            }
        }
        match (self.before_last, self.last) {
            (_, None) => f64::NAN,
            (_, Some((a1, _))) if t - a1 > self.max_age => f64::NAN,
            (None, Some((_, v1))) => v1,
            (Some((a0, v0)), Some((a1, v1))) => v1 + (v1 - v0) * (t - a1) / (a1 - a0),
        }
    }
}

/// Step 5: the fused angle at every sample (finite everywhere).
pub fn fuse(
    est: &SourceEstimates,
    fusion: &WeightedFusion<2>,
    smoothing_q: Option<f64>,
) -> Result<Vec<f64>, RehabError> {
    if let Some(q) = smoothing_q {
        positive("smoothing q", q)?;
    }
    let mut out = Vec::with_capacity(est.times.len());
    // The scalar estimator of Eqs. 19–21: estimate and its variance.
    let mut state: Option<(f64, f64)> = None;
    let readings = est.imu.iter().zip(&est.imu_valid).zip(&est.vision);
    for ((&imu, &valid), &vision) in readings {
        let z = Vector2::new(if valid { imu } else { f64::NAN }, vision);
        let reading = fusion.fuse(&z).ok();
        let value = match (smoothing_q, reading) {
            (None, Some(r)) => r.value,
            (None, None) => imu,
            (Some(q), reading) => {
                let next = match (state, reading) {
                    (None, Some(r)) => (r.value, r.variance),
                    (None, None) => (imu, f64::INFINITY),
                    (Some((x, p)), Some(r)) => {
                        let p_pred = p + q; // Eq. 21
                        let gain = p_pred / (p_pred + r.variance); // Eq. 19
                        (x + gain * (r.value - x), (1.0 - gain) * p_pred) // Eq. 20
                    }
                    (Some((x, p)), None) => (x, p + q),
                };
                state = next.0.is_finite().then_some(next);
                if next.0.is_finite() { next.0 } else { imu }
            }
        };
        out.push(value);
    }
    Ok(out)
}

/// Eq. 28 of `estimate` against `reference` over the samples whose time is in `[from, to]` (non-finite estimates
/// are left out) \[rad²\].
pub fn error_variance(
    times: &[f64],
    estimate: &[f64],
    reference: &[f64],
    window: (f64, f64),
    what: &'static str,
) -> Result<f64, RehabError> {
    let mut ev = ErrorVariance::new();
    for ((&t, &e), &r) in times.iter().zip(estimate).zip(reference) {
        if t >= window.0 && t <= window.1 {
            ev.push(e, r);
        }
    }
    ev.variance().ok_or(RehabError::TooFewSamples {
        what,
        count: ev.count(),
    })
}
