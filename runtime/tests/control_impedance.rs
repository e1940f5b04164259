//! The impedance controller of Eqs. 28–29 on a 1-DOF pendulum.

use bgc_runtime::control::{
    ControlError, DynamicsFn, ImpedanceController, ImpedanceGains, JointReference, JointState,
    ManipulatorDynamics,
};
use bgc_runtime::model::ContinuousModel;
use bgc_runtime::sim::{SampledLoopConfig, simulate_sampled_loop};
use nalgebra::{Matrix1, SVector, Vector1, Vector2};

const MASS: f64 = 2.0;
const LENGTH: f64 = 0.5;
const GRAVITY: f64 = 9.81;

/// A point-mass pendulum: M = m l², C q̇ = 0, G = m g l sin q.
fn pendulum_dynamics() -> impl ManipulatorDynamics<1> {
    DynamicsFn {
        mass: |_q: &Vector1<f64>| Matrix1::new(MASS * LENGTH * LENGTH),
        coriolis: |_q: &Vector1<f64>, _qd: &Vector1<f64>| Vector1::zeros(),
        gravity: |q: &Vector1<f64>| Vector1::new(MASS * GRAVITY * LENGTH * q[0].sin()),
    }
}

fn gains(m: f64, b: f64, k: f64) -> ImpedanceGains<1> {
    ImpedanceGains {
        inertia: Matrix1::new(m),
        damping: Matrix1::new(b),
        stiffness: Matrix1::new(k),
    }
}

#[test]
fn torque_equals_hand_computation() {
    // M_r = 2, B_r = 10, K_r = 50; q = 0.3, q̇ = −0.5; q_d = 0.5, q̇_d = 0.2, q̈_d = 1; τ_h = 0.7.
    // u = 1 + (1/2)[10 (0.2 + 0.5) + 50 (0.5 − 0.3)] = 1 + 0.5 (7 + 10) = 9.5
    // τ = m l² u + m g l sin 0.3 − τ_h = 0.5 · 9.5 + 9.81 · 0.29552020666133955 − 0.7 = 6.949053227347741
    let ctl = ImpedanceController::new(gains(2.0, 10.0, 50.0)).unwrap();
    let cmd = ctl
        .torque(
            &pendulum_dynamics(),
            &JointState {
                q: Vector1::new(0.3),
                qd: Vector1::new(-0.5),
            },
            &JointReference {
                q: Vector1::new(0.5),
                qd: Vector1::new(0.2),
                qdd: Vector1::new(1.0),
            },
            &Vector1::new(0.7),
        )
        .unwrap();
    assert!((cmd.acceleration[0] - 9.5).abs() < 1e-14);
    assert!(
        (cmd.torque[0] - 6.949053227347741).abs() < 1e-12,
        "{}",
        cmd.torque[0]
    );
    assert!(!cmd.saturated);
}

/// The pendulum as a plant: state (q, q̇), input τ, outputs (q, q̇); the wearer adds τ_h(t) = 2 sin 3t.
struct Pendulum;

fn human_torque(t: f64) -> f64 {
    2.0 * (3.0 * t).sin()
}

impl ContinuousModel<2, 1, 2> for Pendulum {
    fn rhs(&self, t: f64, x: &Vector2<f64>, u: &Vector1<f64>, dx: &mut Vector2<f64>) {
        dx[0] = x[1];
        dx[1] = (u[0] + human_torque(t) - MASS * GRAVITY * LENGTH * x[0].sin())
            / (MASS * LENGTH * LENGTH);
    }
    fn outputs(&self, _t: f64, x: &Vector2<f64>, _u: &Vector1<f64>, y: &mut Vector2<f64>) {
        *y = *x;
    }
}

/// Runs the controller at 1 kHz for `seconds` against the reference `r(t) = (q, q̇, q̈)`.
fn run(
    reference: impl Fn(f64) -> (f64, f64, f64),
    compensate_human: bool,
    seconds: f64,
) -> (Vec<f64>, Vec<f64>) {
    let ctl = ImpedanceController::new(gains(1.0, 20.0, 100.0)).unwrap();
    let dynamics = pendulum_dynamics();
    let dt = 1e-3;
    let mut controller = |_k: usize, t: f64, y: &SVector<f64, 2>| {
        let (q, qd, qdd) = reference(t);
        let tau_h = if compensate_human {
            human_torque(t)
        } else {
            0.0
        };
        ctl.torque(
            &dynamics,
            &JointState {
                q: Vector1::new(y[0]),
                qd: Vector1::new(y[1]),
            },
            &JointReference {
                q: Vector1::new(q),
                qd: Vector1::new(qd),
                qdd: Vector1::new(qdd),
            },
            &Vector1::new(tau_h),
        )
        .map(|c| c.torque)
        .unwrap_or(Vector1::new(f64::NAN))
    };
    let cfg = SampledLoopConfig::new(dt, (seconds / dt).round() as usize, Vector2::zeros());
    let traj = simulate_sampled_loop(&Pendulum, &mut controller, &cfg).unwrap();
    let errors = traj
        .times
        .iter()
        .zip(&traj.states)
        .map(|(&t, x)| reference(t).0 - x[0])
        .collect();
    (traj.times, errors)
}

#[test]
fn error_follows_the_target_impedance() {
    // Constant reference 0.2 rad from rest with the human torque compensated: ë + 20 ė + 100 e = 0,
    // critically damped, e(t) = 0.2 (1 + 10 t) e^{−10 t}. The 1 ms hold adds an O(ωT) deviation.
    let (times, errors) = run(|_t| (0.2, 0.0, 0.0), true, 1.0);
    for (t, e) in times.iter().zip(&errors) {
        let target = 0.2 * (1.0 + 10.0 * t) * (-10.0 * t).exp();
        assert!((e - target).abs() < 1e-3, "t={t}: {e} vs {target}");
    }
}

#[test]
fn pendulum_tracks_a_sinusoid() {
    // q_d = 0.5 sin 2t: after the transient (time constant 0.1 s) the error stays below 0.5 mrad.
    let reference = |t: f64| {
        (
            0.5 * (2.0 * t).sin(),
            (2.0 * t).cos(),
            -2.0 * (2.0 * t).sin(),
        )
    };
    let (times, errors) = run(reference, true, 4.0);
    let worst = times
        .iter()
        .zip(&errors)
        .filter(|(t, _)| **t > 1.5)
        .map(|(_, e)| e.abs())
        .fold(0.0, f64::max);
    assert!(worst < 5e-4, "worst tracking error {worst}");
    // Without the human-torque term the wearer's 2 N m pushes the joint off the reference: through the
    // target impedance M_r ë + B_r ė + K_r e = −M_r M⁻¹ τ_h the error reaches a few centiradians.
    let (times, errors) = run(reference, false, 4.0);
    let worst_uncompensated = times
        .iter()
        .zip(&errors)
        .filter(|(t, _)| **t > 1.5)
        .map(|(_, e)| e.abs())
        .fold(0.0, f64::max);
    assert!(worst_uncompensated > 0.02, "{worst_uncompensated}");
}

#[test]
fn limits_and_bad_inputs() {
    let state = JointState {
        q: Vector1::new(0.0),
        qd: Vector1::new(0.0),
    };
    let reference = JointReference {
        q: Vector1::new(1.0),
        qd: Vector1::new(0.0),
        qdd: Vector1::new(0.0),
    };
    // A zero limit leaves the joint unactuated, as the paper's ankle.
    let ctl = ImpedanceController::new(gains(1.0, 20.0, 100.0))
        .unwrap()
        .with_torque_limits(Vector1::new(0.0))
        .unwrap();
    let cmd = ctl
        .torque(&pendulum_dynamics(), &state, &reference, &Vector1::zeros())
        .unwrap();
    assert_eq!(cmd.torque[0], 0.0);
    assert!((cmd.unlimited_torque[0] - 0.5 * 100.0).abs() < 1e-12);
    assert!(cmd.saturated);
    assert_eq!(
        ImpedanceController::new(gains(0.0, 1.0, 1.0)),
        Err(ControlError::SingularInertiaGain)
    );
    let nan_state = JointState {
        q: Vector1::new(f64::NAN),
        ..state
    };
    assert!(matches!(
        ctl.torque(
            &pendulum_dynamics(),
            &nan_state,
            &reference,
            &Vector1::zeros()
        ),
        Err(ControlError::NonFiniteInput {
            name: "q",
            index: 0,
            ..
        })
    ));
    assert!(matches!(
        ImpedanceController::new(gains(1.0, 1.0, 1.0))
            .and_then(|c| c.with_torque_limits(Vector1::new(-1.0))),
        Err(ControlError::BadTorqueLimit { joint: 0, .. })
    ));
}
