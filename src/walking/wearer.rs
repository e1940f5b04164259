//! The synthetic wearer: intended joint trajectories, insole forces, the stance torso load and the human
//! joint torque.
//!
//! # Trajectories
//!
//! Each joint follows a 6-harmonic Fourier series in the gait phase `φ` (cycles), fitted to keypoints of
//! normal level walking read from Winter (2009, Fig. 4.2 and Appendix A): hip flexion from −13° (terminal
//! stance) to 22° (terminal swing), knee flexion 3° to 60° (peak in initial swing at 73 % of the cycle),
//! ankle dorsiflexion −15° (toe-off) to 10° (terminal stance). The cycle is 1 s with heel strike at
//! `φ = 0`, toe-off at 0.62 (62 % stance, 38 % swing); the left leg runs half a cycle behind.
//!
//! Cycle-to-cycle variation: the phase rate (cycles/s) and each joint's excursion about its mean are drawn
//! once per second from `1 + σ N(0, 1)` (seeded) and blended between draws with the quintic smoothstep
//! `s(τ) = 6τ⁵ − 15τ⁴ + 10τ³`, so that `q`, `q̇` and `q̈` stay continuous. The phase is the closed-form
//! integral of the blended rate.
//!
//! # Insoles and the body weight
//!
//! Heel (`F₁`) and ball (`F₂`) force shapes of each foot: heel only for the first 3 % of the cycle (heel
//! strike, `P ≈ 1`), the ball loading by 7 % (heel flat, `P ≈ 0` within ±0.08), the heel unloading from 53 %
//! to 57 % (heel off, `P ≈ −1`) and the ball unloading by toe-off at 62 %. Heel rise in normal gait starts
//! near 40 % of the cycle (Winter 2009); it is put after the contralateral heel strike here because the
//! automaton of Table 3 needs it: its events `p2`/`p4` require one foot in heel flat while the other
//! strikes, and `p1`/`p3` one foot in heel off while the other is flat.
//!
//! The two feet carry the body weight `W` between them: each foot's shapes are scaled by
//! `W / (total shape of both feet)`, so the insole totals add up to `W` at every instant and a foot's share
//! ([`Wearer::support_share`]) rises from 0 to 1 over the loading response (double support, 0–12 % of its
//! cycle), is 1 in single support and falls back to 0 over pre-swing (50–62 %). The scaling leaves the
//! index `P` of Eq. (30), a ratio within one foot, unchanged.
//!
//! # Torso load and ground reaction (Eq. 2)
//!
//! The torso mass rests on the thigh of the leg that carries the body: the load fraction on the right thigh
//! is the right foot's support share. The ground reaction on the right foot has the vertical component
//! `W · share` and points from the ankle through the hip (the leg's axis: the inverted pendulum of walking,
//! whose ground reaction points at the body's centre of mass), see [`super::plant::axial_reaction`].
//!
//! # Human torque
//!
//! The wearer's muscles supply their share of the joint torque the gait needs, and the braces, a spring and
//! damper per joint, pass their correction to the lumped leg:
//!
//! ```text
//! τ_h = (1 − a(t)) ⊙ τ_gait(t) + K_b (q_w − q) + B_b (q̇_w − q̇)
//! ```
//!
//! with `τ_gait` the torque the joints need along `q_w` (Eqs. 2–3 inverse dynamics minus the ground
//! reaction's `Jᵀ R`, computed by [`super::plant::WalkingPlant::joint_torque_demand`]) and `a` the share the
//! wearer leaves to the exoskeleton once it assists: zero at the passive ankle, and at the knee and hip
//! what the motors can deliver (the scenario sizes it to their ratings, `scenario::sized_assistance`).
//! The wearer hands that share over gradually, with the quintic smoothstep over [`ASSISTANCE_RAMP`]
//! seconds from the onset of assistance.

use super::anthropometry::{BODY_MASS, GRAVITY, TORSO_MASS};
use bgc_runtime::control::GrfSample;
use bgc_runtime::noise::Rng;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Fourier coefficients (degrees) `[c₀, a₁, b₁, …, a₆, b₆]` of `c₀ + Σ aₙ cos 2πnφ + bₙ sin 2πnφ`, per joint
/// (ankle, knee, hip). Least-squares fits to a periodic cubic spline through the keypoints:
///
/// ```python
/// import numpy as np; from scipy.interpolate import CubicSpline
/// pts = {'hip': [(0,20),(.1,18),(.2,10),(.3,2),(.4,-6),(.5,-12),(.55,-13),(.6,-8),(.7,8),(.8,18),(.87,22),
///                (.95,21),(1,20)],
///        'knee': [(0,3),(.05,10),(.15,18),(.25,10),(.35,5),(.42,4),(.5,12),(.6,38),(.7,58),(.73,60),(.8,50),
///                 (.9,20),(.97,3),(1,3)],
///        'ankle': [(0,0),(.07,-6),(.15,0),(.3,8),(.45,10),(.55,0),(.62,-15),(.7,-8),(.8,0),(.9,2),(1,0)]}
/// phi = np.linspace(0, 1, 400, endpoint=False)
/// for name, p in pts.items():
///     x, y = np.array(p).T; s = CubicSpline(x, y, bc_type='periodic')(phi)
///     A = np.array([np.ones_like(phi)] + sum([[np.cos(2*np.pi*k*phi), np.sin(2*np.pi*k*phi)]
///                                              for k in range(1, 7)], [])).T
///     print(name, np.linalg.lstsq(A, s, rcond=None)[0])
/// ```
pub const SHAPES_DEG: [[f64; 13]; 3] = [
    [
        0.6740, -1.5483, 5.6530, 0.6167, -6.9468, -2.4224, 0.3107, 2.1848, -0.7250, -0.2272,
        -1.1015, 0.3373, 0.4456,
    ],
    [
        22.3041, -2.7060, -20.8875, -13.1827, 7.7228, -1.4291, 3.2522, -1.3015, 0.8266, -0.3470,
        -0.0644, -0.3039, 0.3083,
    ],
    [
        7.1871, 16.3246, -2.9042, -3.0067, -1.4542, 0.1634, 1.3044, -0.3376, -0.3943, -0.4087,
        0.3241, 0.0558, -0.0513,
    ],
];

/// Fraction of the cycle in stance (heel strike at 0, toe-off here).
pub const STANCE_FRACTION: f64 = 0.62;

/// Seconds over which the wearer hands the assisted share of the torque to the exoskeleton.
pub const ASSISTANCE_RAMP: f64 = 0.25;

/// The quintic smoothstep and its first two derivatives at `τ ∈ [0, 1]` (clamped outside).
fn smoothstep(tau: f64) -> (f64, f64, f64) {
    if tau <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    if tau >= 1.0 {
        return (1.0, 0.0, 0.0);
    }
    let t2 = tau * tau;
    let t3 = t2 * tau;
    (
        t3 * (10.0 - 15.0 * tau + 6.0 * t2),
        30.0 * t2 * (1.0 - tau) * (1.0 - tau),
        60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau),
    )
}

/// A value with its first two time derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    pub q: Vector3<f64>,
    pub qd: Vector3<f64>,
    pub qdd: Vector3<f64>,
}

/// Brace stiffness and damping per joint (ankle, knee, hip).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanGains {
    /// N m/rad.
    pub stiffness: Vector3<f64>,
    /// N m s/rad.
    pub damping: Vector3<f64>,
}

impl Default for HumanGains {
    fn default() -> Self {
        HumanGains {
            stiffness: Vector3::new(150.0, 100.0, 150.0),
            damping: Vector3::new(5.0, 6.0, 10.0),
        }
    }
}

/// Settings of the synthetic wearer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WearerConfig {
    /// Standard deviation of the per-second phase-rate factor.
    pub rate_variation: f64,
    /// Standard deviation of the per-second excursion factor of each joint.
    pub amplitude_variation: f64,
    /// Seconds of gait to prepare.
    pub duration: f64,
    pub seed: u64,
    pub gains: HumanGains,
    /// Torso mass carried by the stance thigh (kg).
    pub torso_mass: f64,
    /// Body weight (N), shared by the insoles.
    pub body_weight: f64,
    /// Share of the gait torque per joint (ankle, knee, hip) the wearer leaves to the exoskeleton once it
    /// assists, in `[0, 1]`.
    pub assistance: [f64; 3],
    /// When the exoskeleton starts assisting (s).
    pub assistance_onset: f64,
}

impl Default for WearerConfig {
    fn default() -> Self {
        WearerConfig {
            rate_variation: 0.02,
            amplitude_variation: 0.04,
            duration: 20.0,
            seed: 2018,
            gains: HumanGains::default(),
            torso_mass: TORSO_MASS,
            body_weight: BODY_MASS * GRAVITY,
            assistance: [0.0; 3],
            assistance_onset: 0.0,
        }
    }
}

/// The synthetic wearer.
#[derive(Clone, Debug)]
pub struct Wearer {
    /// Phase rate at the knots `t = k` s.
    rates: Vec<f64>,
    /// Phase at the knots.
    phases: Vec<f64>,
    /// Excursion factors at the knots, per joint.
    amplitudes: Vec<[f64; 3]>,
    pub gains: HumanGains,
    pub torso_mass: f64,
    pub body_weight: f64,
    pub assistance: Vector3<f64>,
    pub assistance_onset: f64,
}

impl Wearer {
    /// Draws the cycle-to-cycle variation for `cfg.duration` seconds (plus one knot of margin).
    pub fn new(cfg: &WearerConfig) -> Self {
        let mut rng = Rng::new(cfg.seed);
        let knots = cfg.duration.max(0.0).ceil() as usize + 2;
        let mut rates = Vec::with_capacity(knots);
        let mut amplitudes = Vec::with_capacity(knots);
        for k in 0..knots {
            // The first knot is the nominal gait so that every run starts from the same posture.
            let (r, a) = if k == 0 {
                (1.0, [1.0; 3])
            } else {
                let r = 1.0 + cfg.rate_variation * rng.normal();
                let a = std::array::from_fn(|_| 1.0 + cfg.amplitude_variation * rng.normal());
                (r, a)
            };
            rates.push(r);
            amplitudes.push(a);
        }
        let mut phases = Vec::with_capacity(knots);
        let mut phi = 0.0;
        for k in 0..knots {
            phases.push(phi);
            if k + 1 < knots {
                phi += 0.5 * (rates[k] + rates[k + 1]);
            }
        }
        Wearer {
            rates,
            phases,
            amplitudes,
            gains: cfg.gains,
            torso_mass: cfg.torso_mass,
            body_weight: cfg.body_weight,
            assistance: Vector3::from(cfg.assistance),
            assistance_onset: cfg.assistance_onset,
        }
    }

    /// The knot interval holding `t` and the local time `τ ∈ [0, 1]`; times past the end use the last one.
    fn knot(&self, t: f64) -> (usize, f64) {
        let last = self.rates.len().saturating_sub(2);
        let k = if t.is_finite() && t > 0.0 {
            (t.floor() as usize).min(last)
        } else {
            0
        };
        (k, (t - k as f64).max(0.0))
    }

    /// Gait phase of the right leg (cycles since the first heel strike) and its two derivatives.
    pub fn phase(&self, t: f64) -> (f64, f64, f64) {
        let (k, tau) = self.knot(t);
        let (r0, r1) = (self.rates[k], self.rates[k + 1]);
        let dr = r1 - r0;
        let (s, ds, _) = smoothstep(tau);
        // ∫₀^τ s = τ⁶ − 3τ⁵ + 2.5τ⁴ (for τ ≤ 1; beyond, s = 1).
        let int_s = if tau <= 1.0 {
            tau.powi(4) * (tau * tau - 3.0 * tau + 2.5)
        } else {
            0.5 + (tau - 1.0)
        };
        (self.phases[k] + r0 * tau + dr * int_s, r0 + dr * s, dr * ds)
    }

    /// Excursion factor of joint `j` and its derivatives.
    fn amplitude(&self, t: f64, j: usize) -> (f64, f64, f64) {
        let (k, tau) = self.knot(t);
        let (a0, a1) = (self.amplitudes[k][j], self.amplitudes[k + 1][j]);
        let (s, ds, dds) = smoothstep(tau);
        (a0 + (a1 - a0) * s, (a1 - a0) * ds, (a1 - a0) * dds)
    }

    /// The intended joint angles of the right leg (rad), with velocity and acceleration.
    pub fn intended(&self, t: f64) -> Kinematics {
        let (phi, phid, phidd) = self.phase(t);
        let mut out = Kinematics {
            q: Vector3::zeros(),
            qd: Vector3::zeros(),
            qdd: Vector3::zeros(),
        };
        for (j, c) in SHAPES_DEG.iter().enumerate() {
            let (mut g, mut g1, mut g2) = (0.0, 0.0, 0.0);
            for n in 1..=6 {
                let w = 2.0 * PI * n as f64;
                let (a, b) = (c[2 * n - 1], c[2 * n]);
                let (sn, cs) = (w * phi).sin_cos();
                g += a * cs + b * sn;
                g1 += w * (-a * sn + b * cs);
                g2 -= w * w * (a * cs + b * sn);
            }
            let (amp, ampd, ampdd) = self.amplitude(t, j);
            let deg = PI / 180.0;
            out.q[j] = deg * (c[0] + amp * g);
            out.qd[j] = deg * (ampd * g + amp * g1 * phid);
            out.qdd[j] =
                deg * (ampdd * g + 2.0 * ampd * g1 * phid + amp * (g2 * phid * phid + g1 * phidd));
        }
        out
    }

    /// Where a leg is in its own cycle, in `[0, 1)` (0: heel strike).
    pub fn cycle_fraction(&self, t: f64, left: bool) -> f64 {
        let phi = self.phase(t).0 + if left { 0.5 } else { 0.0 };
        phi - phi.floor()
    }

    /// True while the right foot is on the ground.
    pub fn right_in_stance(&self, t: f64) -> bool {
        self.cycle_fraction(t, false) < STANCE_FRACTION
    }

    /// Fraction of the torso load on the right thigh: the right foot's support share.
    pub fn torso_load(&self, t: f64) -> f64 {
        self.support_share(t)
    }

    /// Noise-free, unscaled insole force shapes of one foot at cycle fraction `p` (half the body weight on
    /// each sensor in flat foot).
    fn insole_shape(&self, p: f64) -> GrfSample {
        if !(0.0..STANCE_FRACTION).contains(&p) {
            return GrfSample {
                heel: 0.0,
                ball: 0.0,
            };
        }
        let half = 0.5 * self.body_weight;
        let ramp = |a: f64, b: f64| smoothstep((p - a) / (b - a)).0;
        let tilt = 0.08 * (2.0 * PI * p / STANCE_FRACTION).sin();
        GrfSample {
            heel: half * (1.0 + tilt) * ramp(0.0, 0.03) * (1.0 - ramp(0.53, 0.57)),
            ball: half * (1.0 - tilt) * ramp(0.03, 0.07) * (1.0 - ramp(0.57, STANCE_FRACTION)),
        }
    }

    /// The right foot's share of the body weight at time `t` (0 in swing, 1 in single support).
    pub fn support_share(&self, t: f64) -> f64 {
        let total = |g: GrfSample| g.heel + g.ball;
        let right = total(self.insole_shape(self.cycle_fraction(t, false)));
        let left = total(self.insole_shape(self.cycle_fraction(t, true)));
        if right + left > 0.0 {
            right / (right + left)
        } else {
            0.0
        }
    }

    /// Noise-free insole forces of (right, left) feet at time `t`: the shapes scaled so that both feet
    /// together carry the body weight.
    pub fn insoles(&self, t: f64) -> (GrfSample, GrfSample) {
        let right = self.insole_shape(self.cycle_fraction(t, false));
        let left = self.insole_shape(self.cycle_fraction(t, true));
        let total = right.heel + right.ball + left.heel + left.ball;
        let scale = if total > 0.0 {
            self.body_weight / total
        } else {
            0.0
        };
        let scaled = |g: GrfSample| GrfSample {
            heel: g.heel * scale,
            ball: g.ball * scale,
        };
        (scaled(right), scaled(left))
    }

    /// The share of the gait torque the wearer leaves to the exoskeleton at time `t`.
    pub fn assistance_at(&self, t: f64) -> Vector3<f64> {
        let ramp = smoothstep((t - self.assistance_onset) / ASSISTANCE_RAMP).0;
        self.assistance * ramp
    }

    /// The wearer's joint torque `τ_h` in state `(q, q̇)` at time `t`, given the joint torque `demand` the
    /// gait needs at `t` along the wearer's own trajectory.
    pub fn human_torque(
        &self,
        t: f64,
        q: &Vector3<f64>,
        qd: &Vector3<f64>,
        demand: &Vector3<f64>,
    ) -> Vector3<f64> {
        let w = self.intended(t);
        let steer = self.gains.stiffness.component_mul(&(w.q - q))
            + self.gains.damping.component_mul(&(w.qd - qd));
        let own_share = Vector3::repeat(1.0) - self.assistance_at(t);
        own_share.component_mul(demand) + steer
    }
}
