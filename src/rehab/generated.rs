//! The plants of the study as generated from the `.bg` files at build time (crate `bgc_models`): the rig is
//! [`bgc_models::pendulum_rig::Model`] and the leg [`bgc_models::rehab_leg::Model`], and this module says where the
//! quantities the sensor synthesis needs sit in their vectors.
//!
//! The generated state vectors hold the energy variables first, then the integrated flows (`var x = int(f(..))`):
//!
//! - rig: `x = [q_coupling, p_pendulum, theta, theta_m]` (coupling twist, pendulum momentum, pendulum angle, rotor
//!   angle), `y = [theta_pend, omega_pend, theta_motor]`. The pendulum's angular acceleration is the momentum's
//!   rate over the inertia, `θ̈ = ṗ / J_p`, read off the model's right-hand side; the rotor speed is `θ̇_m`.
//! - leg: both inertias are in derivative causality, so `x = [phi_hip, phi_knee]` (the integrated motor flows) and
//!   `y = [theta_thigh, alpha_knee, theta_calf, omega_thigh, omega_calf]`.
//!
//! The positions are looked up by name in `STATE_NAMES` / `OUTPUT_NAMES` (a renamed variable in a `.bg` file is an
//! error naming it, not a wrong column).

use super::error::RehabError;
use bgc_models::{pendulum_rig, rehab_leg};
use bgc_runtime::model::ContinuousModel;
use nalgebra::SVector;

/// The rig model generated from `models/pendulum_rig.bg`.
pub type PendulumRigModel = pendulum_rig::Model;
/// The leg model generated from `models/rehab_leg.bg`.
pub type RehabLegModel = rehab_leg::Model;

/// Position of `name` in the name list of a generated model.
fn position(
    model: &'static str,
    kind: &'static str,
    names: &[&str],
    name: &'static str,
) -> Result<usize, RehabError> {
    names
        .iter()
        .position(|n| *n == name)
        .ok_or(RehabError::ModelLayout { model, kind, name })
}

/// Where the rig's pendulum quantities sit in the generated model's vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RigLayout {
    /// State: the coupling twist `q_coupling` \[rad\].
    pub twist: usize,
    /// State: the pendulum momentum `p_pendulum` \[N m s\].
    pub momentum: usize,
    /// State: the rotor angle `theta_m` \[rad\] (its rate is the stepper speed).
    pub rotor: usize,
    /// Output: the pendulum angle `theta_pend` \[rad\].
    pub angle: usize,
    /// Output: the pendulum angular velocity `omega_pend` \[rad/s\].
    pub rate: usize,
}

impl RigLayout {
    /// The layout of [`PendulumRigModel`].
    pub fn of_generated() -> Result<Self, RehabError> {
        let state = |n| position("pendulum_rig", "state", &pendulum_rig::STATE_NAMES, n);
        let output = |n| position("pendulum_rig", "output", &pendulum_rig::OUTPUT_NAMES, n);
        Ok(RigLayout {
            twist: state("q_coupling")?,
            momentum: state("p_pendulum")?,
            rotor: state("theta_m")?,
            angle: output("theta_pend")?,
            rate: output("omega_pend")?,
        })
    }
}

/// Where the leg's segment quantities sit in the generated model's outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LegLayout {
    /// Output: the thigh angle from the downward vertical `theta_thigh` \[rad\].
    pub thigh_angle: usize,
    /// Output: the calf inclination from the downward vertical `theta_calf` \[rad\].
    pub calf_angle: usize,
    /// Output: the thigh angular velocity `omega_thigh` \[rad/s\].
    pub thigh_rate: usize,
    /// Output: the calf angular velocity `omega_calf` \[rad/s\].
    pub calf_rate: usize,
}

impl LegLayout {
    /// The layout of [`RehabLegModel`].
    pub fn of_generated() -> Result<Self, RehabError> {
        let output = |n| position("rehab_leg", "output", &rehab_leg::OUTPUT_NAMES, n);
        Ok(LegLayout {
            thigh_angle: output("theta_thigh")?,
            calf_angle: output("theta_calf")?,
            thigh_rate: output("omega_thigh")?,
            calf_rate: output("omega_calf")?,
        })
    }
}

/// The rig model with the defaults of `models/pendulum_rig.bg`.
pub fn pendulum_rig_model() -> PendulumRigModel {
    PendulumRigModel::default()
}

/// The leg model with the defaults of `models/rehab_leg.bg`.
pub fn rehab_leg_model() -> RehabLegModel {
    RehabLegModel::default()
}

/// The rig's state at `t = 0` with the pendulum moving with the rotor and the coupling relaxed, so that the run
/// starts without a transient: `p = J_p θ̇_m(0)`, every other state zero.
pub fn rig_initial_state(
    rig: &PendulumRigModel,
    layout: &RigLayout,
) -> Result<SVector<f64, { pendulum_rig::N_STATES }>, RehabError> {
    let mut x = SVector::<f64, { pendulum_rig::N_STATES }>::zeros();
    let mut dx = x;
    rig.rhs(0.0, &x, &SVector::zeros(), &mut dx);
    let rotor_speed = dx.get(layout.rotor).copied().unwrap_or(f64::NAN);
    let momentum = rig.params().J_p * rotor_speed;
    match x.get_mut(layout.momentum) {
        Some(p) if momentum.is_finite() => *p = momentum,
        _ => {
            return Err(RehabError::BadSetting {
                name: "pendulum_rig initial momentum",
                value: momentum,
                reason: "the rotor speed at t = 0 must be finite",
            });
        }
    }
    Ok(x)
}

/// The pendulum's angular acceleration `ṗ / J_p` at `(t, x)` \[rad/s²\], from the model's right-hand side.
pub fn rig_angular_acceleration(
    rig: &PendulumRigModel,
    layout: &RigLayout,
    t: f64,
    x: &SVector<f64, { pendulum_rig::N_STATES }>,
) -> f64 {
    let mut dx = SVector::<f64, { pendulum_rig::N_STATES }>::zeros();
    rig.rhs(t, x, &SVector::zeros(), &mut dx);
    dx.get(layout.momentum).copied().unwrap_or(f64::NAN) / rig.params().J_p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A name the model lacks is an error naming the model, the kind and the name, not a wrong column.
    #[test]
    fn a_missing_name_is_an_error_naming_it() {
        let err = position(
            "rehab_leg",
            "output",
            &rehab_leg::OUTPUT_NAMES,
            "omega_knee",
        );
        assert_eq!(
            err,
            Err(RehabError::ModelLayout {
                model: "rehab_leg",
                kind: "output",
                name: "omega_knee",
            })
        );
        let text = err.map_or_else(|e| e.to_string(), |i| i.to_string());
        assert_eq!(
            text,
            "the generated rehab_leg model has no output named `omega_knee`"
        );
        assert_eq!(
            position(
                "rehab_leg",
                "output",
                &rehab_leg::OUTPUT_NAMES,
                "omega_calf"
            ),
            Ok(4)
        );
    }
}
