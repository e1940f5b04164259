//! Euler–Lagrange dynamics of the three-link sagittal leg (Sado et al. 2018, Eqs. 1–2), derived by hand.
//!
//! This is the reference model: the `.bg` model `models/walking_leg.bg` describes the same leg as an I-field
//! with `M(q)`, and the generated code will be tested against these functions; until the compiler pipeline
//! generates it, the walking example uses this module as its plant.
//!
//! # Coordinates
//!
//! `q = [θ₁, θ₂, θ₃]` = ankle dorsiflexion, knee flexion, hip flexion (rad), the paper's order. The chain is
//! rooted at the hip (Eq. 1's swing leg, pivoted at a hip that does not accelerate); Eq. (2) keeps the same
//! coordinates and terms for stance ("all terms are as defined in Eq. (1)"), adds the torso mass to the
//! thigh ([`LegDynamics::with_thigh_load`]) and the ground reaction as `−Jᵀ F` ([`LegDynamics::ankle_jacobian`]),
//! where `F` is the force the foot exerts on the ground: the ground's reaction on the foot, `R = −F`,
//! enters as `+Jᵀ R`. The ground pivots the stance leg through that contact force. (Re-rooting the chain at the ankle with the
//! torso lumped on the thigh would leave nothing distal to the hip joint, a singular `M(q)`.)
//! Absolute link angles, counter-clockwise from the downward vertical with the subject facing `+x`:
//!
//! ```text
//! φ_T = θ₃,   φ_S = θ₃ − θ₂,   φ_F = θ₃ − θ₂ + θ₁ + π/2,   i.e. ω = A q̇,  A = [[0,0,1],[0,−1,1],[1,−1,1]]
//! ```
//!
//! (knee flexion swings the shank back; at `θ₁ = 0` the foot points forward, perpendicular to the shank).
//! Link `a` has mass `m_a`, length `l_a`, centre of mass at `c_a` from its proximal joint and inertia `I_a`;
//! with `r(φ) = (sin φ, −cos φ)` the knee is at `l_T r(φ_T)`, the ankle at `l_T r(φ_T) + l_S r(φ_S)`.
//!
//! # Lagrangian
//!
//! `T = ½ ωᵀ D(φ) ω` with `D_aa = d_a`, `D_ab = h_ab cos(φ_a − φ_b)`:
//!
//! ```text
//! d_T = I_T + m_T c_T² + (m_S + m_F) l_T²     h_TS = (m_S c_S + m_F l_S) l_T
//! d_S = I_S + m_S c_S² + m_F l_S²             h_TF = m_F c_F l_T
//! d_F = I_F + m_F c_F²                        h_SF = m_F c_F l_S
//! V   = −g [ (m_T c_T + (m_S + m_F) l_T) cos φ_T + (m_S c_S + m_F l_S) cos φ_S + m_F c_F cos φ_F ]
//! ```
//!
//! Lagrange's equations in `φ` give `D ω̇ + c + G_φ = τ_φ` with `c_a = Σ_b h_ab sin(φ_a − φ_b) ω_b²` and
//! `G_φ,a = ∂V/∂φ_a = g_a sin φ_a`. Since `φ` is affine in `q`, `M(q) = Aᵀ D A`, `C(q, q̇) q̇ = Aᵀ c`,
//! `G(q) = Aᵀ G_φ`, and the Coriolis matrix `C = Aᵀ C_φ A` with `C_φ,ab = h_ab sin(φ_a − φ_b) ω_b` (`a ≠ b`),
//! for which `Ṁ − 2C` is skew-symmetric (`(Ṁ − 2C)_φ,ab = −h_ab sin(φ_a − φ_b)(ω_a + ω_b)`).
//!
//! Every term is linear in the masses when each inertia is `m_a ρ_a²` (see [`super::anthropometry`]), which
//! is what makes the dual UKF's torque observation (Eq. 25) informative about `[m₁, m₂, m₃]`.

use super::anthropometry::{GRAVITY, LegSegments};
use bgc_runtime::control::ManipulatorDynamics;
use nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};

/// The joint-to-absolute-angle map `ω = A q̇`.
pub fn angle_map() -> Matrix3<f64> {
    Matrix3::new(0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 1.0, -1.0, 1.0)
}

/// Absolute link angles `[φ_T, φ_S, φ_F]` for joint angles `q = [θ₁, θ₂, θ₃]`.
pub fn link_angles(q: &Vector3<f64>) -> [f64; 3] {
    let phi_t = q[2];
    let phi_s = q[2] - q[1];
    [phi_t, phi_s, phi_s + q[0] + std::f64::consts::FRAC_PI_2]
}

/// The rigid-body dynamics of the leg for given segments (and torso load on the thigh).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegDynamics {
    pub segments: LegSegments,
    pub gravity: f64,
}

/// Mass-dependent constants of the Lagrangian, in link order thigh, shank, foot.
struct Constants {
    d: [f64; 3],
    /// `h_TS, h_TF, h_SF`.
    h: [f64; 3],
    /// Gravity moments `g_T, g_S, g_F` (N m).
    g: [f64; 3],
}

impl LegDynamics {
    /// Leg with standard gravity.
    pub fn new(segments: LegSegments) -> Self {
        LegDynamics {
            segments,
            gravity: GRAVITY,
        }
    }

    /// The same leg with `extra` kg lumped at the thigh's centre of mass (the stance torso load of Eq. 2).
    pub fn with_thigh_load(&self, extra: f64) -> Self {
        let mut d = *self;
        d.segments.thigh.mass += extra;
        d
    }

    fn constants(&self) -> Constants {
        let (t, s, f) = (
            &self.segments.thigh,
            &self.segments.shank,
            &self.segments.foot,
        );
        let d = [
            t.inertia() + t.mass * t.com * t.com + (s.mass + f.mass) * t.length * t.length,
            s.inertia() + s.mass * s.com * s.com + f.mass * s.length * s.length,
            f.inertia() + f.mass * f.com * f.com,
        ];
        let h = [
            (s.mass * s.com + f.mass * s.length) * t.length,
            f.mass * f.com * t.length,
            f.mass * f.com * s.length,
        ];
        let g = [
            self.gravity * (t.mass * t.com + (s.mass + f.mass) * t.length),
            self.gravity * (s.mass * s.com + f.mass * s.length),
            self.gravity * f.mass * f.com,
        ];
        Constants { d, h, g }
    }

    /// `h_ab` as a symmetric matrix with zero diagonal.
    fn coupling(h: &[f64; 3]) -> Matrix3<f64> {
        Matrix3::new(0.0, h[0], h[1], h[0], 0.0, h[2], h[1], h[2], 0.0)
    }

    /// `D(φ)`, the inertia matrix in absolute angles.
    fn absolute_mass(&self, phi: &[f64; 3]) -> Matrix3<f64> {
        let k = self.constants();
        let h = Self::coupling(&k.h);
        Matrix3::from_fn(|a, b| {
            if a == b {
                k.d[a]
            } else {
                h[(a, b)] * (phi[a] - phi[b]).cos()
            }
        })
    }

    /// `M(q)`.
    pub fn mass_matrix(&self, q: &Vector3<f64>) -> Matrix3<f64> {
        let a = angle_map();
        a.transpose() * self.absolute_mass(&link_angles(q)) * a
    }

    /// The Coriolis matrix `C(q, q̇)` of the Christoffel form (so that `Ṁ − 2C` is skew-symmetric).
    pub fn coriolis_matrix(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> Matrix3<f64> {
        let a = angle_map();
        let phi = link_angles(q);
        let omega = a * qd;
        let h = Self::coupling(&self.constants().h);
        let c_phi = Matrix3::from_fn(|i, j| h[(i, j)] * (phi[i] - phi[j]).sin() * omega[j]);
        a.transpose() * c_phi * a
    }

    /// `Ṁ(q, q̇) = Σ_k ∂M/∂q_k q̇_k`, from the derivative of `D(φ)`.
    pub fn mass_matrix_rate(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> Matrix3<f64> {
        let a = angle_map();
        let phi = link_angles(q);
        let omega = a * qd;
        let h = Self::coupling(&self.constants().h);
        let d_dot =
            Matrix3::from_fn(|i, j| -h[(i, j)] * (phi[i] - phi[j]).sin() * (omega[i] - omega[j]));
        a.transpose() * d_dot * a
    }

    /// `C(q, q̇) q̇`.
    pub fn coriolis_torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> Vector3<f64> {
        let a = angle_map();
        let phi = link_angles(q);
        let omega = a * qd;
        let h = Self::coupling(&self.constants().h);
        let c = Vector3::from_fn(|i, _| {
            (0..3)
                .map(|j| h[(i, j)] * (phi[i] - phi[j]).sin() * omega[j] * omega[j])
                .sum()
        });
        a.transpose() * c
    }

    /// `G(q)`.
    pub fn gravity_torque(&self, q: &Vector3<f64>) -> Vector3<f64> {
        let phi = link_angles(q);
        let g = self.constants().g;
        let g_phi = Vector3::new(
            g[0] * phi[0].sin(),
            g[1] * phi[1].sin(),
            g[2] * phi[2].sin(),
        );
        angle_map().transpose() * g_phi
    }

    /// Kinetic energy `½ q̇ᵀ M q̇` (J).
    pub fn kinetic_energy(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> f64 {
        0.5 * qd.dot(&(self.mass_matrix(q) * qd))
    }

    /// Potential energy relative to the hip height (J).
    pub fn potential_energy(&self, q: &Vector3<f64>) -> f64 {
        let phi = link_angles(q);
        let g = self.constants().g;
        -(g[0] * phi[0].cos() + g[1] * phi[1].cos() + g[2] * phi[2].cos())
    }

    /// Total mechanical energy (J).
    pub fn energy(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> f64 {
        self.kinetic_energy(q, qd) + self.potential_energy(q)
    }

    /// Ankle position relative to the hip (m), `x` forward, `y` up.
    pub fn ankle_position(&self, q: &Vector3<f64>) -> Vector2<f64> {
        let phi = link_angles(q);
        let (lt, ls) = (self.segments.thigh.length, self.segments.shank.length);
        Vector2::new(
            lt * phi[0].sin() + ls * phi[1].sin(),
            -lt * phi[0].cos() - ls * phi[1].cos(),
        )
    }

    /// The Jacobian `J = ∂p_ankle/∂q` of the ankle point. A force `R` applied to the foot at the ankle
    /// point (the ground's reaction) does the generalised work of `Jᵀ R` (virtual work `Rᵀ J δq`); Eq. (2)
    /// writes it `−Jᵀ F` with `F = −R` the force of the foot on the ground.
    pub fn ankle_jacobian(&self, q: &Vector3<f64>) -> Matrix2x3<f64> {
        let phi = link_angles(q);
        let (lt, ls) = (self.segments.thigh.length, self.segments.shank.length);
        let d_phi = Matrix2x3::new(
            lt * phi[0].cos(),
            ls * phi[1].cos(),
            0.0,
            lt * phi[0].sin(),
            ls * phi[1].sin(),
            0.0,
        );
        d_phi * angle_map()
    }

    /// Forward dynamics without friction: `q̈ = M⁻¹ (τ − C q̇ − G)`; `None` if `M` is not invertible.
    pub fn acceleration(
        &self,
        q: &Vector3<f64>,
        qd: &Vector3<f64>,
        tau: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        let rhs = tau - self.coriolis_torque(q, qd) - self.gravity_torque(q);
        self.mass_matrix(q).cholesky().map(|ch| ch.solve(&rhs))
    }

    /// Inverse dynamics without friction, `M q̈ + C q̇ + G`.
    pub fn inverse(&self, q: &Vector3<f64>, qd: &Vector3<f64>, qdd: &Vector3<f64>) -> Vector3<f64> {
        self.mass_matrix(q) * qdd + self.coriolis_torque(q, qd) + self.gravity_torque(q)
    }
}

impl ManipulatorDynamics<3> for LegDynamics {
    fn mass_matrix(&self, q: &Vector3<f64>, m: &mut Matrix3<f64>) {
        *m = LegDynamics::mass_matrix(self, q);
    }
    fn coriolis_torque(&self, q: &Vector3<f64>, qd: &Vector3<f64>, c: &mut Vector3<f64>) {
        *c = LegDynamics::coriolis_torque(self, q, qd);
    }
    fn gravity_torque(&self, q: &Vector3<f64>, g: &mut Vector3<f64>) {
        *g = LegDynamics::gravity_torque(self, q);
    }
}
