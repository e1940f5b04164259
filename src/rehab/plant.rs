//! Hand-derived implementations of the measurement-system example's two `.bg` models, one function per model,
//! each returning a [`ContinuousModel`]: [`pendulum_rig`] (`models/pendulum_rig.bg`) and [`rehab_leg`]
//! (`models/rehab_leg.bg`).
//!
//! The study simulates the models generated from the `.bg` files ([`super::generated`]); these implementations of
//! the models' bond-graph equations, written independently of the compiler, are the reference those are tested
//! against (same state and output order, same trajectories). Parameter values are those of the
//! `.bg` defaults in SI units (a test checks that they agree).
//!
//! **Pendulum rig.** Integral causality on the coupling `C` (stiffness `k_s`) and the pendulum `I` (`J_p`); the
//! stepper `MSf` sets the flow of `j_motor`. States `x = [q_c, p, θ, θ_m]` (coupling twist, pendulum momentum,
//! and the integrated flows `theta = int(f(j_pend))`, `theta_m = int(f(j_motor))`). With `ω_m = A ω₀ cos(ω₀ t)`,
//! `ω₀ = 2π/T_ref` and `ω_p = p/J_p`:
//!
//! - the 0-junction `j_shaft` splits the rotor speed: `q̇_c = ω_m − ω_p` (flow of `j_twist`);
//! - the coupling torque is the common effort of `j_shaft`: `τ_c = k_s q_c + d_s (ω_m − ω_p)`;
//! - the 1-junction `j_pend` sums the efforts: `ṗ = τ_c − b_p ω_p − m_p g l_p sin θ` (the gravity source's bond
//!   points into the junction, so its effort adds);
//! - `θ̇ = ω_p`, `θ̇_m = ω_m`.
//!
//! Outputs `y = [θ, ω_p, θ_m]`.
//!
//! **Leg.** Both motors are flow sources, so both inertias are in derivative causality and the only states are the
//! integrated flows `x = [φ_hip, φ_knee]` with `φ̇_hip = ḣ(t)`, `φ̇_knee = k̇(t)`, the derivatives of the Fourier
//! series of the hip and knee curves ([`GaitCurve::rate`]). The outputs add the curves' values at `t = 0`:
//! `y = [θ, α, θ − α, ω_thigh, ω_calf]` with `θ = h(0) + φ_hip`, `α = k(0) + φ_knee`, `ω_thigh = ḣ`, and the
//! 0-junction `j_knee` giving `ω_calf = ω_thigh − k̇`.

use bgc_runtime::model::ContinuousModel;
use nalgebra::SVector;
use std::f64::consts::PI;

const DEG: f64 = PI / 180.0;

/// Parameters of `models/pendulum_rig.bg`, in SI units.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PendulumRigParams {
    /// Amplitude of the stepper's sinusoidal angle profile \[rad\].
    pub a_ref: f64,
    /// Period of the profile \[s\].
    pub t_ref: f64,
    /// Magnetic stiffness of the stepper \[N m/rad\].
    pub k_s: f64,
    /// Damping of the drive and coupling \[N m s/rad\].
    pub d_s: f64,
    /// Pendulum inertia about the pivot \[kg m²\].
    pub j_p: f64,
    /// Pivot bearing friction \[N m s/rad\].
    pub b_p: f64,
    /// Pendulum mass \[kg\].
    pub m_p: f64,
    /// Pivot to centre of mass \[m\].
    pub l_p: f64,
    /// Gravity \[m/s²\].
    pub g: f64,
}

impl Default for PendulumRigParams {
    fn default() -> Self {
        PendulumRigParams {
            a_ref: 30.0 * DEG,
            t_ref: 2.0,
            k_s: 25.0,
            d_s: 0.2,
            j_p: 0.012,
            b_p: 0.002,
            m_p: 0.35,
            l_p: 0.18,
            g: 9.81,
        }
    }
}

/// The pendulum rig (hand-derived from `models/pendulum_rig.bg`; equations in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PendulumRig {
    pub params: PendulumRigParams,
}

/// The model of `models/pendulum_rig.bg` with its default parameters.
pub fn pendulum_rig() -> PendulumRig {
    PendulumRig {
        params: PendulumRigParams::default(),
    }
}

impl PendulumRig {
    /// Number of states, inputs and outputs.
    pub const NX: usize = 4;

    /// The stepper's angle profile `A sin(2π t/T)` \[rad\].
    pub fn reference_angle(&self, t: f64) -> f64 {
        let p = &self.params;
        p.a_ref * (2.0 * PI * t / p.t_ref).sin()
    }

    /// The stepper's rotor speed, the flow of the `MSf` \[rad/s\].
    pub fn motor_speed(&self, t: f64) -> f64 {
        let p = &self.params;
        let w0 = 2.0 * PI / p.t_ref;
        p.a_ref * w0 * (w0 * t).cos()
    }

    /// The state at `t = 0` with the pendulum moving with the rotor and the coupling relaxed, so that the run starts
    /// without a transient.
    pub fn initial_state(&self) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(0.0, self.params.j_p * self.motor_speed(0.0), 0.0, 0.0)
    }
}

impl ContinuousModel<4, 0, 3> for PendulumRig {
    fn rhs(&self, t: f64, x: &SVector<f64, 4>, _u: &SVector<f64, 0>, dx: &mut SVector<f64, 4>) {
        let p = &self.params;
        let omega_m = self.motor_speed(t);
        let omega_p = x[1] / p.j_p;
        let twist_rate = omega_m - omega_p;
        let tau_c = p.k_s * x[0] + p.d_s * twist_rate;
        dx[0] = twist_rate;
        dx[1] = tau_c - p.b_p * omega_p - p.m_p * p.g * p.l_p * x[2].sin();
        dx[2] = omega_p;
        dx[3] = omega_m;
    }

    fn outputs(&self, _t: f64, x: &SVector<f64, 4>, _u: &SVector<f64, 0>, y: &mut SVector<f64, 3>) {
        y[0] = x[2];
        y[1] = x[1] / self.params.j_p;
        y[2] = x[3];
    }
}

/// A periodic curve `c₀ + Σᵢ (aᵢ cos(i ω t) + bᵢ sin(i ω t))`, `ω = 2π/period` (the form of the paper's Eq. 36).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GaitCurve {
    /// Mean \[rad\].
    pub c0: f64,
    /// Cosine coefficients of harmonics 1..=4 \[rad\].
    pub a: [f64; 4],
    /// Sine coefficients of harmonics 1..=4 \[rad\].
    pub b: [f64; 4],
    /// Period \[s\].
    pub period: f64,
}

impl GaitCurve {
    /// The angle at `t` \[rad\].
    pub fn value(&self, t: f64) -> f64 {
        let w = 2.0 * PI / self.period;
        let mut v = self.c0;
        for (i, (a, b)) in self.a.iter().zip(self.b.iter()).enumerate() {
            let n = (i + 1) as f64;
            v += a * (n * w * t).cos() + b * (n * w * t).sin();
        }
        v
    }

    /// The angular velocity at `t` \[rad/s\].
    pub fn rate(&self, t: f64) -> f64 {
        let w = 2.0 * PI / self.period;
        let mut v = 0.0;
        for (i, (a, b)) in self.a.iter().zip(self.b.iter()).enumerate() {
            let n = (i + 1) as f64;
            v += n * w * (b * (n * w * t).cos() - a * (n * w * t).sin());
        }
        v
    }
}

/// Parameters of `models/rehab_leg.bg`, in SI units.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RehabLegParams {
    /// The hip (thigh) angle curve.
    pub hip: GaitCurve,
    /// The knee flexion curve.
    pub knee: GaitCurve,
    /// Thigh inertia about the hip \[kg m²\] (the hip motor's load; it does not change the angles).
    pub j_t: f64,
    /// Calf inertia about the knee \[kg m²\] (the knee motor's load).
    pub j_c: f64,
}

impl Default for RehabLegParams {
    // The knee's third sine coefficient is a fitted 3.14 deg, not an approximation of π.
    #[allow(clippy::approx_constant)]
    fn default() -> Self {
        let period = 3.0;
        let deg4 = |v: [f64; 4]| v.map(|x| x * DEG);
        RehabLegParams {
            hip: GaitCurve {
                c0: 12.90 * DEG,
                a: deg4([18.99, -0.66, -0.43, -0.02]),
                b: deg4([1.03, -3.82, 0.71, -0.25]),
                period,
            },
            knee: GaitCurve {
                c0: 24.10 * DEG,
                a: deg4([-0.87, -13.95, -1.94, -1.18]),
                b: deg4([-21.28, 5.89, 3.14, 0.59]),
                period,
            },
            j_t: 0.25,
            j_c: 0.08,
        }
    }
}

/// The exoskeleton leg (hand-derived from `models/rehab_leg.bg`; equations in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RehabLeg {
    pub params: RehabLegParams,
}

/// The model of `models/rehab_leg.bg` with its default parameters.
pub fn rehab_leg() -> RehabLeg {
    RehabLeg {
        params: RehabLegParams::default(),
    }
}

impl ContinuousModel<2, 0, 5> for RehabLeg {
    fn rhs(&self, t: f64, _x: &SVector<f64, 2>, _u: &SVector<f64, 0>, dx: &mut SVector<f64, 2>) {
        dx[0] = self.params.hip.rate(t);
        dx[1] = self.params.knee.rate(t);
    }

    fn outputs(&self, t: f64, x: &SVector<f64, 2>, _u: &SVector<f64, 0>, y: &mut SVector<f64, 5>) {
        let p = &self.params;
        let theta = p.hip.value(0.0) + x[0];
        let alpha = p.knee.value(0.0) + x[1];
        let omega_thigh = p.hip.rate(t);
        y[0] = theta;
        y[1] = alpha;
        y[2] = theta - alpha;
        y[3] = omega_thigh;
        y[4] = omega_thigh - p.knee.rate(t);
    }
}
