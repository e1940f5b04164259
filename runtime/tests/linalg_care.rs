//! Continuous algebraic Riccati equation and LQR against hand-derived and scipy references.
#![allow(clippy::excessive_precision)] // reference values are pasted from numpy at full precision

use bgc_runtime::design::{dlqr, lqr};
use bgc_runtime::linalg::{MatrixError, RiccatiError, c2d_zoh, care, care_with_cross};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

fn max_rel_diff(x: &DMatrix<f64>, reference: &DMatrix<f64>) -> f64 {
    assert_eq!(x.shape(), reference.shape());
    (x - reference).amax() / reference.amax()
}

/// Double integrator, Q = I, R = 1: by hand, X = [[√3, 1], [1, √3]] and K = [1, √3]
/// (from the (2,2) entry 2x₁₂ − x₂₂² + 1 = 0 … x₁₂ = 1, x₂₂ = √3, x₁₁ = x₁₂ x₂₂).
#[test]
fn double_integrator_matches_hand_solution() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let sol = care(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)).unwrap();
    let s3 = 3f64.sqrt();
    let x_ref = DMatrix::from_row_slice(2, 2, &[s3, 1.0, 1.0, s3]);
    let k_ref = DMatrix::from_row_slice(1, 2, &[1.0, s3]);
    assert!(max_rel_diff(&sol.x, &x_ref) < 1e-12, "X = {}", sol.x);
    assert!(max_rel_diff(&sol.k, &k_ref) < 1e-12, "K = {}", sol.k);
    assert!(sol.relative_residual < 1e-14);
    // Closed-loop poles: s² + √3 s + 1 = 0.
    for l in &sol.closed_loop_eigenvalues {
        assert!((l.re + s3 / 2.0).abs() < 1e-12 && (l.im.abs() - 0.5).abs() < 1e-12);
    }
}

fn laub4() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            -0.1, 0.02, 0.0, 0.3, 0.5, -0.4, 0.1, 0.0, 0.0, 0.2, 0.9, -0.5, 1.0, 0.0, 0.3, -1.2,
        ],
    );
    let b = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 0.0, 0.5, 0.2, 0.0, 0.0, 1.0]);
    let q = DMatrix::from_diagonal(&nalgebra::dvector![1.0, 2.0, 3.0, 4.0]);
    let r = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.1, 2.0]);
    (a, b, q, r)
}

/// A 4-state, 2-input case with an unstable open loop. Reference:
/// ```python
/// import numpy as np, scipy.linalg as sl
/// a = np.array([[-0.1, 0.02, 0.0, 0.3], [0.5, -0.4, 0.1, 0.0], [0.0, 0.2, 0.9, -0.5], [1.0, 0.0, 0.3, -1.2]])
/// b = np.array([[1.0, 0.0], [0.0, 0.5], [0.2, 0.0], [0.0, 1.0]])
/// q = np.diag([1.0, 2.0, 3.0, 4.0]); r = np.array([[1.0, 0.1], [0.1, 2.0]])
/// x = sl.solve_continuous_are(a, b, q, r); k = np.linalg.solve(r, b.T @ x)
/// n = np.array([[0.1, 0.0], [0.0, 0.2], [0.1, 0.1], [0.0, 0.0]])
/// xn = sl.solve_continuous_are(a, b, q, r, s=n); kn = np.linalg.solve(r, b.T @ xn + n.T)
/// ```
#[test]
fn four_state_two_input_matches_scipy() {
    let (a, b, q, r) = laub4();
    let sol = care(&a, &b, &q, &r).unwrap();
    let k_ref = DMatrix::from_row_slice(
        2,
        4,
        &[
            0.3204320069184663,
            1.4722692300781257,
            6.856962195121628,
            -1.0681831617308595,
            1.948621498169514,
            -1.6089349781530133,
            -10.436895238579757,
            3.041626411008514,
        ],
    );
    let x33 = 145.77952159675553;
    assert!(max_rel_diff(&sol.k, &k_ref) < 1e-10, "K = {}", sol.k);
    assert!((sol.x[(2, 2)] - x33).abs() < 1e-10 * x33);
    assert!((sol.x[(0, 3)] - 6.001464880043331).abs() < 1e-10 * x33);
    assert!(sol.relative_residual < 1e-13);
    assert!(sol.closed_loop_eigenvalues.iter().all(|l| l.re < 0.0));

    let n = DMatrix::from_row_slice(4, 2, &[0.1, 0.0, 0.0, 0.2, 0.1, 0.1, 0.0, 0.0]);
    let sol = care_with_cross(&a, &b, &q, &r, Some(&n)).unwrap();
    let kn_ref = DMatrix::from_row_slice(
        2,
        4,
        &[
            0.2574279313049201,
            1.5143753158301334,
            7.134981308511309,
            -1.1440361948185525,
            1.9604345227509172,
            -1.6524446206653323,
            -10.575597255296401,
            3.085433306207436,
        ],
    );
    assert!(max_rel_diff(&sol.k, &kn_ref) < 1e-10, "K = {}", sol.k);
    assert!((sol.x[(2, 2)] - 150.97699591683286).abs() < 1e-10 * 150.0);
}

/// The back-support exoskeleton with double integral action (Designs 2020, 4, 53, Eqs. 3, 12, 15), the
/// ill-scaled case: Q up to 5·10¹⁵, R = 10¹², stiffnesses over inertias of 3·10⁸. Reference:
/// ```python
/// import numpy as np, scipy.linalg as sl
/// Jm, Jg, rg, kg = 3.06e-4, 0.40e-4, 160.0, 2.64e4
/// Jsi, Jse, ks = 1e-4, 1.19e-3, 3.38e4
/// bg, dg, keh = 0.65, 6.0, 1125.0
/// bf = ds = deh = 0.0
/// J = Jm + Jg
/// A1 = np.array([
///  [0, 1, 0, 0, 0, 0],
///  [-kg/(J*rg**2), -(bf*rg**2+bg+dg)/(J*rg**2), kg/(J*rg), dg/(J*rg), 0, 0],
///  [0, 0, 0, 1, 0, 0],
///  [kg/(Jsi*rg), dg/(Jsi*rg), -(kg+ks)/Jsi, -(dg+ds)/Jsi, ks/Jsi, ds/Jsi],
///  [0, 0, 0, 0, 0, 1],
///  [0, 0, ks/Jse, ds/Jse, -(keh+ks)/Jse, -(deh+ds)/Jse]])
/// Bm = np.array([[0, 1/J, 0, 0, 0, 0]]).T
/// Cb = np.array([[0, 0, 0, 0, keh, deh]])
/// A = np.zeros((8, 8)); A[:6, :6] = A1; A[6, :6] = -Cb; A[7, 6] = 1.0
/// B = np.vstack([Bm, np.zeros((2, 1))])
/// Q = np.diag([1e5, 1e5, 1e7, 1e7, 1e7, 1e7, 5e13, 5e15]); R = np.array([[1e12]])
/// X = sl.solve_continuous_are(A, B, Q, R); K = np.linalg.solve(R, B.T @ X)
/// ```
#[test]
fn back_support_double_integral_matches_scipy() {
    let (a, b, q, r) = back_support_8();
    let sol = lqr(&a, &b, &q, &r).unwrap();
    let k_ref = [
        2.0821445876217322e+00,
        3.8057558579070741e-02,
        2.1694368122909964e+00,
        1.0483931120972736e-04,
        4.7667612132025521e-02,
        1.5833450878658204e-03,
        -9.8096319494451354e+00,
        -7.0710678123102056e+01,
    ];
    for (j, &kr) in k_ref.iter().enumerate() {
        let rel = (sol.k[(0, j)] - kr).abs() / kr.abs();
        assert!(
            rel < 1e-8,
            "K[{j}] = {} vs scipy {kr} (rel {rel:e})",
            sol.k[(0, j)]
        );
    }
    assert!(
        sol.relative_residual < 1e-10,
        "residual {:e}",
        sol.relative_residual
    );
    assert!(sol.closed_loop_eigenvalues.iter().all(|l| l.re < 0.0));
}

/// The same design sampled with a zero-order hold at 1 kHz and solved as a DARE (doubling + Hewer).
///
/// scipy's solution is itself only accurate to about 1.2·10⁻⁸ here, so the reference is a 50-digit one: the
/// exact ZOH matrices by `mpmath.expm` and Hewer's iteration in 50-digit arithmetic (converging to 10⁻⁵⁰ in
/// four steps from scipy's X), the scipy value being checked to agree to 2·10⁻⁸:
/// ```python
/// import mpmath as mp, scipy.signal as ss   # continuing the snippet above
/// mp.mp.dps = 50
/// M = mp.zeros(9, 9); M[:8, :8] = A * 1e-3; M[:8, 8] = B * 1e-3        # entrywise, via mp.mpf
/// E = mp.expm(M); Ad, Bd = E[:8, :8], E[:8, 8]
/// Ad_s, Bd_s, _, _, _ = ss.cont2discrete((A, B, np.eye(8), np.zeros((8, 1))), 1e-3, method='zoh')
/// X = mp.matrix(sl.solve_discrete_are(Ad_s, Bd_s, Q, R).tolist())
/// for it in range(8):                                                  # Hewer: Newton on the DARE
///     K = (Bd.T*X*Ad) / (R + (Bd.T*X*Bd)[0, 0]); Acl = Ad - Bd*K
///     X = solution of Acl.T X Acl - X + Q + K.T R K = 0 (Kronecker form, mp.lu_solve)
/// ```
#[test]
fn back_support_sampled_dlqr_matches_high_precision_reference() {
    let (a, b, q, r) = back_support_8();
    let sys = StateSpace::new(a, b, DMatrix::identity(8, 8), DMatrix::zeros(8, 1)).unwrap();
    let d = c2d_zoh(&sys, 1e-3).unwrap();
    let sol = dlqr(d.a(), d.b(), &q, &r).unwrap();
    let k_hp = [
        1.9993771442634825673,
        0.037033961782676446712,
        2.0571661539058837704,
        0.00010112003172118189434,
        0.046085098867278136699,
        0.0015217059944375101475,
        -9.3186926341463875009,
        -66.926907612615330594,
    ];
    let k_scipy = [
        1.9993771673644434e+00,
        3.7033962217506211e-02,
        2.0571661772737011e+00,
        1.0112003289539238e-04,
        4.6085099387341948e-02,
        1.5217060120257008e-03,
        -9.3186927402590012e+00,
        -6.6926908391358253e+01,
    ];
    for j in 0..8 {
        let k = sol.k[(0, j)];
        let rel_hp = (k - k_hp[j]).abs() / k_hp[j].abs();
        let rel_scipy = (k - k_scipy[j]).abs() / k_scipy[j].abs();
        assert!(
            rel_hp < 1e-11,
            "K[{j}] = {k} vs {} (rel {rel_hp:e})",
            k_hp[j]
        );
        assert!(
            rel_scipy < 2e-8,
            "K[{j}] = {k} vs scipy {} (rel {rel_scipy:e})",
            k_scipy[j]
        );
    }
    assert!(
        sol.relative_residual < 1e-10,
        "residual {:e}",
        sol.relative_residual
    );
    let rho = sol
        .closed_loop_eigenvalues
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max);
    assert!((rho - 0.990048515511187).abs() < 1e-9);
}

/// The ZOH of the stiff 8-state model at 1 kHz (‖AΔt‖₁ ≈ 3·10⁵ in physical units) against a 50-digit
/// `mpmath.expm` of `[A B; 0 0]·Δt` (continuing the snippet above):
/// ```python
/// import mpmath as mp; mp.mp.dps = 50
/// M = mp.zeros(9, 9)
/// for i in range(8):
///     for j in range(8): M[i, j] = mp.mpf(A[i, j]) * mp.mpf('1e-3')
///     M[i, 8] = mp.mpf(B[i, 0]) * mp.mpf('1e-3')
/// E = mp.expm(M)
/// ```
/// Without balancing, Higham's scaling and squaring needs 16 squarings here and the gains of the sampled
/// design drifted by 10⁻⁹; balanced, the entries agree to about 10⁻¹³.
#[test]
fn back_support_zoh_matches_50_digit_expm() {
    let (a, b, _, _) = back_support_8();
    let sys = StateSpace::new(a, b, DMatrix::identity(8, 8), DMatrix::zeros(8, 1)).unwrap();
    let d = c2d_zoh(&sys, 1e-3).unwrap();
    let reference = [
        ((0, 0), 0.99977791821863993116),
        ((1, 2), 22.798036854267179879),
        ((3, 2), -855.23063848567437954),
        ((3, 4), 747.63088570760913621),
        ((5, 4), 1797.6921218547602876),
        ((7, 2), -0.00018725228638582357944),
    ];
    for ((i, j), v) in reference {
        let rel = (d.a()[(i, j)] - v).abs() / v.abs();
        assert!(
            rel < 1e-12,
            "Ad[{i},{j}] = {} vs {v} (rel {rel:e})",
            d.a()[(i, j)]
        );
    }
    for (i, v) in [(1, 2.8896063552327976485), (7, -3.541103242284202674e-10)] {
        let rel = (d.b()[(i, 0)] - v).abs() / v.abs();
        assert!(
            rel < 1e-12,
            "Bd[{i}] = {} vs {v} (rel {rel:e})",
            d.b()[(i, 0)]
        );
    }
}

pub fn back_support_8() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (jm, jg, rg, kg) = (3.06e-4, 0.40e-4, 160.0, 2.64e4);
    let (jsi, jse, ks) = (1e-4, 1.19e-3, 3.38e4);
    let (bg, dg, keh) = (0.65, 6.0, 1125.0);
    let (bf, ds, deh) = (0.0, 0.0, 0.0);
    let j = jm + jg;
    let mut a = DMatrix::<f64>::zeros(8, 8);
    let a1 = [
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [
            -kg / (j * rg * rg),
            -(bf * rg * rg + bg + dg) / (j * rg * rg),
            kg / (j * rg),
            dg / (j * rg),
            0.0,
            0.0,
        ],
        [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        [
            kg / (jsi * rg),
            dg / (jsi * rg),
            -(kg + ks) / jsi,
            -(dg + ds) / jsi,
            ks / jsi,
            ds / jsi,
        ],
        [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [
            0.0,
            0.0,
            ks / jse,
            ds / jse,
            -(keh + ks) / jse,
            -(deh + ds) / jse,
        ],
    ];
    for (i, row) in a1.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            a[(i, c)] = v;
        }
    }
    a[(6, 4)] = -keh;
    a[(6, 5)] = -deh;
    a[(7, 6)] = 1.0;
    let mut b = DMatrix::<f64>::zeros(8, 1);
    b[(1, 0)] = 1.0 / j;
    let q = DMatrix::from_diagonal(&nalgebra::dvector![
        1e5, 1e5, 1e7, 1e7, 1e7, 1e7, 5e13, 5e15
    ]);
    let r = DMatrix::from_element(1, 1, 1e12);
    (a, b, q, r)
}

#[test]
fn bad_inputs_are_refused() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let q = DMatrix::<f64>::identity(2, 2);
    let r = DMatrix::<f64>::identity(1, 1);
    let mut a_nan = a.clone();
    a_nan[(1, 0)] = f64::NAN;
    assert!(matches!(
        care(&a_nan, &b, &q, &r),
        Err(RiccatiError::Input(MatrixError::NonFinite {
            name: "A",
            row: 1,
            col: 0,
            ..
        }))
    ));
    let a_rect = DMatrix::<f64>::zeros(2, 3);
    assert!(matches!(
        care(&a_rect, &b, &q, &r),
        Err(RiccatiError::Input(MatrixError::NotSquare {
            name: "A",
            rows: 2,
            cols: 3
        }))
    ));
    let r_neg = DMatrix::from_element(1, 1, -1.0);
    assert!(matches!(
        care(&a, &b, &q, &r_neg),
        Err(RiccatiError::Input(MatrixError::NotPositiveDefinite {
            name: "R",
            ..
        }))
    ));
    let q_asym = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]);
    assert!(matches!(
        care(&a, &b, &q_asym, &r),
        Err(RiccatiError::Input(MatrixError::NotSymmetric {
            name: "Q",
            row: 0,
            col: 1,
            ..
        }))
    ));
    let q_indef = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
    assert!(matches!(
        care(&a, &b, &q_indef, &r),
        Err(RiccatiError::Input(MatrixError::NotPositiveSemidefinite {
            name: "Q",
            ..
        }))
    ));
    let b_wrong = DMatrix::<f64>::zeros(3, 1);
    assert!(matches!(
        care(&a, &b_wrong, &q, &r),
        Err(RiccatiError::Input(MatrixError::Shape {
            name: "B",
            rows: 3,
            ..
        }))
    ));
}

/// ẋ₁ = x₁ (unstable, no input), ẋ₂ = u: the mode λ = 1 with direction e₁ cannot be stabilised.
#[test]
fn unstabilizable_mode_is_named() {
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let err = care(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)).unwrap_err();
    match err {
        RiccatiError::NotStabilizable {
            eigenvalue,
            direction,
        } => {
            assert!((eigenvalue.re - 1.0).abs() < 1e-12 && eigenvalue.im.abs() < 1e-12);
            let d = direction.unwrap();
            assert!((d[0].norm() - 1.0).abs() < 1e-12 && d[1].norm() < 1e-12);
        }
        other => panic!("expected NotStabilizable, got {other:?}"),
    }
}

/// Double integrator weighted only on velocity: the position mode λ = 0 (direction e₁) is invisible to Q.
#[test]
fn undetectable_mode_is_named() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let q = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]);
    let err = care(&a, &b, &q, &DMatrix::identity(1, 1)).unwrap_err();
    match err {
        RiccatiError::NotDetectable {
            eigenvalue,
            direction,
        } => {
            assert!(eigenvalue.norm() < 1e-9);
            let d = direction.unwrap();
            assert!((d[0].norm() - 1.0).abs() < 1e-9 && d[1].norm() < 1e-9);
        }
        other => panic!("expected NotDetectable, got {other:?}"),
    }
}

/// A stiff system whose slow mode (−0.01) is stable but uncontrollable next to a fast one (−10⁸): it must be
/// accepted (stabilisable), and X follows by hand: x₁₁ = q₁/(2·0.01) = 50 (a Lyapunov equation, the input
/// cannot act on it), x₂₂ the positive root of −2·10⁸ x − x² + 1 = 0, i.e. 1/(10⁸ + √(10¹⁶ + 1)).
#[test]
fn stiff_stable_uncontrollable_mode_is_accepted() {
    let a = DMatrix::from_row_slice(2, 2, &[-0.01, 0.0, 0.0, -1e8]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let sol = care(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)).unwrap();
    let x22 = 1.0 / (1e8 + (1e16f64 + 1.0).sqrt());
    assert!((sol.x[(0, 0)] - 50.0).abs() < 1e-12 * 50.0);
    assert!((sol.x[(1, 1)] - x22).abs() < 1e-12 * x22);
    assert!(sol.x[(0, 1)].abs() < 1e-15);
    assert!((sol.k[(0, 1)] - x22).abs() < 1e-12 * x22);
}

mod random {
    use super::*;
    use proptest::prelude::*;

    fn residual_of(
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        q: &DMatrix<f64>,
        r: &DMatrix<f64>,
        x: &DMatrix<f64>,
    ) -> f64 {
        let r_inv = r.clone().try_inverse().unwrap();
        let xbrbx = x * b * &r_inv * b.transpose() * x;
        let res = a.transpose() * x + x * a - &xbrbx + q;
        res.norm() / (2.0 * (x * a).norm() + xbrbx.norm() + q.norm())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// For generic (almost surely controllable) 4-state, 2-input systems, the returned X satisfies the CARE
        /// (residual recomputed here), is symmetric positive semidefinite, and A − BK is Hurwitz.
        #[test]
        fn generic_systems_satisfy_the_equation(
            a_entries in prop::collection::vec(-2.0f64..2.0, 16),
            b_entries in prop::collection::vec(-1.0f64..1.0, 8),
            m_entries in prop::collection::vec(-1.0f64..1.0, 16),
            r_scale in 0.01f64..100.0,
        ) {
            let a = DMatrix::from_row_slice(4, 4, &a_entries);
            let b = DMatrix::from_row_slice(4, 2, &b_entries);
            let m = DMatrix::from_row_slice(4, 4, &m_entries);
            let q = m.transpose() * &m + DMatrix::identity(4, 4) * 0.1;
            let r = DMatrix::from_row_slice(2, 2, &[1.0, 0.3, 0.3, 2.0]) * r_scale;
            let sol = care(&a, &b, &q, &r).unwrap();
            // The refinement stops when a Newton step no longer lowers the residual (rounding): for these
            // systems between about 1e-16 and a few 1e-12 (3.8e-12 for the case saved in
            // linalg_care.proptest-regressions, with ‖X‖ = 3.1e3 and R = 0.01 [1 0.3; 0.3 2]); the solver
            // refuses above 1e-8.
            prop_assert!(residual_of(&a, &b, &q, &r, &sol.x) < 1e-10);
            prop_assert!((&sol.x - sol.x.transpose()).amax() <= 1e-14 * sol.x.amax());
            let min_eig = sol.x.clone().symmetric_eigen().eigenvalues.min();
            prop_assert!(min_eig > -1e-12 * sol.x.amax());
            let closed = &a - &b * &sol.k;
            prop_assert!(closed.complex_eigenvalues().iter().all(|l| l.re < 0.0));
        }
    }
}

/// Degenerate weights: with Q = 0 and a stable A the optimal control is u = 0 (X = 0, K = 0); with Q = 0 and an
/// unstable scalar A = a > 0, B = 1, R = 1 the stabilising solution is the minimum-energy one, but (Q, A) is not
/// detectable, which these solvers refuse by contract.
#[test]
fn zero_state_weight() {
    let a = DMatrix::from_row_slice(2, 2, &[-1.0, 0.5, 0.0, -2.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let sol = care(&a, &b, &DMatrix::zeros(2, 2), &DMatrix::identity(1, 1)).unwrap();
    assert_eq!(sol.x.amax(), 0.0);
    assert_eq!(sol.k.amax(), 0.0);
    let err = care(
        &DMatrix::from_element(1, 1, 2.0),
        &DMatrix::from_element(1, 1, 1.0),
        &DMatrix::zeros(1, 1),
        &DMatrix::identity(1, 1),
    )
    .unwrap_err();
    assert!(
        matches!(err, RiccatiError::NotDetectable { eigenvalue, .. } if (eigenvalue.re - 2.0).abs() < 1e-12)
    );
}

/// Scaling `A`, `B`, `Q` and `R` by a common `s` multiplies every term of the CARE by `s` (with `X` and
/// `K = R⁻¹BᵀX` unchanged) and the closed-loop eigenvalues by `s`: a change of the unit of time. Before, a scale
/// of 1e-20 was refused as `ClosedLoopUnstable` (an absolute margin of 1e-12 on `Re λ`), and 1e-200 gave
/// eigenvalues that underflowed to zero.
#[test]
fn a_care_is_invariant_under_a_common_scaling() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let (q, r) = (DMatrix::identity(2, 2), DMatrix::identity(1, 1));
    let unscaled = care(&a, &b, &q, &r).unwrap();
    for s in [1e-200, 1e-150, 1e-20, 1e-3, 1e3, 1e100, 1e150] {
        let scaled = care(&(&a * s), &(&b * s), &(&q * s), &(&r * s))
            .unwrap_or_else(|e| panic!("scale {s:e}: {e}"));
        assert!(
            (&scaled.k - &unscaled.k).amax() <= 1e-12 * unscaled.k.amax(),
            "scale {s:e}: K {} against {}",
            scaled.k,
            unscaled.k
        );
        for (l, l1) in scaled
            .closed_loop_eigenvalues
            .iter()
            .zip(&unscaled.closed_loop_eigenvalues)
        {
            assert!(
                (l / s - l1).norm() <= 1e-12 * l1.norm(),
                "scale {s:e}: {l} against {l1}"
            );
        }
    }
}

/// `ẋ = s·[1 0.1; 0 1] x + s·[0; 0.1] u`, `Q = s·I`, `R = s`: `s` is a change of the unit of time (and of the
/// cost), which leaves `X` and `K` unchanged, so every `s` that f64 holds gives scipy's gain at `s = 1`:
///
/// ```python
/// A = np.array([[1, .1], [0, 1]]); B = np.array([[0], [.1]])
/// X = scipy.linalg.solve_continuous_are(A, B, np.eye(2), np.eye(1)); K = B.T @ X   # scipy 1.17.1
/// ```
#[test]
fn a_change_of_the_unit_of_time_keeps_the_gain() {
    let k_ref = DMatrix::from_row_slice(1, 2, &[401.0049688133984, 40.05012375393605]);
    for e in [-300, -200, -150, -50, 0, 50, 150, 200, 300] {
        let s = 10f64.powi(e);
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]) * s;
        let b = DMatrix::from_row_slice(2, 1, &[0.0, 0.1]) * s;
        let q = DMatrix::identity(2, 2) * s;
        let r = DMatrix::identity(1, 1) * s;
        let sol = care(&a, &b, &q, &r).unwrap_or_else(|e| panic!("s = {s:e}: {e}"));
        assert!(
            max_rel_diff(&sol.k, &k_ref) < 1e-10,
            "s = {s:e}: K = {}",
            sol.k
        );
        assert!(sol.relative_residual < 1e-12, "s = {s:e}");
    }
}

/// Control far cheaper than the plant's rates: with `B` in units 1e10 times smaller, the fast closed-loop pole
/// (about −1e10) and the slow ones (about −1) are 10 orders apart, the Hamiltonian's slow eigenvalues sit at its
/// imaginary axis to working precision and the sign function fails (scipy 1.17.1 returns a gain with a relative
/// residual of 2.4e-4 here). That is said as an ill-conditioned problem, not as a residual of `inf` after 0
/// iterations. At 1e3 the gain is scipy's:
///
/// ```python
/// A = np.array([[1, .1, 0], [0, 1, .2], [-.3, 0, .5]]); B = np.array([[0], [.1], [1]]) * 1e3
/// X = scipy.linalg.solve_continuous_are(A, B, np.eye(3), np.eye(1)); K = B.T @ X
/// ```
#[test]
fn control_far_cheaper_than_the_plant_is_named_ill_conditioned() {
    let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.1, 0.0, 0.0, 1.0, 0.2, -0.3, 0.0, 0.5]);
    let b = DMatrix::from_row_slice(3, 1, &[0.0, 0.1, 1.0]);
    let (q, r) = (DMatrix::identity(3, 3), DMatrix::identity(1, 1));
    let k_ref = DMatrix::from_row_slice(
        1,
        3,
        &[161.3484817781298, 9.683084793485538, 0.041185456229025696],
    );
    let sol = care(&a, &(&b * 1e3), &q, &r).expect("solvable at 1e3");
    assert!(max_rel_diff(&sol.k, &k_ref) < 1e-8, "K = {}", sol.k);
    match care(&a, &(&b * 1e10), &q, &r) {
        Err(err @ RiccatiError::IllConditioned { .. }) => {
            let text = err.to_string();
            assert!(text.contains("rescale") && text.contains("PBH"), "{text}");
        }
        other => panic!("expected IllConditioned, got {other:?}"),
    }
}

/// A state weight far below what stabilising the plant costs: `ẋ = [0 1; 4 0.4] x + [0; 1] u` has the poles
/// 0.2 ± √4.04 (2.20998 unstable, −1.80998 stable). As `Q/R → 0` the gain tends to the minimum-energy one, which
/// keeps the stable pole and mirrors the unstable one: `A − BK` has the characteristic polynomial
/// `(s + 1.80998)(s + 2.20998) = s² + 2√4.04 s + 4`, so `K = [8, 0.4 + 2√4.04]` by hand (scipy 1.17.1 gives the
/// same at `Q = 1e-40 I`). Before, every `Q/R` below about 1e-35 was refused ("the solver did not converge"): the
/// weight scale balanced `Q` against `G` and left the Hamiltonian's coupling blocks negligible.
#[test]
fn a_state_weight_far_below_the_cost_of_stabilising_gives_the_minimum_energy_gain() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 4.0, 0.4]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let k_ref = DMatrix::from_row_slice(1, 2, &[8.0, 0.4 + 2.0 * 4.04f64.sqrt()]);
    for ratio in [1e-20, 1e-40, 1e-100, 1e-200, 1e-300] {
        let weights = [
            (DMatrix::identity(2, 2) * ratio, DMatrix::identity(1, 1)),
            (DMatrix::identity(2, 2), DMatrix::identity(1, 1) / ratio),
        ];
        for (q, r) in &weights {
            let sol = care(&a, &b, q, r).unwrap_or_else(|e| panic!("Q/R = {ratio:e}: {e}"));
            assert!(
                max_rel_diff(&sol.k, &k_ref) < 1e-10,
                "Q/R = {ratio:e}: K = {}",
                sol.k
            );
        }
    }
}
