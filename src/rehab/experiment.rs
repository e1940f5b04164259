//! The two experiments of the paper with their sensor set-ups: the pendulum rig run that measures the sensor
//! variances and gives the fusion weights (Sec. 2.3.3, Eqs. 27–30), and the exoskeleton test without load that
//! applies those weights to the thigh and calf (Sec. 3.1, Eqs. 31–35).
//!
//! The paper prints neither its sensors' noise nor its camera's frame rate; the set-up here is that of an MPU6050
//! on a vibrating rig (accelerometer noise 0.2 m/s² per axis, gyro noise 0.3 deg/s, a residual gyro bias of
//! 0.3 deg/s after the start-up calibration) and of a webcam tracking markers by template matching (20 frame/s,
//! 600 px/m in the plane of motion, 2.5 px marker noise, 60 ms from capture to the fusion node, 5 % of frames
//! lost). The IMU filter uses the paper's `Q` and, for `R`, the accelerometer-angle variance measured on the rig.
//!
//! The Eqs. 19–21 stage after the weighted fusion is left out by default: as the paper writes it (Eq. 20 predicts
//! with the previous estimate) it is a random walk, and on these moving angles its lag costs more than its
//! smoothing gains (with `q` = 1 deg² per sample E_fusion on the rig rises from 9.4 to 18.3 deg²).

use super::error::RehabError;
use super::generated::{PendulumRigModel, RehabLegModel};
use super::pipeline::{ImuFilterTuning, SourceEstimates, error_variance, estimate_sources, fuse};
use super::sensors::{CameraSpec, ImuSpec, capture_frames, sample_imu};
use super::sensors::{Frame, ImuSample};
use super::truth::{LegGeometry, RigGeometry, Truth, leg_truth, rig_truth};
use bgc_runtime::estimation::angle::accelerometer_angle;
use bgc_runtime::estimation::fusion::ErrorVariance;
use bgc_runtime::estimation::fusion::WeightedFusion;
use bgc_runtime::noise::Rng;
use nalgebra::Vector2;

/// Squared degrees per squared radian, to report E in deg² as the paper does.
pub const DEG2_PER_RAD2: f64 = (180.0 / std::f64::consts::PI) * (180.0 / std::f64::consts::PI);

/// Rig window of Eq. 28: samples 195..1447, t = 2.0107..15.0016 s.
pub const RIG_WINDOW: (f64, f64) = (2.0107, 15.0016);
/// Exoskeleton window of Eq. 31: samples 358..1525, t = 5.001..21.005 s.
pub const LEG_WINDOW: (f64, f64) = (5.001, 21.005);

/// The sensors, their processing and the run.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Setup {
    pub imu: ImuSpec,
    pub camera: CameraSpec,
    pub filter: ImuFilterTuning,
    /// IMU mounting radius from the pivot, per segment (rig: the pendulum; leg: thigh, calf) \[m\].
    pub imu_radius: [f64; 2],
    /// Oldest vision frame the first-order hold extrapolates from \[s\].
    pub max_vision_age: f64,
    /// Process variance per sample of the Eqs. 19–21 stage after the weighted fusion \[rad²\]; `None` leaves the
    /// stage out.
    pub smoothing_q: Option<f64>,
    /// Step of the true-motion grid \[s\].
    pub truth_dt: f64,
    /// Length of the run \[s\].
    pub t_end: f64,
    /// Window of the E figures \[s\].
    pub window: (f64, f64),
}

impl Setup {
    /// The rig run: one IMU sampled every 10.38 ms (Eq. 28's sample numbering), a 20 frame/s camera.
    pub fn rig() -> Self {
        let dt = (RIG_WINDOW.1 - RIG_WINDOW.0) / (1447.0 - 195.0);
        Setup {
            imu: ImuSpec {
                dt,
                accel_noise: 0.20,
                gyro_noise: 0.3_f64.to_radians(),
                gyro_bias: 0.3_f64.to_radians(),
            },
            camera: CameraSpec {
                frame_rate: 20.0,
                latency: 0.06,
                pixel_noise: 2.5,
                scale: 600.0,
                lost_probability: 0.05,
            },
            filter: ImuFilterTuning::paper(),
            imu_radius: [0.20, 0.20],
            max_vision_age: 0.15,
            smoothing_q: None,
            truth_dt: 1e-3,
            t_end: 16.0,
            window: RIG_WINDOW,
        }
    }

    /// The exoskeleton test: the same sensors, four IMUs on one Arduino sampled every 13.71 ms (Eq. 31's sample
    /// numbering), units at 0.20 m below the hip and 0.12 m below the knee (the calf cuff).
    pub fn leg() -> Self {
        let dt = (LEG_WINDOW.1 - LEG_WINDOW.0) / (1525.0 - 358.0);
        let rig = Setup::rig();
        Setup {
            imu: ImuSpec { dt, ..rig.imu },
            imu_radius: [0.20, 0.12],
            t_end: 22.0,
            window: LEG_WINDOW,
            ..rig
        }
    }
}

/// The E figures of Eq. 28 of one segment \[deg²\].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Figures {
    pub e_vision: f64,
    pub e_imu: f64,
    pub e_fusion: f64,
    /// The accelerometer angle alone (Eq. 2).
    pub e_accel: f64,
}

/// One segment's run: estimates, fused angle and figures.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentRun {
    pub name: &'static str,
    pub estimates: SourceEstimates,
    pub fused: Vec<f64>,
    pub figures: Figures,
    /// Frames delivered and frames captured.
    pub frames_delivered: usize,
    pub frames_captured: usize,
}

/// The rig run: the segment and the fusion it calibrated.
#[derive(Clone, Debug, PartialEq)]
pub struct RigRun {
    pub segment: SegmentRun,
    /// Variances measured on the rig (Eq. 28) of the IMU and the vision \[rad²\].
    pub variances: [f64; 2],
    /// Weights of Eq. 27 for the IMU and the vision.
    pub weights: [f64; 2],
    /// Accelerometer-angle variance measured on the rig (Eq. 28), the IMU filter's `R` \[rad²\].
    pub accel_variance: f64,
    /// Fused variance of Eq. 25 \[rad²\].
    pub fused_variance: f64,
    pub calibration: Calibration,
}

/// Per-stream seeds derived from one seed, so that each sensor's noise is its own stream.
fn stream(seed: u64, segment: usize, sensor: u64) -> Rng {
    Rng::new(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ ((segment as u64) << 8)
            ^ sensor.wrapping_mul(0xD1B5_4A32_D192_ED03),
    )
}

/// The synthetic sensor data of one segment.
struct Recorded {
    samples: Vec<ImuSample>,
    frames: Vec<Frame>,
    frames_captured: usize,
}

fn record(truth: &Truth, segment: usize, setup: &Setup, seed: u64) -> Result<Recorded, RehabError> {
    let radius = setup
        .imu_radius
        .get(segment)
        .copied()
        .ok_or(RehabError::BadSetting {
            name: "segment",
            value: segment as f64,
            reason: "no IMU radius for this segment",
        })?;
    let samples = sample_imu(
        truth,
        segment,
        radius,
        &setup.imu,
        &mut stream(seed, segment, 1),
    )?;
    let capture = capture_frames(truth, segment, &setup.camera, &mut stream(seed, segment, 2))?;
    Ok(Recorded {
        samples,
        frames: capture.frames,
        frames_captured: capture.captured,
    })
}

/// Steps 1–5 on recorded data, and the figures.
fn process(
    truth: &Truth,
    segment: usize,
    name: &'static str,
    rec: Recorded,
    setup: &Setup,
    calibration: &Calibration,
) -> Result<SegmentRun, RehabError> {
    let est = estimate_sources(
        truth,
        segment,
        &rec.samples,
        &rec.frames,
        setup.imu.dt,
        &calibration.filter,
        setup.max_vision_age,
    )?;
    let fused = fuse(&est, &calibration.fusion, setup.smoothing_q)?;
    let figures = figures(&est, &fused, setup.window)?;
    Ok(SegmentRun {
        name,
        estimates: est,
        fused,
        figures,
        frames_delivered: rec.frames.len(),
        frames_captured: rec.frames_captured,
    })
}

/// E of the three sources and the fusion over the setup's window.
pub fn figures(
    est: &SourceEstimates,
    fused: &[f64],
    window: (f64, f64),
) -> Result<Figures, RehabError> {
    let e = |v: &[f64], what| {
        error_variance(&est.times, v, &est.truth, window, what).map(|x| x * DEG2_PER_RAD2)
    };
    Ok(Figures {
        e_vision: e(&est.vision, "E of the vision")?,
        e_imu: e(&est.imu, "E of the IMU")?,
        e_fusion: e(fused, "E of the fusion")?,
        e_accel: e(&est.accel_angle, "E of the accelerometer angle")?,
    })
}

/// What the rig run calibrates: the IMU filter (its `R` measured) and the fusion weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    pub filter: ImuFilterTuning,
    pub fusion: WeightedFusion<2>,
}

/// The rig run, as the paper calibrates on its test platform: the accelerometer-angle variance (Eq. 28) becomes
/// the IMU filter's `R`; the IMU and vision variances (Eq. 28) give the weights of Eq. 27; then the fusion runs
/// with them.
pub fn run_rig(rig: &PendulumRigModel, setup: &Setup, seed: u64) -> Result<RigRun, RehabError> {
    let truth = rig_truth(rig, RigGeometry::default(), setup.t_end, setup.truth_dt)?;
    let rec = record(&truth, 0, setup, seed)?;
    let mut accel = ErrorVariance::new();
    for s in &rec.samples {
        if s.t >= setup.window.0 && s.t <= setup.window.1 {
            let reference = truth.state(0, s.t).map_or(f64::NAN, |x| x.angle);
            accel.push(accelerometer_angle(s.acc[0], s.acc[1], s.acc[2]), reference);
        }
    }
    let accel_variance = accel.variance().ok_or(RehabError::TooFewSamples {
        what: "the accelerometer-angle variance on the rig",
        count: accel.count(),
    })?;
    let filter = ImuFilterTuning {
        r: accel_variance,
        ..setup.filter
    };
    let est = estimate_sources(
        &truth,
        0,
        &rec.samples,
        &rec.frames,
        setup.imu.dt,
        &filter,
        setup.max_vision_age,
    )?;
    let var_imu = error_variance(
        &est.times,
        &est.imu,
        &est.truth,
        setup.window,
        "E of the IMU",
    )?;
    let var_vision = error_variance(
        &est.times,
        &est.vision,
        &est.truth,
        setup.window,
        "E of the vision",
    )?;
    let fusion = WeightedFusion::new(Vector2::new(var_imu, var_vision)).map_err(|source| {
        RehabError::Estimation {
            stage: "the weights of Eq. 27",
            source,
        }
    })?;
    let calibration = Calibration { filter, fusion };
    let segment = process(&truth, 0, "pendulum", rec, setup, &calibration)?;
    let w = fusion.weights();
    Ok(RigRun {
        weights: [w[0], w[1]],
        variances: [var_imu, var_vision],
        accel_variance,
        fused_variance: fusion.variance(),
        calibration,
        segment,
    })
}

/// The exoskeleton test without load with the rig's calibration: thigh and calf.
pub fn run_leg(
    leg: &RehabLegModel,
    setup: &Setup,
    calibration: &Calibration,
    seed: u64,
) -> Result<[SegmentRun; 2], RehabError> {
    let truth = leg_truth(leg, LegGeometry::default(), setup.t_end, setup.truth_dt)?;
    let thigh = record(&truth, 0, setup, seed)?;
    let calf = record(&truth, 1, setup, seed)?;
    Ok([
        process(&truth, 0, "thigh", thigh, setup, calibration)?,
        process(&truth, 1, "calf", calf, setup, calibration)?,
    ])
}
