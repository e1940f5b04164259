//! The back-support exoskeleton study (Designs 2020, 4, 53) against scipy references and the paper's figures.
//!
//! The study's plant is the state space bgc generates from `models/back_support.bg`; the first test holds it
//! against Eq. 3 coded by hand below. References (scipy 1.17, numpy), one script; the model is Eq. 3 with the
//! seeds' README parameters:
//! ```python
//! import numpy as np, scipy.linalg as sl
//! from scipy.signal import cont2discrete
//! np.set_printoptions(precision=17)
//! Jm, Jg, rg, kg = 3.06e-4, 0.40e-4, 160.0, 2.64e4
//! Jsi, Jse, ks = 1e-4, 1.19e-3, 3.38e4
//! bg, dg, keh = 0.65, 6.0, 1125.0
//! J = Jm + Jg
//! def a7(friction):                      # friction: the b_g term of the motor line (b_g/r_g² or b_g/r_g)
//!     A = np.zeros((7, 7))
//!     A[0, 1] = 1; A[2, 3] = 1; A[4, 5] = 1
//!     A[1, :4] = [-kg/(J*rg**2), -(friction + dg/rg**2)/J, kg/(J*rg), dg/(J*rg)]
//!     A[3, :5] = [kg/(Jsi*rg), dg/(Jsi*rg), -(kg+ks)/Jsi, -dg/Jsi, ks/Jsi]
//!     A[5, 2:7] = [ks/Jse, 0, -(keh+ks)/Jse, 0, keh/Jse]
//!     return A
//! B = np.zeros((7, 2)); B[1, 0] = 1/J; B[6, 1] = 1
//! C = np.array([[0, 1, 0, 0, 0, 0, 0], [0, 0, ks, 0, -ks, 0, 0]], float)
//! def outputs(A):                        # exact (ZOH) response of the model check on the 1 ms grid
//!     Ad, Bd, *_ = cont2discrete((A, B, C, np.zeros((2, 2))), 1e-3)
//!     x = np.zeros(7); ys = [C @ x]
//!     for k in range(1000):
//!         u = np.array([0.1, 0.05 if k >= 100 else 0.0])
//!         x = Ad @ x + Bd @ u; ys.append(C @ x)
//!     return np.array(ys)
//! y3 = outputs(a7(bg/rg**2)); y1 = outputs(a7(bg/rg))
//! print(abs(y3[:,1]-y1[:,1]).max(), abs(y3[:,0]-y1[:,0]).max())   # 16.72948654582 19.22211513625
//! A1 = a7(bg/rg**2)[:6, :6]; Bm = B[:6, :1]; Cb = np.array([[0, 0, 0, 0, keh, 0]])
//! def lqi(qz):
//!     p = len(qz); A = np.zeros((6+p, 6+p)); A[:6, :6] = A1; A[6, :6] = -Cb
//!     if p == 2: A[7, 6] = 1
//!     Bq = np.vstack([Bm, np.zeros((p, 1))]); Q = np.diag([1e5, 1e5, 1e7, 1e7, 1e7, 1e7] + qz)
//!     X = sl.solve_continuous_are(A, Bq, Q, np.array([[1e12]])); return (Bq.T @ X / 1e12).ravel()
//! for qz in ([5e13], [1e13], [5e13, 5e15], [1e13, 5e15]): print(lqi(qz))
//! # noise-free lifting scenario: exact ZOH plant, state feedback on the trunk-relative state
//! A7 = a7(bg/rg**2); C7b = np.array([0, 0, 0, 0, keh, 0, -keh])
//! Ad, Bd, *_ = cont2discrete((A7, B, C, np.zeros((2, 2))), 1e-3)
//! v = np.array([rg, 0, 1, 0, 1, 0])
//! for qz in ([5e13, 5e15], [1e13, 5e15]):
//!     K = lqi(qz); Kx, kz, kzz = K[:6], K[6], K[7]
//!     x = np.zeros(7); z = zz = 0.0; us = []
//!     for k in range(1000):
//!         t = k * 1e-3; delta = x[:6] - v * x[6]
//!         yb = C7b @ x; u = -(Kx @ delta) - kz * z - kzz * zz; us.append(u)
//!         zz += 1e-3 * z; z += 1e-3 * ((10.0 if 0.1 <= t + 1e-12 < 0.6 else 0.0) - yb)
//!         x = Ad @ x + Bd @ np.array([u, 0.1])
//!     us = np.array(us); i = np.argmax(abs(us))
//!     print(abs(us[i]), i * 1e-3)        # 0.606994512979 0.115, and 0.463182219721 0.118
//! K = lqi([5e13, 5e15]); Kx, kz, kzz = K[:6], K[6], K[7]
//! # margins at the plant input with the continuous observer of Eq. 9 (python-control 0.10.2)
//! import control as ct
//! from scipy.optimize import brentq
//! T = 1e-3; sw, sh, sv, st = 0.1e-3/3, 0.15e-3/3, 0.1e-6/3, 35e-3/3
//! Bh = np.array([[-rg, 0, -1, 0, -1, 0]]).T; Cm = C[:, :6]
//! L, _, _ = ct.lqe(A1, np.hstack([Bm, Bh]), Cm, np.diag([sw**2, sh**2]) * T, np.diag([sv**2, st**2]) * T)
//! Ac = np.zeros((8, 8)); Ac[:6, :6] = A1 - Bm @ Kx[None, :] - L @ Cm
//! Ac[:6, 6] = -Bm[:, 0] * kz; Ac[:6, 7] = -Bm[:, 0] * kzz; Ac[6, :6] = -Cb; Ac[7, 6] = 1
//! ctrl = ct.ss(Ac, np.vstack([L, np.zeros((2, 2))]), -K[None, :], np.zeros((1, 2)))
//! loop = -ct.series(ct.ss(A1, Bm, Cm, np.zeros((2, 1))), ctrl)
//! gm, pm, sm, wpc, wgc, wms = ct.stability_margins(loop)
//! print(gm, pm, wgc, np.deg2rad(pm) / wgc)   # 1.2021457581 14.3798879873 35.4972484667 0.0070703055
//! # rejection bandwidth: |closed loop / open loop| from θ̇_h to ŷ_b rises through −3 dB
//! n = 14; Acl = np.zeros((n, n))
//! Acl[:6, :6] = A1; Acl[:6, 6:12] = -Bm @ Kx[None, :]; Acl[:6, 12] = -Bm[:, 0] * kz; Acl[:6, 13] = -Bm[:, 0] * kzz
//! Acl[6:12, :6] = L @ Cm; Acl[6:12, 6:12] = A1 - Bm @ Kx[None, :] - L @ Cm
//! Acl[6:12, 12] = -Bm[:, 0] * kz; Acl[6:12, 13] = -Bm[:, 0] * kzz; Acl[12, 6:12] = -Cb; Acl[13, 12] = 1
//! Bcl = np.vstack([Bh, Bh, [[0], [0]]]); Ccl = np.zeros((1, n)); Ccl[0, 6:12] = Cb
//! cl = ct.ss(Acl, Bcl, Ccl, 0); ol = ct.ss(A1, Bh, Cb, 0)
//! f = lambda hz: 20 * np.log10(abs(cl(2j * np.pi * hz)) / abs(ol(2j * np.pi * hz))) + 3
//! print(brentq(lambda h: f(h).item(), 1.0, 6.0))   # 5.0349307169
//! ```

#![allow(clippy::excessive_precision)] // reference values are pasted from scipy at full precision

use nalgebra::SMatrix;

use bgc_runtime::linalg::RiccatiError;
use bgc_runtime::sim::SolverOptions;
use bgc_workspace::back_support::BackSupportError;
use bgc_workspace::back_support::lqr::{self, PAPER_STATE_GAIN};
use bgc_workspace::back_support::model_check::model_check;
use bgc_workspace::back_support::observer::{self, NoiseModel};
use bgc_workspace::back_support::params::Params;
use bgc_workspace::back_support::plant::{self, DesignModel, NU, NX, NY, Plant};
use bgc_workspace::back_support::scenario::{self, PlantIntegration, ScenarioConfig};
use bgc_workspace::back_support::{recovery, robustness};

fn setup() -> (Params, Plant, DesignModel) {
    let p = Params::paper();
    let plant = plant::plant(&p).unwrap();
    let model = plant::design_model(&plant, &p).unwrap();
    (p, plant, model)
}

/// Eq. 3 of the paper coded by hand from its printed entries, with the gearbox friction as `b_g / r_g²` in the
/// motor line (where the bond graph's `R: b_g` after the gearbox reflects to), and the outputs of Eqs. 5–6.
fn eq3_by_hand(p: &Params) -> Plant {
    let j = p.j_motor();
    let rg = p.r_g;
    let (jsi, jse) = (p.j_s_int, p.j_s_ext);
    #[rustfmt::skip]
    let a = SMatrix::<f64, NX, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        -p.k_g / (j * rg * rg), -(p.b_f * rg * rg + p.b_g + p.d_g) / (j * rg * rg),
            p.k_g / (j * rg), p.d_g / (j * rg), 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        p.k_g / (jsi * rg), p.d_g / (jsi * rg), -(p.k_g + p.k_s) / jsi, -(p.d_g + p.d_s) / jsi,
            p.k_s / jsi, p.d_s / jsi, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
        0.0, 0.0, p.k_s / jse, p.d_s / jse, -(p.k_eh + p.k_s) / jse, -(p.d_eh + p.d_s) / jse,
            p.k_eh / jse,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    #[rustfmt::skip]
    let b = SMatrix::<f64, NX, NU>::from_row_slice(&[
        0.0, 0.0,
        1.0 / j, 0.0,
        0.0, 0.0,
        0.0, 0.0,
        0.0, 0.0,
        0.0, p.d_eh / jse,
        0.0, 1.0,
    ]);
    #[rustfmt::skip]
    let c = SMatrix::<f64, NY, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, p.k_s, p.d_s, -p.k_s, -p.d_s, 0.0,
        0.0, 0.0, 0.0, 0.0, p.k_eh, p.d_eh, -p.k_eh,
    ]);
    #[rustfmt::skip]
    let d = SMatrix::<f64, NY, NU>::from_row_slice(&[
        0.0, 0.0,
        0.0, 0.0,
        0.0, -p.d_eh,
    ]);
    Plant::new(a, b, c, d)
}

/// `got` equals `want` entrywise to `rel` times the largest |entry| of `want`.
fn assert_matrix_close<const R: usize, const C: usize>(
    what: &str,
    got: &SMatrix<f64, R, C>,
    want: &SMatrix<f64, R, C>,
    rel: f64,
) {
    let scale = want.abs().max();
    for i in 0..R {
        for j in 0..C {
            let (g, w) = (got[(i, j)], want[(i, j)]);
            assert!(
                (g - w).abs() <= rel * scale,
                "{what}[{i}, {j}]: generated {g} vs Eq. 3 {w} (scale {scale})"
            );
        }
    }
}

fn assert_eq3(p: &Params) {
    let generated = plant::plant(p).unwrap();
    let hand = eq3_by_hand(p);
    assert_matrix_close("A", &generated.a, &hand.a, 1e-12);
    assert_matrix_close("B", &generated.b, &hand.b, 1e-12);
    assert_matrix_close("C", &generated.c, &hand.c, 1e-12);
    assert_matrix_close("D", &generated.d, &hand.d, 1e-12);
}

#[test]
fn generated_plant_is_eq3() {
    assert_eq3(&Params::paper());
    // The paper neglects b_f, d_s and d_eh; with them non-zero every entry of Eq. 3 takes part.
    assert_eq3(&Params {
        b_f: 2e-3,
        d_s: 1.5,
        d_eh: 0.8,
        ..Params::paper()
    });
    // Non-physical parameters are refused, naming the parameter.
    match plant::plant(&Params {
        k_s: -1.0,
        ..Params::paper()
    }) {
        Err(BackSupportError::Parameter { name, value, .. }) => {
            assert_eq!((name, value), ("k_s", -1.0));
        }
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

fn assert_close(got: &[f64], want: &[f64], rel: f64) {
    assert_eq!(got.len(), want.len());
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= rel * w.abs(),
            "entry {i}: {g} vs {w} (got {got:?})"
        );
    }
}

#[test]
fn lqr_gains_match_scipy_and_explain_the_printed_ones() {
    let (_, _, model) = setup();
    let d = lqr::designs(&model).unwrap();
    let single = [
        1.7444642661223100e+00,
        3.4815627264647833e-02,
        1.5351053096559444e+00,
        8.8425572022333913e-05,
        3.4909017709544882e-02,
        1.2893501845364448e-03,
        -7.0710678125041433e+00,
    ];
    let reproducing = [
        9.9962214256357029e-01,
        2.6329936488780580e-02,
        6.4073848585254944e-01,
        5.8212938875162719e-05,
        1.9931786487463059e-02,
        7.9158579766745187e-04,
        -3.1622776603015983e+00,
    ];
    let double = [
        2.0821445876217322e+00,
        3.8057558579070741e-02,
        2.1694368122909964e+00,
        1.0483931120972736e-04,
        4.7667612132025521e-02,
        1.5833450878658204e-03,
        -9.8096319494451354e+00,
        -7.0710678123102056e+01,
    ];
    // scipy's own residual limits its agreement to about 1e-10.
    assert_close(&d.single.k, &single, 1e-8);
    assert_close(&d.single_reproducing.k, &reproducing, 1e-8);
    assert_close(&d.double.k, &double, 1e-8);
    let double_reproducing = [
        1.5437124909872226e+00,
        3.2755474886206483e-02,
        1.4445960729557246e+00,
        8.3196855631300330e-05,
        3.6830873213284335e-02,
        1.2137406253899254e-03,
        -6.6694676005198765e+00,
        -7.0710678120139065e+01,
    ];
    assert_close(&d.double_reproducing.k, &double_reproducing, 1e-8);
    // The outer integral gain is −√(q/r) for any plant: Eq. 14's q_z = 5e13 gives −7.07, not Eq. 17's −3.16.
    assert!((d.single.outer_integral_gain().unwrap() + 50f64.sqrt()).abs() < 1e-9);
    assert!((d.double.outer_integral_gain().unwrap() + 5000f64.sqrt()).abs() < 1e-9);
    // With q_z = 1e13 the design reproduces Eqs. 16–17 to the printed two decimals.
    for (got, paper) in d
        .single_reproducing
        .state_gain()
        .iter()
        .zip(PAPER_STATE_GAIN)
    {
        assert!((got - paper).abs() <= 0.005, "{got} vs {paper}");
    }
    assert!(
        (d.single_reproducing.outer_integral_gain().unwrap() - lqr::PAPER_SINGLE_INTEGRAL_GAIN)
            .abs()
            <= 0.005
    );
    assert!(
        (d.double.outer_integral_gain().unwrap() - lqr::PAPER_DOUBLE_INTEGRAL_GAIN).abs() <= 0.005
    );
    // The printed weights do not: the first state gain is 1.74, not 1.00.
    assert!((d.single.k[0] - PAPER_STATE_GAIN[0]).abs() > 0.7);
}

#[test]
fn model_check_agrees_to_solver_tolerance_and_the_printed_friction_does_not() {
    let check = model_check(&Params::paper()).unwrap();
    // The generated bond-graph model (10 states) against Eq. 1: same equations, same solver (rtol 1e-10),
    // differences far below the paper's 0.09 N m and 0.07 rad/s.
    assert!(
        check.max_torque_difference < 1e-6,
        "{}",
        check.max_torque_difference
    );
    assert!(
        check.max_velocity_difference < 1e-6,
        "{}",
        check.max_velocity_difference
    );
    // b_g/r_g as printed in Eq. 1: the exact (ZOH) scipy response gives these differences.
    let rel_t = (check.max_torque_difference_as_printed - 16.72948654582).abs() / 16.73;
    let rel_v = (check.max_velocity_difference_as_printed - 19.22211513625).abs() / 19.22;
    assert!(rel_t < 1e-6, "{}", check.max_torque_difference_as_printed);
    assert!(rel_v < 1e-6, "{}", check.max_velocity_difference_as_printed);
}

#[test]
fn seven_state_observer_is_refused_naming_the_rigid_rotation() {
    let (p, plant, model) = setup();
    let noise = NoiseModel::three_sigma();
    let cases = observer::seven_state_check(&plant, &noise, 1e-3).unwrap();
    let expected = observer::expected_rigid_direction(&p);
    for case in &cases {
        assert!(!case.detectable, "{}", case.name);
        assert_eq!(case.unobservable.len(), 1, "{}", case.name);
        match &case.lqe {
            Err(
                e @ RiccatiError::NotDetectable {
                    eigenvalue,
                    direction,
                },
            ) => {
                assert!(eigenvalue.norm() < 1e-9, "{eigenvalue}");
                let d = direction.as_ref().unwrap();
                for (i, want) in expected.iter().enumerate() {
                    assert!((d[i] / d[0] - want).norm() < 1e-9, "direction {d}");
                }
                let text = e.to_string();
                assert!(
                    text.contains("not detectable") && text.contains("eigenvalue 0"),
                    "{text}"
                );
            }
            other => panic!("{}: expected NotDetectable, got {other:?}", case.name),
        }
    }
    // The trunk-relative 6-state model is observable and gives a stable filter.
    let obs = observer::design(&model, &noise, 1e-3).unwrap();
    assert!(obs.observable);
    assert!(
        obs.discrete
            .observer_eigenvalues
            .iter()
            .all(|l| l.norm() < 1.0)
    );
    assert!(
        obs.continuous
            .observer_eigenvalues
            .iter()
            .all(|l| l.re < 0.0)
    );
}

#[test]
fn lifting_scenario_peak_torque_and_estimation_errors() {
    let (p, plant, model) = setup();
    let designs = lqr::designs(&model).unwrap();
    let noise = NoiseModel::three_sigma();
    let obs = observer::design(&model, &noise, 1e-3).unwrap();

    // Noise-free, over the first 0.2 s (the peak follows the reference step at 0.1 s): the scipy loop.
    let quiet = NoiseModel {
        motor_torque: 0.0,
        trunk_velocity: 0.0,
        motor_velocity: 0.0,
        sensor_torque: 0.0,
    };
    let cfg = ScenarioConfig {
        duration: 0.2,
        noise: quiet,
        ..ScenarioConfig::paper()
    };
    let run = scenario::run(&p, &plant, &model, &designs.double, &obs, &cfg).unwrap();
    assert!(
        (run.peak_motor_torque - 0.606994512979).abs() < 1e-5,
        "{}",
        run.peak_motor_torque
    );
    assert!((run.peak_time - 0.115).abs() < 1e-9);
    // The filter starts at the true state and sees no noise: it tracks to solver accuracy.
    assert!(run.human_torque_mse < 1e-10, "{}", run.human_torque_mse);
    // With q_z = 1e13 (the weight Eqs. 16–17 imply) the peak stays inside the paper's ±0.56 N m.
    let run = scenario::run(&p, &plant, &model, &designs.double_reproducing, &obs, &cfg).unwrap();
    assert!(
        (run.peak_motor_torque - 0.463182219721).abs() < 1e-5,
        "{}",
        run.peak_motor_torque
    );
    assert!((run.peak_time - 0.118).abs() < 1e-9);

    // The exact zero-order-hold step and a tight ODE solve per sample give the same record (with noise, 1 s).
    let exact = scenario::run(
        &p,
        &plant,
        &model,
        &designs.double,
        &obs,
        &ScenarioConfig::paper(),
    )
    .unwrap();
    let ode_cfg = ScenarioConfig {
        integration: PlantIntegration::Ode(SolverOptions {
            rtol: 1e-11,
            atol: 1e-14,
            ..SolverOptions::default()
        }),
        ..ScenarioConfig::paper()
    };
    let ode = scenario::run(&p, &plant, &model, &designs.double, &obs, &ode_cfg).unwrap();
    assert_eq!(exact.motor_torque.len(), ode.motor_torque.len());
    let worst = exact
        .motor_torque
        .iter()
        .zip(&ode.motor_torque)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0_f64, f64::max);
    assert!(
        worst < 1e-6 * exact.peak_motor_torque,
        "max |Δτ_m| = {worst:e}"
    );

    // The paper's scenario with noise (1 s).
    let run = scenario::run(
        &p,
        &plant,
        &model,
        &designs.double,
        &obs,
        &ScenarioConfig::paper(),
    )
    .unwrap();
    // Noise barely moves the peak; it exceeds the paper's ±0.56 N m by about 8 % (see the example's report).
    assert!(
        run.peak_motor_torque > 0.56 && run.peak_motor_torque < 0.615,
        "{}",
        run.peak_motor_torque
    );
    // Estimation errors below the paper's figures and consistent with the filter's own covariance.
    assert!(run.human_torque_mse < 1e-4);
    let ratio = run.human_torque_mse / obs.predicted_human_torque_variance;
    assert!(
        (0.25..4.0).contains(&ratio),
        "human torque MSE / predicted = {ratio}"
    );
    assert!(run.motor_velocity_mse < 3e-6);
    let ratio = run.motor_velocity_mse_true / obs.predicted_motor_velocity_variance;
    assert!(
        (0.8..1.25).contains(&ratio),
        "motor velocity MSE / predicted = {ratio}"
    );
}

#[test]
fn margins_and_rejection_bandwidth_match_python_control() {
    let (_, _, model) = setup();
    let designs = lqr::designs(&model).unwrap();
    let obs = observer::design(&model, &NoiseModel::three_sigma(), 1e-3).unwrap();
    let r = robustness::analyse(&model, &designs.double, &obs.continuous.l, &obs).unwrap();
    // The observer gain spans 1e-5 … 3e6 and scipy's CARE reaches a relative residual of only ~1e-5 on it, so
    // the python-control figures agree to about 1e-5.
    let m = &r.observer_loop;
    let rel = |got: f64, want: f64| (got - want).abs() / want.abs();
    assert!(rel(m.gain_margin, 1.2021457581) < 1e-4, "{}", m.gain_margin);
    assert!(
        rel(m.phase_margin, 14.3798879873) < 1e-4,
        "{}",
        m.phase_margin
    );
    assert!(rel(m.gain_crossover.unwrap(), 35.4972484667) < 1e-4);
    assert!(
        rel(m.delay_margin, 0.0070703055) < 1e-4,
        "{}",
        m.delay_margin
    );
    // The 1 kHz loop of the scenario's filter is close to the continuous one.
    assert!(rel(r.sampled_loop.phase_margin, m.phase_margin) < 0.05);
    assert!(rel(r.sampled_loop.delay_margin, m.delay_margin) < 0.05);
    // With the full state the LQR keeps its classical margin (PM ≥ 60° for a single-input LQR).
    assert!(r.state_feedback_loop.phase_margin >= 60.0);
    // Double integral action: no DC response to a constant trunk velocity.
    assert!(r.disturbance_dc_gain < 1e-9);
    let bw = r.rejection_bandwidth_hz.unwrap();
    assert!(rel(bw, 5.0349307169) < 1e-6, "{bw}");
}

#[test]
fn recovered_observer_meets_the_margins_and_the_estimation_bounds() {
    // Reference: the script above with the recovery weight q added to the motor-torque intensity,
    //   for q in [0.0, 1e-11, 1e-6]:
    //       L, _, _ = ct.lqe(A1, np.hstack([Bm, Bh]), Cm, np.diag([sw**2 * T + q, sh**2 * T]),
    //                        np.diag([sv**2, st**2]) * T)
    //       (controller and loop as above); print(q, *ct.stability_margins(loop)[:2], wgc, dm)
    // -> 0      1.2021457581  14.3798879873  35.4972484667  0.0070703055
    //    1e-11  1.2e15 (no crossing)  52.0179234859  49.4007988351  0.0183779221
    //    1e-6   0.2969146520  60.3431450603  110.099330902  0.0095657853   (the LQR's own: 60.34°)
    let (p, plant, model) = setup();
    let designs = lqr::designs(&model).unwrap();
    let cfg = ScenarioConfig::paper();
    let rec = recovery::recover(&p, &plant, &model, &designs.double, &cfg).unwrap();
    let rel = |got: f64, want: f64| (got - want).abs() / want.abs();
    let at = |q: f64| {
        rec.sweep
            .iter()
            .find(|pt| rel(pt.q, q) < 1e-9 || (q == 0.0 && pt.q == 0.0))
            .unwrap()
    };
    // q = 0 is the plain design of Eq. 9 (the margins test above).
    let plain = &at(0.0).margins;
    assert!(rel(plain.gain_margin, 1.2021457581) < 1e-4, "{plain:?}");
    assert!(rel(plain.phase_margin, 14.3798879873) < 1e-4, "{plain:?}");

    // The chosen weight: the smallest of the sweep meeting 6 dB / 45° in both loops.
    assert!(rel(rec.q, 1e-11) < 1e-9, "q = {}", rec.q);
    let m = &rec.robustness.observer_loop;
    assert!(rel(m.phase_margin, 52.0179234859) < 1e-4, "{m:?}");
    assert!(
        rel(m.gain_crossover.unwrap(), 49.4007988351) < 1e-4,
        "{m:?}"
    );
    assert!(rel(m.delay_margin, 0.0183779221) < 1e-4, "{m:?}");
    // No phase crossover at all: the gain can grow or shrink without limit (python-control's 1.2e15 is a
    // numerically infinite gain margin).
    assert_eq!(m.gain_increase_margin, None);
    assert_eq!(m.gain_reduction_margin, None);
    assert!(recovery::meets_margins(m));
    let ms = &rec.robustness.sampled_loop;
    assert!(recovery::meets_margins(ms), "{ms:?}");
    assert!(ms.phase_margin >= 45.0 && ms.delay_margin > 0.015, "{ms:?}");
    // The grid point below the chosen one does not meet them: the choice is the smallest.
    let below = rec.sweep.iter().rev().find(|pt| pt.q < rec.q).unwrap();
    assert!(
        !recovery::meets_margins(&below.margins),
        "{:?}",
        below.margins
    );

    // The recovered design of the example is the runtime's LTR gain: observer::design with the recovery noise.
    let swept = &at(rec.q).observer.l;
    let designed = &rec.observer.continuous.l;
    assert!((swept - designed).norm() <= 1e-8 * designed.norm());

    // Estimation errors of the lifting scenario within the paper's figures (Figs. 17, 19).
    let run = &rec.scenario;
    assert!(
        run.human_torque_mse <= recovery::PAPER_HUMAN_TORQUE_MSE,
        "{}",
        run.human_torque_mse
    );
    assert!(
        run.motor_velocity_mse <= recovery::PAPER_MOTOR_VELOCITY_MSE,
        "{}",
        run.motor_velocity_mse
    );

    // Recovery: as q grows the loop tends to the LQR's (python-control at q = 1e-6; LQR alone 60.34°).
    let high = &at(1e-6).margins;
    assert!(rel(high.phase_margin, 60.3431450603) < 1e-4, "{high:?}");
    assert!(
        rel(high.gain_reduction_margin.unwrap(), 0.2969146520) < 1e-4,
        "{high:?}"
    );
    let lqr_loop = &rec.robustness.state_feedback_loop;
    let last = &rec.sweep[rec.sweep.len() - 1].margins;
    assert!(
        (last.phase_margin - lqr_loop.phase_margin).abs() < 1e-3,
        "{last:?}"
    );
    assert!((last.stability_margin - lqr_loop.stability_margin).abs() < 1e-6);
}
