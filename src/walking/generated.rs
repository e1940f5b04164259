//! The simulated exoskeleton leg runs on the model bgc generates from `models/walking_leg.bg` (crate
//! `bgc_models`, module `walking_leg`: an I-field with `M(q)`, its rates solved from the mass-matrix form).
//!
//! The estimator and the computed-torque controller keep their own hand-written model ([`super::dynamics`]), as a
//! controller's internal model is separate from the machine it drives; `tests/walking_equations.rs` checks that
//! both describe the same leg.
//!
//! The `.bg` model is written for the paper's segment table: lengths `0.245 H`, `0.246 H`, `0.152 H`, centres of
//! mass and inertias in the proportions of Table 1, free link masses. [`params`] maps a [`LegModel`] onto its
//! parameters and refuses (NaN parameters, so the simulation reports non-finite rates) a leg whose geometry the
//! file cannot express.

use super::anthropometry::{
    COM_FRACTION, FOOT_LENGTH_PER_HEIGHT, INERTIA_COEFFICIENT, SHANK_LENGTH_PER_HEIGHT,
    THIGH_LENGTH_PER_HEIGHT,
};
use super::plant::LegModel;
use bgc_models::walking_leg as generated;
use nalgebra::{Vector2, Vector3, Vector6};

/// The generated model's parameters for `leg` with `thigh_load` kg of torso on the thigh; every field NaN when
/// the leg's geometry is not that of the `.bg` file.
pub fn params(leg: &LegModel, thigh_load: f64) -> generated::Params {
    let s = &leg.dynamics.segments;
    let height = s.thigh.length / THIGH_LENGTH_PER_HEIGHT;
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-300);
    let segments = [
        (&s.thigh, THIGH_LENGTH_PER_HEIGHT, 0),
        (&s.shank, SHANK_LENGTH_PER_HEIGHT, 1),
        (&s.foot, FOOT_LENGTH_PER_HEIGHT, 2),
    ];
    let shaped = segments.iter().all(|(seg, per_height, i)| {
        same(seg.length, per_height * height)
            && same(seg.com, COM_FRACTION[*i] * seg.length)
            && same(
                seg.gyration_sq,
                INERTIA_COEFFICIENT[*i] * seg.length * seg.length,
            )
    });
    let [ankle, knee, hip] = leg.friction.joints;
    let ankle_free = ankle.static_friction == 0.0
        && ankle.damping == 0.0
        && ankle.stiffness == 0.0
        && ankle.stiffness_offset == 0.0;
    let p = generated::Params {
        g: leg.dynamics.gravity,
        height,
        stance: 1.0,
        m_F: s.foot.mass,
        m_S: s.shank.mass,
        m_T: s.thigh.mass + thigh_load,
        eps: leg.friction.epsilon,
        b0_knee: knee.static_friction,
        b2_knee: knee.damping,
        k_knee: knee.stiffness,
        ts0_knee: knee.stiffness_offset,
        b0_hip: hip.static_friction,
        b2_hip: hip.damping,
        k_hip: hip.stiffness,
        ts0_hip: hip.stiffness_offset,
    };
    if shaped && ankle_free {
        p
    } else {
        generated::Params { g: f64::NAN, ..p }
    }
}

/// `ẋ` of the leg with `thigh_load` kg on the thigh, driven by the actuator torques `actuator` (the ankle's is
/// added to the human torque: the `.bg` model has no ankle motor), the human torques `human` and the ground
/// reaction `reaction` on the foot at the ankle point (the `.bg` input is the foot's force on the ground, its
/// negative).
pub fn derivative(
    leg: &LegModel,
    thigh_load: f64,
    x: &Vector6<f64>,
    actuator: &Vector3<f64>,
    human: &Vector3<f64>,
    reaction: &Vector2<f64>,
) -> Vector6<f64> {
    let p = params(leg, thigh_load);
    // INPUT_NAMES: tau_a2, tau_a3, tau_h1, tau_h2, tau_h3, F_x, F_y.
    let u = generated::Inputs::from_column_slice(&[
        actuator[1],
        actuator[2],
        human[0] + actuator[0],
        human[1],
        human[2],
        -reaction[0],
        -reaction[1],
    ]);
    generated::rhs(&p, 0.0, x, &u)
}
