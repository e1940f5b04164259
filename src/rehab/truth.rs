//! The true motion of the instrumented segments, from a simulation of the plant models.
//!
//! A segment is a rigid link of angle `φ` from the downward vertical (positive forwards), turning about a pivot
//! `P` in the sagittal plane (`x` forwards, `z` up). A point at distance `r` from the pivot along the link is at
//! `P + r (sin φ, −cos φ)`; differentiating twice,
//!
//! `a = a_P + r φ̈ (cos φ, sin φ) + r φ̇² (−sin φ, cos φ)`,
//!
//! the tangential and centripetal accelerations the paper neglects in Eq. 2 (Sec. 2.3.1 notes they bias the
//! accelerometer's gravity direction).
//!
//! The plants are the models generated from the `.bg` files ([`super::generated`]), simulated on a fine time grid;
//! the angle and rate of each segment are the model's outputs there.
//!
//! Rig: one segment, the pendulum about a fixed pivot; its angular acceleration is `ṗ / J_p` from the model's
//! right-hand side at the simulated states. Leg (exoskeleton without load, frame fixed): the thigh about the fixed
//! hip and the calf about the knee, which is carried by the thigh at distance `L_t`: `P_knee = L_t (sin θ, −cos θ)`
//! with the acceleration of the formula above at `r = L_t`. The leg's states are the integrated motor flows, so
//! its right-hand side gives rates, not accelerations: those are central differences of the rate on the grid
//! (second order; one-sided at the ends).

use super::error::{RehabError, positive};
use super::generated::{
    LegLayout, PendulumRigModel, RehabLegModel, RigLayout, rig_angular_acceleration,
    rig_initial_state,
};
use bgc_runtime::model::ContinuousModel;
use bgc_runtime::sim::{SolverOptions, Trajectory, simulate_open_loop};
use nalgebra::SVector;

/// The motion of one segment at the grid times of its [`Truth`].
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentTrack {
    pub name: &'static str,
    /// Angle from the downward vertical \[rad\].
    pub angle: Vec<f64>,
    /// Angular velocity \[rad/s\].
    pub rate: Vec<f64>,
    /// Angular acceleration \[rad/s²\].
    pub accel: Vec<f64>,
    /// Pivot position `(x, z)` \[m\].
    pub pivot_pos: Vec<[f64; 2]>,
    /// Pivot acceleration `(x, z)` \[m/s²\].
    pub pivot_acc: Vec<[f64; 2]>,
    /// Distance from the pivot to the distal marker (length seen by the camera) \[m\].
    pub length: f64,
}

/// The state of a segment at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentState {
    pub angle: f64,
    pub rate: f64,
    pub accel: f64,
    pub pivot_pos: [f64; 2],
    pub pivot_acc: [f64; 2],
}

impl SegmentState {
    /// Position of the point at distance `r` along the segment \[m\].
    pub fn point(&self, r: f64) -> [f64; 2] {
        let (s, c) = self.angle.sin_cos();
        [self.pivot_pos[0] + r * s, self.pivot_pos[1] - r * c]
    }

    /// Acceleration of the point at distance `r` along the segment \[m/s²\].
    pub fn point_acc(&self, r: f64) -> [f64; 2] {
        let (s, c) = self.angle.sin_cos();
        let w2 = self.rate * self.rate;
        [
            self.pivot_acc[0] + r * (self.accel * c - w2 * s),
            self.pivot_acc[1] + r * (self.accel * s + w2 * c),
        ]
    }
}

/// The true motion of all segments on a uniform time grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    pub times: Vec<f64>,
    pub segments: Vec<SegmentTrack>,
}

impl Truth {
    /// The state of segment `segment` at time `t`, linearly interpolated on the grid; `None` outside the grid or for
    /// an unknown segment.
    pub fn state(&self, segment: usize, t: f64) -> Option<SegmentState> {
        let seg = self.segments.get(segment)?;
        let (&t0, &t1) = (self.times.first()?, self.times.last()?);
        if !(t >= t0 && t <= t1) || self.times.len() < 2 {
            return None;
        }
        let dt = (t1 - t0) / (self.times.len() - 1) as f64;
        let i = (((t - t0) / dt).floor() as usize).min(self.times.len() - 2);
        let s = ((t - self.times.get(i)?) / dt).clamp(0.0, 1.0);
        let lerp = |v: &[f64]| -> Option<f64> { Some(v.get(i)? * (1.0 - s) + v.get(i + 1)? * s) };
        let lerp2 = |v: &[[f64; 2]]| -> Option<[f64; 2]> {
            let (a, b) = (v.get(i)?, v.get(i + 1)?);
            Some([a[0] * (1.0 - s) + b[0] * s, a[1] * (1.0 - s) + b[1] * s])
        };
        Some(SegmentState {
            angle: lerp(&seg.angle)?,
            rate: lerp(&seg.rate)?,
            accel: lerp(&seg.accel)?,
            pivot_pos: lerp2(&seg.pivot_pos)?,
            pivot_acc: lerp2(&seg.pivot_acc)?,
        })
    }
}

/// Geometry of the rig as the sensors see it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RigGeometry {
    /// Pivot to the distal vision marker \[m\].
    pub marker_length: f64,
}

impl Default for RigGeometry {
    fn default() -> Self {
        RigGeometry {
            marker_length: 0.30,
        }
    }
}

/// Geometry of the leg as the sensors see it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LegGeometry {
    /// Hip to knee \[m\].
    pub thigh_length: f64,
    /// Knee to ankle marker \[m\].
    pub calf_length: f64,
}

impl Default for LegGeometry {
    fn default() -> Self {
        LegGeometry {
            thigh_length: 0.42,
            calf_length: 0.40,
        }
    }
}

fn grid(t_end: f64, dt: f64) -> Result<Vec<f64>, RehabError> {
    positive("t_end", t_end)?;
    positive("truth grid step", dt)?;
    let n = (t_end / dt).round();
    if !(2.0..=1e7).contains(&n) {
        return Err(RehabError::BadSetting {
            name: "truth grid step",
            value: dt,
            reason: "the run must have between 2 and 1e7 grid steps",
        });
    }
    Ok((0..=n as usize).map(|k| k as f64 * dt).collect())
}

/// Central differences of `v` on a uniform grid of step `dt` (one-sided at the ends).
fn derivative(v: &[f64], dt: f64) -> Vec<f64> {
    let n = v.len();
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
            match (v.get(lo), v.get(hi)) {
                (Some(a), Some(b)) if hi > lo => (b - a) / ((hi - lo) as f64 * dt),
                _ => 0.0,
            }
        })
        .collect()
}

fn simulate<M: ContinuousModel<NX, 0, NY>, const NX: usize, const NY: usize>(
    model: &M,
    name: &'static str,
    x0: &SVector<f64, NX>,
    times: &[f64],
) -> Result<Trajectory<NX, 0, NY>, RehabError> {
    let opts = SolverOptions {
        rtol: 1e-9,
        atol: 1e-11,
        ..SolverOptions::default()
    };
    simulate_open_loop(model, 0.0, x0, |_| SVector::<f64, 0>::zeros(), times, &opts).map_err(
        |source| RehabError::Simulation {
            model: name,
            source,
        },
    )
}

/// Column `i` of a series of vectors (NaN where `i` is out of range, which the layouts rule out).
fn column<const N: usize>(v: &[SVector<f64, N>], i: usize) -> Vec<f64> {
    v.iter()
        .map(|x| x.get(i).copied().unwrap_or(f64::NAN))
        .collect()
}

/// The true motion of the rig's pendulum from `0` to `t_end`, on a grid of step `dt`, simulated from the generated
/// model and started without a transient ([`rig_initial_state`]).
pub fn rig_truth(
    rig: &PendulumRigModel,
    geometry: RigGeometry,
    t_end: f64,
    dt: f64,
) -> Result<Truth, RehabError> {
    positive("marker_length", geometry.marker_length)?;
    let layout = RigLayout::of_generated()?;
    let times = grid(t_end, dt)?;
    let tr = simulate(
        rig,
        "pendulum_rig",
        &rig_initial_state(rig, &layout)?,
        &times,
    )?;
    let angle = column(&tr.outputs, layout.angle);
    let rate = column(&tr.outputs, layout.rate);
    let accel: Vec<f64> = tr
        .times
        .iter()
        .zip(&tr.states)
        .map(|(&t, x)| rig_angular_acceleration(rig, &layout, t, x))
        .collect();
    let n = times.len();
    Ok(Truth {
        times,
        segments: vec![SegmentTrack {
            name: "pendulum",
            angle,
            rate,
            accel,
            pivot_pos: vec![[0.0, 0.0]; n],
            pivot_acc: vec![[0.0, 0.0]; n],
            length: geometry.marker_length,
        }],
    })
}

/// The true motion of the thigh (segment 0) and calf (segment 1) from `0` to `t_end`, on a grid of step `dt`.
///
/// The generated model's states are the motors' integrated flows, zero at `t = 0`; its outputs add the curves'
/// values at `t = 0`.
pub fn leg_truth(
    leg: &RehabLegModel,
    geometry: LegGeometry,
    t_end: f64,
    dt: f64,
) -> Result<Truth, RehabError> {
    positive("thigh_length", geometry.thigh_length)?;
    positive("calf_length", geometry.calf_length)?;
    let layout = LegLayout::of_generated()?;
    let times = grid(t_end, dt)?;
    let tr = simulate(leg, "rehab_leg", &SVector::zeros(), &times)?;
    let thigh = column(&tr.outputs, layout.thigh_angle);
    let calf = column(&tr.outputs, layout.calf_angle);
    let thigh_rate = column(&tr.outputs, layout.thigh_rate);
    let calf_rate = column(&tr.outputs, layout.calf_rate);
    let thigh_acc = derivative(&thigh_rate, dt);
    let calf_acc = derivative(&calf_rate, dt);
    let n = times.len();
    let (knee_pos, knee_acc): (Vec<[f64; 2]>, Vec<[f64; 2]>) = thigh
        .iter()
        .zip(&thigh_rate)
        .zip(&thigh_acc)
        .map(|((&angle, &rate), &accel)| {
            let s = SegmentState {
                angle,
                rate,
                accel,
                pivot_pos: [0.0, 0.0],
                pivot_acc: [0.0, 0.0],
            };
            (
                s.point(geometry.thigh_length),
                s.point_acc(geometry.thigh_length),
            )
        })
        .unzip();
    Ok(Truth {
        times,
        segments: vec![
            SegmentTrack {
                name: "thigh",
                angle: thigh,
                rate: thigh_rate,
                accel: thigh_acc,
                pivot_pos: vec![[0.0, 0.0]; n],
                pivot_acc: vec![[0.0, 0.0]; n],
                length: geometry.thigh_length,
            },
            SegmentTrack {
                name: "calf",
                angle: calf,
                rate: calf_rate,
                accel: calf_acc,
                pivot_pos: knee_pos,
                pivot_acc: knee_acc,
                length: geometry.calf_length,
            },
        ],
    })
}
