//! Synthetic sensors: the MPU6050 inertial units read by the Arduino and sent by Bluetooth, and the camera of the
//! visual measurement unit (paper Secs. 2.1.3, 2.2 and 2.3.3).
//!
//! **IMU.** Each unit sits on its segment at radius `r` from the pivot, its `x` axis along the segment towards the
//! pivot, `z` along the direction of motion reversed, `y` lateral (so that Eq. 2 gives the segment angle when the
//! unit is still). It reads the specific force `a − g⃗` of its mounting point ([`super::truth`]) in its axes plus
//! white noise, and the angular rate about `y` plus the residual bias left by the start-up calibration (the paper's
//! Arduino stores the still reading as a constant and subtracts it, Sec. 2.3.3) plus white noise. Samples are
//! taken every `dt`; the paper's logs give `dt` (Eq. 28: samples 195..1447 span 2.0107..15.0016 s on the rig, so
//! 10.38 ms; Eq. 31: 358..1525 span 5.001..21.005 s on the exoskeleton, so 13.71 ms, four units on one Arduino).
//! Each sample carries the Arduino's time stamp, so the Bluetooth link's latency does not shift it.
//!
//! **Camera.** Frames are captured at `frame_rate` with a random phase; the markers at the segment's pivot and its
//! distal end are located with Gaussian pixel noise, and the angle is `atan2(Δx, −Δz)` of the two markers. A frame
//! reaches the fusion node `latency` after capture (image processing, Sec. 2.2.2) and is stamped on arrival, as a
//! ROS message is. A frame is lost (template matching failed, Sec. 4) with probability `lost_probability`,
//! independently; a lost frame is simply never delivered (see [`super::pipeline`] for how the gap is bridged).

use super::error::{RehabError, non_negative, positive};
use super::truth::Truth;
use bgc_runtime::noise::Rng;

/// Standard gravity \[m/s²\].
pub const GRAVITY: f64 = 9.81;

/// The inertial unit and its sampling.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImuSpec {
    /// Sample interval \[s\].
    pub dt: f64,
    /// Accelerometer noise per axis, standard deviation \[m/s²\].
    pub accel_noise: f64,
    /// Gyro noise, standard deviation \[rad/s\].
    pub gyro_noise: f64,
    /// Gyro bias left after the start-up calibration \[rad/s\].
    pub gyro_bias: f64,
}

/// The camera of the visual measurement unit.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CameraSpec {
    /// Frames per second \[Hz\].
    pub frame_rate: f64,
    /// Capture-to-arrival delay \[s\].
    pub latency: f64,
    /// Marker location noise per image axis, standard deviation \[px\].
    pub pixel_noise: f64,
    /// Image scale in the plane of motion \[px/m\].
    pub scale: f64,
    /// Probability that a frame is lost.
    pub lost_probability: f64,
}

/// One IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// Arduino time stamp \[s\].
    pub t: f64,
    /// Accelerometer `(x, y, z)` \[m/s²\].
    pub acc: [f64; 3],
    /// Gyro rate about `y`, bias-compensated by the calibration \[rad/s\].
    pub gyro: f64,
}

/// One delivered camera frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Arrival time at the fusion node, its time stamp \[s\].
    pub arrival: f64,
    /// Segment angle from the two markers \[rad\].
    pub angle: f64,
}

impl ImuSpec {
    fn check(&self) -> Result<(), RehabError> {
        positive("imu.dt", self.dt)?;
        non_negative("imu.accel_noise", self.accel_noise)?;
        non_negative("imu.gyro_noise", self.gyro_noise)?;
        if !self.gyro_bias.is_finite() {
            return Err(RehabError::BadSetting {
                name: "imu.gyro_bias",
                value: self.gyro_bias,
                reason: "must be finite",
            });
        }
        Ok(())
    }
}

impl CameraSpec {
    fn check(&self) -> Result<(), RehabError> {
        positive("camera.frame_rate", self.frame_rate)?;
        non_negative("camera.latency", self.latency)?;
        non_negative("camera.pixel_noise", self.pixel_noise)?;
        positive("camera.scale", self.scale)?;
        if !(0.0..1.0).contains(&self.lost_probability) {
            return Err(RehabError::BadSetting {
                name: "camera.lost_probability",
                value: self.lost_probability,
                reason: "must be in [0, 1)",
            });
        }
        Ok(())
    }
}

fn unknown_segment(segment: usize) -> RehabError {
    RehabError::BadSetting {
        name: "segment",
        value: segment as f64,
        reason: "no such segment in the true motion",
    }
}

/// The IMU samples of segment `segment` over the whole run, the unit mounted at `radius` \[m\] from the pivot.
pub fn sample_imu(
    truth: &Truth,
    segment: usize,
    radius: f64,
    spec: &ImuSpec,
    rng: &mut Rng,
) -> Result<Vec<ImuSample>, RehabError> {
    spec.check()?;
    non_negative("imu radius", radius)?;
    let t_end = truth.times.last().copied().unwrap_or(0.0);
    let mut out = Vec::new();
    let mut k = 0usize;
    loop {
        let t = k as f64 * spec.dt;
        if t > t_end {
            break;
        }
        let s = truth
            .state(segment, t)
            .ok_or_else(|| unknown_segment(segment))?;
        let a = s.point_acc(radius);
        // Specific force: the acceleration minus gravity (0, −g).
        let f = [a[0], a[1] + GRAVITY];
        let (sn, cs) = s.angle.sin_cos();
        let along = -f[0] * sn + f[1] * cs; // towards the pivot
        let tangential = f[0] * cs + f[1] * sn; // direction of increasing angle
        out.push(ImuSample {
            t,
            acc: [
                along + rng.gaussian(0.0, spec.accel_noise),
                rng.gaussian(0.0, spec.accel_noise),
                -tangential + rng.gaussian(0.0, spec.accel_noise),
            ],
            gyro: s.rate + spec.gyro_bias + rng.gaussian(0.0, spec.gyro_noise),
        });
        k += 1;
    }
    Ok(out)
}

/// What the camera gave over a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    /// The frames that reach the fusion node, in arrival order.
    pub frames: Vec<Frame>,
    /// The number of frames captured, lost ones included.
    pub captured: usize,
}

/// The camera frames of segment `segment` over the whole run.
pub fn capture_frames(
    truth: &Truth,
    segment: usize,
    spec: &CameraSpec,
    rng: &mut Rng,
) -> Result<Capture, RehabError> {
    spec.check()?;
    let length = truth
        .segments
        .get(segment)
        .ok_or_else(|| unknown_segment(segment))?
        .length;
    let t_end = truth.times.last().copied().unwrap_or(0.0);
    let period = 1.0 / spec.frame_rate;
    let phase = rng.uniform() * period;
    let mut out = Vec::new();
    let mut j = 0usize;
    loop {
        let t = phase + j as f64 * period;
        if t > t_end {
            break;
        }
        j += 1;
        let lost = rng.uniform() < spec.lost_probability;
        let s = truth
            .state(segment, t)
            .ok_or_else(|| unknown_segment(segment))?;
        let noise = spec.pixel_noise / spec.scale;
        let p0 = s.pivot_pos;
        let p1 = s.point(length);
        let dx = p1[0] - p0[0] + rng.gaussian(0.0, noise) - rng.gaussian(0.0, noise);
        let dz = p1[1] - p0[1] + rng.gaussian(0.0, noise) - rng.gaussian(0.0, noise);
        if !lost {
            out.push(Frame {
                arrival: t + spec.latency,
                angle: dx.atan2(-dz),
            });
        }
    }
    Ok(Capture {
        frames: out,
        captured: j,
    })
}
