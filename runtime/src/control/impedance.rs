//! Impedance-based computed-torque control (Sado et al. 2018, Eqs. 28–29).
//!
//! For a manipulator `M(q) q̈ + C(q, q̇) q̇ + G(q) + τ_f = τ_a + τ_h` (Eq. 1; Eq. 2 adds `−Jᵀ F` in stance) the
//! control torque is
//!
//! ```text
//! τ_c  = M(q) u_aq + C(q, q̇) q̇ + G(q) − τ̂_h                               (28)
//! u_aq = q̈_d + M_r⁻¹ [ B_r (q̇_d − q̇) + K_r (q_d − q) ]                    (29)
//! ```
//!
//! With a correct model, no friction and the human torque known (`τ̂_h = τ_h`), substituting (28) in (1)
//! leaves `q̈ = u_aq`, so the tracking error `e = q_d − q` obeys the target impedance
//! `M_r ë + B_r ė + K_r e = 0`. If `τ̂_h` is not measured (pass zero) the human torque acts on that
//! impedance: `M_r ë + B_r ė + K_r e = −M_r M(q)⁻¹ τ_h` — the wearer meets a compliant, not a rigid, joint.
//!
//! Eq. (28) has no friction term; a friction estimate (Eq. 3) can be compensated by adding it to
//! [`ManipulatorDynamics::coriolis_torque`]. The stance-phase contact term `Jᵀ F` of Eq. (2) is likewise the
//! caller's to include in the dynamics it supplies. Everything is on fixed-size `SVector`/`SMatrix` values:
//! nothing allocates.

use nalgebra::{SMatrix, SVector};

use super::error::ControlError;

/// The rigid-body terms of an `N`-joint manipulator.
pub trait ManipulatorDynamics<const N: usize> {
    /// Writes the inertia matrix `M(q)`.
    fn mass_matrix(&self, q: &SVector<f64, N>, m: &mut SMatrix<f64, N, N>);
    /// Writes the Coriolis and centripetal torque `C(q, q̇) q̇`.
    fn coriolis_torque(&self, q: &SVector<f64, N>, qd: &SVector<f64, N>, c: &mut SVector<f64, N>);
    /// Writes the gravity torque `G(q)`.
    fn gravity_torque(&self, q: &SVector<f64, N>, g: &mut SVector<f64, N>);
}

/// [`ManipulatorDynamics`] from three closures: `M(q)`, `C(q, q̇) q̇` and `G(q)`.
#[derive(Clone, Copy, Debug)]
pub struct DynamicsFn<FM, FC, FG> {
    pub mass: FM,
    pub coriolis: FC,
    pub gravity: FG,
}

impl<FM, FC, FG, const N: usize> ManipulatorDynamics<N> for DynamicsFn<FM, FC, FG>
where
    FM: Fn(&SVector<f64, N>) -> SMatrix<f64, N, N>,
    FC: Fn(&SVector<f64, N>, &SVector<f64, N>) -> SVector<f64, N>,
    FG: Fn(&SVector<f64, N>) -> SVector<f64, N>,
{
    fn mass_matrix(&self, q: &SVector<f64, N>, m: &mut SMatrix<f64, N, N>) {
        *m = (self.mass)(q);
    }
    fn coriolis_torque(&self, q: &SVector<f64, N>, qd: &SVector<f64, N>, c: &mut SVector<f64, N>) {
        *c = (self.coriolis)(q, qd);
    }
    fn gravity_torque(&self, q: &SVector<f64, N>, g: &mut SVector<f64, N>) {
        *g = (self.gravity)(q);
    }
}

/// The target impedance `M_r ë + B_r ė + K_r e` (inertia, damping, stiffness).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceGains<const N: usize> {
    pub inertia: SMatrix<f64, N, N>,
    pub damping: SMatrix<f64, N, N>,
    pub stiffness: SMatrix<f64, N, N>,
}

/// Measured joint positions and velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointState<const N: usize> {
    pub q: SVector<f64, N>,
    pub qd: SVector<f64, N>,
}

/// Reference joint kinematics (in the paper, predicted by the dual UKF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointReference<const N: usize> {
    pub q: SVector<f64, N>,
    pub qd: SVector<f64, N>,
    pub qdd: SVector<f64, N>,
}

/// The output of one control step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceCommand<const N: usize> {
    /// The torque to apply, after the torque limits.
    pub torque: SVector<f64, N>,
    /// The torque of Eq. (28) before limiting.
    pub unlimited_torque: SVector<f64, N>,
    /// The commanded acceleration `u_aq` of Eq. (29).
    pub acceleration: SVector<f64, N>,
    /// Whether any joint was clipped by its torque limit.
    pub saturated: bool,
}

/// The controller of Eqs. (28)–(29), with optional symmetric torque limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceController<const N: usize> {
    gains: ImpedanceGains<N>,
    /// `M_r⁻¹ B_r` and `M_r⁻¹ K_r`, computed once.
    damping_per_inertia: SMatrix<f64, N, N>,
    stiffness_per_inertia: SMatrix<f64, N, N>,
    torque_limits: Option<SVector<f64, N>>,
}

impl<const N: usize> ImpedanceController<N> {
    /// Checks the gains (finite, `M_r` invertible) and precomputes `M_r⁻¹ B_r`, `M_r⁻¹ K_r`.
    pub fn new(gains: ImpedanceGains<N>) -> Result<Self, ControlError> {
        for (name, m) in [
            ("inertia", &gains.inertia),
            ("damping", &gains.damping),
            ("stiffness", &gains.stiffness),
        ] {
            if let Some(i) = m.iter().position(|v| !v.is_finite()) {
                return Err(ControlError::NonFiniteGain {
                    name,
                    row: i % N,
                    col: i / N,
                });
            }
        }
        let inverse = gains
            .inertia
            .try_inverse()
            .filter(|inv| inv.iter().all(|v| v.is_finite()))
            .ok_or(ControlError::SingularInertiaGain)?;
        // A numerically singular M_r gives an inverse that does not invert it; refuse rather than use it.
        let residual = (gains.inertia * inverse - SMatrix::<f64, N, N>::identity()).norm();
        if residual > 1e-8 {
            return Err(ControlError::SingularInertiaGain);
        }
        let damping_per_inertia = inverse * gains.damping;
        let stiffness_per_inertia = inverse * gains.stiffness;
        Ok(ImpedanceController {
            gains,
            damping_per_inertia,
            stiffness_per_inertia,
            torque_limits: None,
        })
    }

    /// Clips each joint torque to `[−limit, limit]`. A zero limit leaves a joint unactuated (the ankle of the
    /// paper's exoskeleton, `τ_a = [0, τ_2, τ_3]`).
    pub fn with_torque_limits(mut self, limits: SVector<f64, N>) -> Result<Self, ControlError> {
        if let Some(joint) = limits.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(ControlError::BadTorqueLimit {
                joint,
                value: limits[joint],
            });
        }
        self.torque_limits = Some(limits);
        Ok(self)
    }

    pub fn gains(&self) -> &ImpedanceGains<N> {
        &self.gains
    }

    /// The control torque of Eq. (28) for the measured `state`, the `reference` and the estimated human
    /// torque `human_torque` (zero if not measured).
    pub fn torque<D: ManipulatorDynamics<N>>(
        &self,
        dynamics: &D,
        state: &JointState<N>,
        reference: &JointReference<N>,
        human_torque: &SVector<f64, N>,
    ) -> Result<ImpedanceCommand<N>, ControlError> {
        for (name, v) in [
            ("q", &state.q),
            ("qd", &state.qd),
            ("q_ref", &reference.q),
            ("qd_ref", &reference.qd),
            ("qdd_ref", &reference.qdd),
            ("human_torque", human_torque),
        ] {
            finite_vector(name, v)?;
        }
        let acceleration = reference.qdd
            + self.damping_per_inertia * (reference.qd - state.qd)
            + self.stiffness_per_inertia * (reference.q - state.q);
        let mut m = SMatrix::<f64, N, N>::zeros();
        let mut c = SVector::<f64, N>::zeros();
        let mut g = SVector::<f64, N>::zeros();
        dynamics.mass_matrix(&state.q, &mut m);
        dynamics.coriolis_torque(&state.q, &state.qd, &mut c);
        dynamics.gravity_torque(&state.q, &mut g);
        if m.iter().any(|v| !v.is_finite()) {
            return Err(ControlError::NonFiniteModel { term: "M(q)" });
        }
        if c.iter().any(|v| !v.is_finite()) {
            return Err(ControlError::NonFiniteModel {
                term: "C(q, qd) qd",
            });
        }
        if g.iter().any(|v| !v.is_finite()) {
            return Err(ControlError::NonFiniteModel { term: "G(q)" });
        }
        let unlimited_torque = m * acceleration + c + g - human_torque;
        let (torque, saturated) = match &self.torque_limits {
            None => (unlimited_torque, false),
            Some(limits) => {
                let clipped = unlimited_torque.zip_map(limits, |t, l| t.clamp(-l, l));
                (clipped, clipped != unlimited_torque)
            }
        };
        Ok(ImpedanceCommand {
            torque,
            unlimited_torque,
            acceleration,
            saturated,
        })
    }
}

fn finite_vector<const N: usize>(
    name: &'static str,
    v: &SVector<f64, N>,
) -> Result<(), ControlError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(ControlError::NonFiniteInput {
            name,
            index,
            value: v[index],
        }),
        None => Ok(()),
    }
}
