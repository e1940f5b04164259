//! The leg as a continuous model `ẋ = f(x, u)` with `x = [q, q̇]` (Eqs. 1–3 and 8).
//!
//! [`LegModel`]: `M(q) q̈ + C(q, q̇) q̇ + G(q) + τ_f(q, q̇) = u`, where `u = τ_a + τ_h − Jᵀ F` is the total
//! generalised torque of Eq. (8) and the output is `q` (the joint position sensors).
//!
//! [`WalkingPlant`]: the same leg worn by the synthetic wearer of [`super::wearer`]. The input is the
//! exoskeleton's actuator torque `τ_a` (the ankle entry is ignored: the ankle is passive); the wearer adds
//! the human torque `τ_h(t, x)` through the braces and loads the thigh with the torso in stance (Eq. 2).
//! The ground reaction is not simulated as a separate contact force: in this hip-rooted model the human
//! torque stands for `τ_h − Jᵀ F`.
//!
//! The wearer leads: their limbs follow the intended trajectory `q_w(t)` and the braces (the paper's "soft
//! braces ... facilitate compliance in coupled motion") transmit `τ_h = K_b (q_w − q) + B_b (q̇_w − q̇)` to
//! the lumped leg; Eq. (28) subtracts the measured `τ_h`.
//!
//! Outputs ([`PLANT_OUTPUTS`] of them), in five groups of three (ankle, knee, hip):
//!
//! 1. the joint position sensors, reading the wearer's joint angles `q_w` at the braces;
//! 2. the joint torque of the gait, `τ_a + τ_h − Jᵀ F` along the wearer's trajectory, computed by inverse
//!    dynamics of Eqs. (2)–(3) with the torso load: what the torque sensors read with the exoskeleton in step
//!    with the wearer. It is the filter's input `u` (Eq. 8) and its torque observation `d` (Eq. 24). It is
//!    taken from the gait, not from the simulated exoskeleton, so that the filter's input does not contain
//!    the controller's own tracking effort: with it, the filter reads the controller's effort as the
//!    wearer's motion, the reference it feeds back runs ahead of the leg, and the loop diverges (it did,
//!    within 0.2 s, when we tried);
//! 3. the brace torque `τ_h`;
//! 4. the motor encoder angles `q` and 5. the joint speeds from motor rpm `q̇` (the impedance loop's
//!    feedback).

use super::anthropometry::{LegFriction, LegSegments};
use super::dynamics::LegDynamics;
use super::wearer::Wearer;
use bgc_runtime::model::{ContinuousModel, ParamError, Parametric};
use nalgebra::{SVector, Vector3, Vector6};

/// Splits a state `[q, q̇]`.
pub fn split(x: &Vector6<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (
        x.fixed_rows::<3>(0).into_owned(),
        x.fixed_rows::<3>(3).into_owned(),
    )
}

/// Joins `q` and `q̇` into a state.
pub fn join(q: &Vector3<f64>, qd: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(q[0], q[1], q[2], qd[0], qd[1], qd[2])
}

/// The leg with friction, driven by the total generalised torque.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegModel {
    pub dynamics: LegDynamics,
    pub friction: LegFriction,
}

impl LegModel {
    /// Segments with friction.
    pub fn new(segments: LegSegments, friction: LegFriction) -> Self {
        LegModel {
            dynamics: LegDynamics::new(segments),
            friction,
        }
    }

    /// `τ_f(q, q̇)`.
    pub fn friction_torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> Vector3<f64> {
        Vector3::from(
            self.friction
                .torque(&[q[0], q[1], q[2]], &[qd[0], qd[1], qd[2]]),
        )
    }

    /// `ẋ` for the total torque `u`; non-finite if `M(q)` is singular.
    pub fn derivative(&self, x: &Vector6<f64>, u: &Vector3<f64>) -> Vector6<f64> {
        let (q, qd) = split(x);
        let tau = u - self.friction_torque(&q, &qd);
        match self.dynamics.acceleration(&q, &qd, &tau) {
            Some(qdd) => join(&qd, &qdd),
            None => Vector6::repeat(f64::NAN),
        }
    }

    /// The torque of Eq. (25), `Y = M q̈ + C q̇ + G + τ_f`.
    pub fn torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>, qdd: &Vector3<f64>) -> Vector3<f64> {
        self.dynamics.inverse(q, qd, qdd) + self.friction_torque(q, qd)
    }

    /// One classical Runge–Kutta step of length `h` with the torque held.
    pub fn rk4_step(&self, x: &Vector6<f64>, u: &Vector3<f64>, h: f64) -> Vector6<f64> {
        let k1 = self.derivative(x, u);
        let k2 = self.derivative(&(x + k1 * (h / 2.0)), u);
        let k3 = self.derivative(&(x + k2 * (h / 2.0)), u);
        let k4 = self.derivative(&(x + k3 * h), u);
        x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
    }
}

/// The link masses `[m₁, m₂, m₃]` (foot, shank, thigh) by index, for the runtime's parameter estimators.
impl Parametric for LegModel {
    fn param_names(&self) -> &'static [&'static str] {
        &["m1_foot", "m2_shank", "m3_thigh"]
    }

    fn param(&self, index: usize) -> Option<f64> {
        self.dynamics.segments.masses().get(index).copied()
    }

    fn set_param(&mut self, index: usize, value: f64) -> Result<(), ParamError> {
        let name = *self
            .param_names()
            .get(index)
            .ok_or(ParamError::NoSuchParam { index })?;
        if !(value.is_finite() && value > 0.0) {
            return Err(ParamError::NonPhysical {
                name,
                value,
                reason: "a link mass must be finite and positive",
            });
        }
        let mut m = self.dynamics.segments.masses();
        m[index] = value;
        self.dynamics.segments = self.dynamics.segments.with_masses(m);
        Ok(())
    }
}

impl ContinuousModel<6, 3, 3> for LegModel {
    fn rhs(&self, _t: f64, x: &Vector6<f64>, u: &Vector3<f64>, dx: &mut Vector6<f64>) {
        *dx = self.derivative(x, u);
    }
    fn outputs(&self, _t: f64, x: &Vector6<f64>, _u: &Vector3<f64>, y: &mut Vector3<f64>) {
        *y = x.fixed_rows::<3>(0).into_owned();
    }
}

/// Number of outputs of [`WalkingPlant`]: `[q_w, τ_gait, τ_h, q, q̇]`.
pub const PLANT_OUTPUTS: usize = 15;

/// The leg worn by the synthetic wearer: input `τ_a`, outputs `[q_w, τ_gait, τ_h, q, q̇]`.
#[derive(Clone, Debug)]
pub struct WalkingPlant {
    /// The leg without the torso load.
    pub leg: LegModel,
    pub wearer: Wearer,
}

impl WalkingPlant {
    /// The leg at time `t`, with the torso load the wearer carries on it then.
    pub fn leg_at(&self, t: f64) -> LegModel {
        let mut leg = self.leg;
        leg.dynamics = leg
            .dynamics
            .with_thigh_load(self.wearer.torso_load(t) * self.wearer.torso_mass);
        leg
    }

    /// The actuator torque actually applied: the passive ankle gets none.
    pub fn actuator(u: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(0.0, u[1], u[2])
    }

    /// The joint torque of the gait at time `t`: Eq. (2)–(3) inverse dynamics along the wearer's trajectory.
    pub fn gait_torque(&self, t: f64) -> Vector3<f64> {
        let w = self.wearer.intended(t);
        self.leg_at(t).torque(&w.q, &w.qd, &w.qdd)
    }

    /// The human torque `τ_h` at time `t` in state `x`.
    pub fn human_torque(&self, t: f64, x: &Vector6<f64>) -> Vector3<f64> {
        let (q, qd) = split(x);
        self.wearer.human_torque(t, &q, &qd, &self.leg_at(t))
    }
}

impl ContinuousModel<6, 3, PLANT_OUTPUTS> for WalkingPlant {
    fn rhs(&self, t: f64, x: &Vector6<f64>, u: &Vector3<f64>, dx: &mut Vector6<f64>) {
        *dx = self
            .leg_at(t)
            .derivative(x, &(Self::actuator(u) + self.human_torque(t, x)));
    }
    fn outputs(
        &self,
        t: f64,
        x: &Vector6<f64>,
        _u: &Vector3<f64>,
        y: &mut SVector<f64, PLANT_OUTPUTS>,
    ) {
        let human = self.human_torque(t, x);
        let gait = self.gait_torque(t);
        let wearer = self.wearer.intended(t);
        for i in 0..3 {
            y[i] = wearer.q[i];
            y[3 + i] = gait[i];
            y[6 + i] = human[i];
            y[9 + i] = x[i];
            y[12 + i] = x[3 + i];
        }
    }
}

/// The controller's view of the leg for Eq. (28): the estimated rigid-body model, with the friction of
/// Eq. (3) added to the velocity-dependent term so that the computed torque compensates it (Eq. 28 itself
/// has no friction term).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionCompensated(pub LegModel);

impl bgc_runtime::control::ManipulatorDynamics<3> for FrictionCompensated {
    fn mass_matrix(&self, q: &Vector3<f64>, m: &mut nalgebra::Matrix3<f64>) {
        *m = self.0.dynamics.mass_matrix(q);
    }
    fn coriolis_torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>, c: &mut Vector3<f64>) {
        *c = self.0.dynamics.coriolis_torque(q, qd) + self.0.friction_torque(q, qd);
    }
    fn gravity_torque(&self, q: &Vector3<f64>, g: &mut Vector3<f64>) {
        *g = self.0.dynamics.gravity_torque(q);
    }
}
