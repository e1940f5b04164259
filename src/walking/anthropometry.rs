//! Segment parameters of the coupled human–exoskeleton leg (Sado et al. 2018, Table 1, Eqs. 4–5) and the
//! joint friction and stiffness of the exoskeleton (Eq. 3, Table 8).
//!
//! # Segments
//!
//! Masses, centre-of-mass positions and sagittal moments of inertia follow Table 1 (right leg of an adult
//! male, fractions of the body mass and of the segment length) for the paper's average subject, 77 kg and
//! 1.69 m. Segment lengths are not in the paper; they are Winter's fractions of body height H (Winter,
//! *Biomechanics and Motor Control of Human Movement*, 4th ed., Wiley 2009, Table 4.1): thigh (greater
//! trochanter to femoral condyles) 0.245 H, shank (femoral condyles to medial malleolus) 0.246 H, foot
//! length 0.152 H.
//!
//! Eq. (5) writes the moment of inertia as `C₄ · (total body mass) · length² + C₅`. Read with Table 1's
//! coefficient as `C₄` it gives 1.6 kg m² for the thigh, ten times Winter's value, so we read Table 1's
//! coefficient per unit *segment* mass, `I = k · m_seg · L²` (`C₅ = 0`): thigh 0.173 kg m² (Winter about the
//! centre of mass: 0.146), shank 0.033 kg m² (Winter 0.061), foot 2.1e-4 kg m² (Winter 0.014). This reading
//! keeps each inertia proportional to its mass, so the torque of Eq. (25) is linear in the masses that the
//! dual UKF estimates.
//!
//! The exoskeleton's link masses are not printed in the paper; the lumped links here carry the human
//! segments only. The torso mass `m_tor` that Eq. (2) adds to the thigh in stance is not printed either: we
//! take 8 kg (exoskeleton torso bar, backpack with the drive electronics, and the 2.0 kg payload of the
//! experiment).
//!
//! # Friction and stiffness (Eq. 3, Table 8, right leg)
//!
//! `τ_f = b₀ tanh(q̇/ε) + b₂ q̇ + k_s q + τ_s0`. Table 8 found no kinetic Coulomb term (`b₁ = 0`) but a static
//! friction `b₀`; the case split of Eq. (3) (static friction at rest, viscous in motion) is a discontinuous
//! law that no ODE solver integrates, so the static level is applied as a smooth Coulomb term
//! `b₀ tanh(q̇/ε)`. We take `ε = 0.05 rad/s` (2.9 °/s): an order of magnitude below walking joint speeds
//! (1–6 rad/s), so the friction reaches its full level within the first percent of a swing, while the
//! regularised slope `b₀/ε` (43 N m s/rad at the hip, 106 at the knee) keeps the fastest friction time
//! constant, about `I/(b₀/ε)` ≈ 3 ms for the shank and foot about the knee, above the 1 ms sub-step of
//! the filter's explicit integrator. Table 8 prints the damping slopes with a minus sign (the regression of actuating
//! torque against velocity); as a friction torque on the left of Eq. (1) they are dissipative, so we use
//! their magnitudes, per rad/s (the table gives no velocity unit; per deg/s would be a 1600 N m s/rad
//! damper). Stiffness slopes are per degree in Table 8 and are converted to per radian. The ankle is passive
//! and unsensed for friction in the paper: no friction there.

use serde::Serialize;

/// Standard gravity (m/s²).
pub const GRAVITY: f64 = 9.80665;

/// The paper's average subject: body mass (kg).
pub const BODY_MASS: f64 = 77.0;
/// The paper's average subject: height (m).
pub const BODY_HEIGHT: f64 = 1.69;

/// Winter's segment lengths as fractions of body height (Winter 2009, Table 4.1).
pub const THIGH_LENGTH_PER_HEIGHT: f64 = 0.245;
/// Shank (leg) length over height (Winter 2009, Table 4.1).
pub const SHANK_LENGTH_PER_HEIGHT: f64 = 0.246;
/// Foot length over height (Winter 2009, Table 4.1).
pub const FOOT_LENGTH_PER_HEIGHT: f64 = 0.152;

/// Table 1, right leg: segment mass over body mass (thigh, shank, foot).
pub const MASS_FRACTION: [f64; 3] = [0.1057, 0.0505, 0.0119];
/// Table 1, right leg: centre of mass from the proximal joint over segment length (thigh, shank, foot).
pub const COM_FRACTION: [f64; 3] = [0.39, 0.42, 0.44];
/// Table 1, right leg: sagittal moment-of-inertia coefficient (thigh, shank, foot), read as `I/(m L²)`.
pub const INERTIA_COEFFICIENT: [f64; 3] = [0.1238, 0.0490, 0.0035];

/// Torso mass added to the thigh in stance (Eq. 2), kg (not printed in the paper; see the module docs).
pub const TORSO_MASS: f64 = 8.0;

/// One rigid link of the chain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Segment {
    /// Mass (kg).
    pub mass: f64,
    /// Joint-to-joint length (m).
    pub length: f64,
    /// Distance of the centre of mass from the proximal joint (m).
    pub com: f64,
    /// Moment of inertia about the centre of mass over the mass, `I/m` (m²); the inertia scales with the mass.
    pub gyration_sq: f64,
}

impl Segment {
    /// Moment of inertia about the centre of mass (kg m²).
    pub fn inertia(&self) -> f64 {
        self.mass * self.gyration_sq
    }
}

/// The three links in the paper's parameter order `w = [m₁, m₂, m₃]`: foot, shank, thigh.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LegSegments {
    pub foot: Segment,
    pub shank: Segment,
    pub thigh: Segment,
}

impl LegSegments {
    /// Table 1 and Winter's lengths for a subject of `body_mass` kg and `height` m.
    pub fn anthropometric(body_mass: f64, height: f64) -> Self {
        let seg = |i: usize, per_height: f64| {
            let length = per_height * height;
            Segment {
                mass: MASS_FRACTION[i] * body_mass,
                length,
                com: COM_FRACTION[i] * length,
                gyration_sq: INERTIA_COEFFICIENT[i] * length * length,
            }
        };
        LegSegments {
            thigh: seg(0, THIGH_LENGTH_PER_HEIGHT),
            shank: seg(1, SHANK_LENGTH_PER_HEIGHT),
            foot: seg(2, FOOT_LENGTH_PER_HEIGHT),
        }
    }

    /// The paper's average subject (77 kg, 1.69 m).
    pub fn paper_subject() -> Self {
        Self::anthropometric(BODY_MASS, BODY_HEIGHT)
    }

    /// The masses `[m₁, m₂, m₃]` (foot, shank, thigh).
    pub fn masses(&self) -> [f64; 3] {
        [self.foot.mass, self.shank.mass, self.thigh.mass]
    }

    /// A copy with the masses replaced (inertias scale with them).
    pub fn with_masses(&self, m: [f64; 3]) -> Self {
        let mut s = *self;
        s.foot.mass = m[0];
        s.shank.mass = m[1];
        s.thigh.mass = m[2];
        s
    }
}

/// Friction and stiffness of one joint (Eq. 3 with the smooth Coulomb term).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JointFriction {
    /// Static friction level `b₀` (N m).
    pub static_friction: f64,
    /// Viscous coefficient `b₂` (N m s/rad).
    pub damping: f64,
    /// Stiffness slope (N m/rad).
    pub stiffness: f64,
    /// Stiffness offset (N m).
    pub stiffness_offset: f64,
}

impl JointFriction {
    /// No friction or stiffness.
    pub const NONE: JointFriction = JointFriction {
        static_friction: 0.0,
        damping: 0.0,
        stiffness: 0.0,
        stiffness_offset: 0.0,
    };

    /// `τ_f(q, q̇)` with the Coulomb regularisation `epsilon` (rad/s).
    pub fn torque(&self, q: f64, qd: f64, epsilon: f64) -> f64 {
        self.static_friction * (qd / epsilon).tanh()
            + self.damping * qd
            + self.stiffness * q
            + self.stiffness_offset
    }
}

/// The Coulomb regularisation `ε` of Eq. (3) (rad/s); see the module docs.
pub const COULOMB_EPSILON: f64 = 0.05;

/// Table 8, right leg, per joint in the order ankle, knee, hip.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LegFriction {
    pub joints: [JointFriction; 3],
    /// The Coulomb regularisation `ε` (rad/s).
    pub epsilon: f64,
}

impl LegFriction {
    /// Table 8, right hip and right knee; the passive ankle has none.
    pub fn table8_right() -> Self {
        let per_deg = 180.0 / std::f64::consts::PI;
        LegFriction {
            joints: [
                JointFriction::NONE,
                JointFriction {
                    static_friction: 5.318,
                    damping: 6.7238,
                    stiffness: 0.015 * per_deg,
                    stiffness_offset: -0.058,
                },
                JointFriction {
                    static_friction: 2.130,
                    damping: 28.009,
                    stiffness: 0.31 * per_deg,
                    stiffness_offset: -0.042,
                },
            ],
            epsilon: COULOMB_EPSILON,
        }
    }

    /// No friction anywhere (for the energy check).
    pub fn none() -> Self {
        LegFriction {
            joints: [JointFriction::NONE; 3],
            epsilon: COULOMB_EPSILON,
        }
    }

    /// `τ_f(q, q̇)` per joint.
    pub fn torque(&self, q: &[f64; 3], qd: &[f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.joints[i].torque(q[i], qd[i], self.epsilon))
    }
}
