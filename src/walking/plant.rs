//! The leg as a continuous model `ẋ = f(x, u)` with `x = [q, q̇]` (Eqs. 1–3 and 8).
//!
//! [`LegModel`]: `M(q) q̈ + C(q, q̇) q̇ + G(q) + τ_f(q, q̇) = u`, where `u = τ_a + τ_h − Jᵀ F` is the total
//! generalised torque of Eq. (8) and the output is `q` (the joint position sensors).
//!
//! [`WalkingPlant`]: the same leg worn by the synthetic wearer of [`super::wearer`], simulated on the model
//! generated from `models/walking_leg.bg` ([`super::generated`]). The input is the
//! exoskeleton's actuator command; the motors deliver it up to their rated torques
//! ([`MOTOR_PEAK_TORQUE`], the passive ankle none). The wearer adds the human torque `τ_h(t, x)`, loads the
//! thigh with the torso in stance and stands on the foot, whose ground reaction `R` enters as `Jᵀ R` (Eq. 2):
//!
//! ```text
//! M(q) q̈ + C(q, q̇) q̇ + G(q) + τ_f(q, q̇) = sat(τ_a) + τ_h + Jᵀ(q) R
//! ```
//!
//! The paper writes this term `−Jᵀ F`: its `F` is the force the foot exerts on the ground, `F = −R`.
//! `R = (R_x, R_y)` acts on the foot at the ankle point; its vertical component is the body weight the
//! right foot carries ([`super::wearer::Wearer::support_share`]) and it points from the ankle through the hip
//! ([`axial_reaction`]), so it loads the knee (the extensors hold the bent knee against it) and, by
//! construction, exerts no torque about the hip.
//!
//! The wearer leads: their muscles supply their share of the torque the gait needs and the braces (the
//! paper's "soft braces ... facilitate compliance in coupled motion") transmit a correction
//! `K_b (q_w − q) + B_b (q̇_w − q̇)` to the lumped leg; Eq. (28) subtracts the measured `τ_h`.
//!
//! Outputs ([`PLANT_OUTPUTS`] of them), in five groups of three (ankle, knee, hip):
//!
//! 1. the joint position sensors, reading the wearer's joint angles `q_w` at the braces;
//! 2. the generalised joint torque of the gait, `u = τ_a + τ_h + Jᵀ R` along the wearer's trajectory
//!    (Eq. 8's input), computed by inverse dynamics of Eqs. (2)–(3) with the torso load: what the torque
//!    sensors and insoles give with the exoskeleton in step with the wearer. It is the filter's input. It is
//!    taken from the gait, not from the simulated exoskeleton, so that the filter's input does not contain
//!    the controller's own tracking effort: with it, the filter reads the controller's effort as the
//!    wearer's motion, the reference it feeds back runs ahead of the leg, and the loop diverges (it did,
//!    within 0.2 s, when we tried);
//! 3. the brace torque sensors, reading `τ_h`;
//! 4. the motor encoder angles `q` and 5. the joint speeds from motor rpm `q̇` (the impedance loop's
//!    feedback).

use super::anthropometry::{LegFriction, LegSegments};
use super::dynamics::LegDynamics;
use super::wearer::Wearer;
use bgc_runtime::model::{ContinuousModel, ParamError, Parametric};
use nalgebra::{SVector, Vector2, Vector3, Vector6};

/// Peak torques of the actuators (N m), ankle, knee, hip: the passive ankle has no motor; the knee and hip
/// motors are rated 17 and 38 N m (Sado et al. 2018, "Mechanical system").
pub const MOTOR_PEAK_TORQUE: [f64; 3] = [0.0, 17.0, 38.0];

/// A ground reaction on the foot with vertical component `vertical` (N, upward positive) directed from
/// the ankle at `ankle` (relative to the hip, `y` up) through the hip: `R = vertical · (x/y, 1)`. Zero when
/// the ankle is not below the hip.
pub fn axial_reaction(vertical: f64, ankle: &Vector2<f64>) -> Vector2<f64> {
    if ankle[1] < 0.0 {
        Vector2::new(vertical * ankle[0] / ankle[1], vertical)
    } else {
        Vector2::zeros()
    }
}

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

/// Number of outputs of [`WalkingPlant`]: `[q_w, u_gait, τ_h, q, q̇]`.
pub const PLANT_OUTPUTS: usize = 15;

/// The leg worn by the synthetic wearer: input the actuator command, outputs `[q_w, u_gait, τ_h, q, q̇]`.
#[derive(Clone, Debug)]
pub struct WalkingPlant {
    /// The leg without the torso load.
    pub leg: LegModel,
    pub wearer: Wearer,
}

impl WalkingPlant {
    /// The torso mass (kg) on the thigh at time `t`.
    pub fn thigh_load(&self, t: f64) -> f64 {
        self.wearer.torso_load(t) * self.wearer.torso_mass
    }

    /// The leg at time `t`, with the torso load the wearer carries on it then.
    pub fn leg_at(&self, t: f64) -> LegModel {
        let mut leg = self.leg;
        leg.dynamics = leg.dynamics.with_thigh_load(self.thigh_load(t));
        leg
    }

    /// The actuator torque the motors deliver for the command `u`: clipped to [`MOTOR_PEAK_TORQUE`] (the
    /// passive ankle gets none). Non-finite commands deliver nothing.
    pub fn actuator(u: &Vector3<f64>) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            let limit = MOTOR_PEAK_TORQUE[i];
            if u[i].is_finite() {
                u[i].clamp(-limit, limit)
            } else {
                0.0
            }
        })
    }

    /// Whether the command `u` exceeds a motor's rating at an actuated joint.
    pub fn saturates(u: &Vector3<f64>) -> bool {
        (1..3).any(|i| u[i].abs() > MOTOR_PEAK_TORQUE[i])
    }

    /// The ground reaction on the right foot (N) at time `t` with the leg at `q`.
    pub fn ground_reaction(&self, t: f64, q: &Vector3<f64>) -> Vector2<f64> {
        let vertical = self.wearer.support_share(t) * self.wearer.body_weight;
        axial_reaction(vertical, &self.leg.dynamics.ankle_position(q))
    }

    /// The generalised torque `Jᵀ(q) R` of the ground reaction at time `t` with the leg at `q`.
    pub fn ground_torque(&self, t: f64, q: &Vector3<f64>) -> Vector3<f64> {
        self.leg.dynamics.ankle_jacobian(q).transpose() * self.ground_reaction(t, q)
    }

    /// The generalised joint torque of the gait at time `t`, `u = M q̈ + C q̇ + G + τ_f` (Eqs. 2–3) along the
    /// wearer's trajectory with the torso load.
    pub fn gait_torque(&self, t: f64) -> Vector3<f64> {
        let w = self.wearer.intended(t);
        self.leg_at(t).torque(&w.q, &w.qd, &w.qdd)
    }

    /// The torque the joints (muscles and motors together) must supply along the wearer's trajectory at
    /// time `t`: the gait torque less what the ground reaction provides, `u − Jᵀ R`.
    pub fn joint_torque_demand(&self, t: f64) -> Vector3<f64> {
        let w = self.wearer.intended(t);
        self.gait_torque(t) - self.ground_torque(t, &w.q)
    }

    /// The largest magnitude per joint of [`Self::joint_torque_demand`] at `samples` instants evenly spread
    /// over `[from, to]`.
    pub fn peak_joint_torque_demand(&self, from: f64, to: f64, samples: usize) -> Vector3<f64> {
        let n = samples.max(2);
        (0..n)
            .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
            .fold(Vector3::zeros(), |peak: Vector3<f64>, t| {
                peak.sup(&self.joint_torque_demand(t).abs())
            })
    }

    /// The human torque `τ_h` at time `t` in state `x`.
    pub fn human_torque(&self, t: f64, x: &Vector6<f64>) -> Vector3<f64> {
        let (q, qd) = split(x);
        self.wearer
            .human_torque(t, &q, &qd, &self.joint_torque_demand(t))
    }
}

impl ContinuousModel<6, 3, PLANT_OUTPUTS> for WalkingPlant {
    /// The leg's motion from the model generated from `models/walking_leg.bg` ([`super::generated`]).
    fn rhs(&self, t: f64, x: &Vector6<f64>, u: &Vector3<f64>, dx: &mut Vector6<f64>) {
        let (q, _) = split(x);
        *dx = super::generated::derivative(
            &self.leg,
            self.thigh_load(t),
            x,
            &Self::actuator(u),
            &self.human_torque(t, x),
            &self.ground_reaction(t, &q),
        );
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

/// Eq. (28)'s torque `τ` made deliverable with a passive ankle: the ankle entry, which no motor applies,
/// is dropped and the knee and hip torques absorb its effect, `τ' = τ − M(q)[:, 0] τ₀ / M₀₀`. Under the
/// model, `τ'` gives the knee and hip the accelerations `u_aq` of Eq. (29) while the ankle moves as its
/// own (human and passive) torques make it, `q̈₀ = u₀ − τ₀ / M₀₀`, instead of the `u₀` that Eq. (28)
/// assumes. `None` if `M₀₀` is not positive.
pub fn passive_ankle_torque(
    mass_matrix: &nalgebra::Matrix3<f64>,
    torque: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let m00 = mass_matrix[(0, 0)];
    if !(m00.is_finite() && m00 > 0.0) {
        return None;
    }
    let mut deliverable = torque - mass_matrix.column(0) * (torque[0] / m00);
    // Zero by construction; set exactly rather than leave the rounding of τ₀ − M₀₀ τ₀ / M₀₀.
    deliverable[0] = 0.0;
    Some(deliverable)
}

/// The controller's view of the leg for Eq. (28): the estimated rigid-body model, with the friction of
/// Eq. (3) added to the velocity-dependent term so that the computed torque compensates it (Eq. 28 itself
/// has no friction term), and the stance term of Eq. (2): the generalised torque `Jᵀ R` of the measured
/// ground reaction, which the leg receives without the motors' help, is taken off the gravity term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComputedTorqueModel {
    pub leg: LegModel,
    /// `Jᵀ R` at the measured posture (zero in swing).
    pub ground_torque: Vector3<f64>,
}

impl bgc_runtime::control::ManipulatorDynamics<3> for ComputedTorqueModel {
    fn mass_matrix(&self, q: &Vector3<f64>, m: &mut nalgebra::Matrix3<f64>) {
        *m = self.leg.dynamics.mass_matrix(q);
    }
    fn coriolis_torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>, c: &mut Vector3<f64>) {
        *c = self.leg.dynamics.coriolis_torque(q, qd) + self.leg.friction_torque(q, qd);
    }
    fn gravity_torque(&self, q: &Vector3<f64>, g: &mut Vector3<f64>) {
        *g = self.leg.dynamics.gravity_torque(q) - self.ground_torque;
    }
}
