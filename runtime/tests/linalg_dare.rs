//! Discrete algebraic Riccati equation and dlqr against scipy and python-control.
#![allow(clippy::excessive_precision)] // reference values are pasted from numpy at full precision

use bgc_runtime::design::{dlqr, dlqr_with_cross};
use bgc_runtime::linalg::{RiccatiError, dare};
use nalgebra::DMatrix;

fn max_abs_diff(x: &DMatrix<f64>, reference: &[f64]) -> f64 {
    x.transpose()
        .iter()
        .zip(reference)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// Double integrator sampled at 0.1 s, Q = I, R = 1:
/// ```python
/// import numpy as np, scipy.linalg as sl, control as ct
/// dt = 0.1; A = np.array([[1, dt], [0, 1]]); B = np.array([[dt**2/2], [dt]])
/// sl.solve_discrete_are(A, B, np.eye(2), np.eye(1)); K, S, E = ct.dlqr(A, B, np.eye(2), np.eye(1))
/// ```
#[test]
fn sampled_double_integrator_matches_scipy() {
    let dt = 0.1;
    let a = DMatrix::from_row_slice(2, 2, &[1.0, dt, 0.0, 1.0]);
    let b = DMatrix::from_row_slice(2, 1, &[dt * dt / 2.0, dt]);
    let sol = dlqr(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)).unwrap();
    let x_ref = [
        17.834931322189007,
        10.01249219725043,
        10.01249219725043,
        17.856586460328874,
    ];
    assert!(max_abs_diff(&sol.x, &x_ref) < 1e-10 * 17.9, "X = {}", sol.x);
    assert!(max_abs_diff(&sol.k, &[0.9170745631140975, 1.635596185046635]) < 1e-10);
    for l in &sol.closed_loop_eigenvalues {
        assert!((l.re - 0.9159275043398831).abs() < 1e-10);
        assert!((l.im.abs() - 0.04585369237717499).abs() < 1e-10);
    }
    assert!(sol.relative_residual < 1e-13);
}

/// Unstable 3-state, 2-input case, with and without cross weight:
/// ```python
/// A3 = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.3], [0.1, 0.0, 0.5]])
/// B3 = np.array([[1.0, 0.0], [0.0, 1.0], [0.5, 0.5]])
/// Q3 = np.diag([2.0, 1.0, 0.5]); R3 = np.array([[1.0, 0.2], [0.2, 0.5]])
/// N3 = np.array([[0.1, 0.0], [0.0, 0.1], [0.05, 0.0]])
/// X = sl.solve_discrete_are(A3, B3, Q3, R3); np.linalg.solve(R3 + B3.T@X@B3, B3.T@X@A3)
/// X = sl.solve_discrete_are(A3, B3, Q3, R3, s=N3); np.linalg.solve(R3 + B3.T@X@B3, B3.T@X@A3 + N3.T)
/// ```
#[test]
fn three_state_two_input_with_cross_matches_scipy() {
    let a = DMatrix::from_row_slice(3, 3, &[1.1, 0.2, 0.0, 0.0, 0.9, 0.3, 0.1, 0.0, 0.5]);
    let b = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 0.5, 0.5]);
    let q = DMatrix::from_diagonal(&nalgebra::dvector![2.0, 1.0, 0.5]);
    let r = DMatrix::from_row_slice(2, 2, &[1.0, 0.2, 0.2, 0.5]);
    let n = DMatrix::from_row_slice(3, 2, &[0.1, 0.0, 0.0, 0.1, 0.05, 0.0]);
    let sol = dare(&a, &b, &q, &r).unwrap();
    let x_ref = [
        2.9541952446210944,
        0.36593839144180185,
        -0.02251124032802617,
        0.36593839144180185,
        1.4684524536950487,
        0.02124737971295851,
        -0.02251124032802617,
        0.02124737971295851,
        0.6196617741023326,
    ];
    let k_ref = [
        0.8124951234825087,
        0.11876718800973135,
        0.01353052638783686,
        -0.07549974674755952,
        0.6138939544322001,
        0.2795452412418803,
    ];
    assert!(max_abs_diff(&sol.x, &x_ref) < 1e-10);
    assert!(max_abs_diff(&sol.k, &k_ref) < 1e-10);
    let sol = dlqr_with_cross(&a, &b, &q, &r, &n).unwrap();
    let kn_ref = [
        0.8286059025509868,
        0.11118634661317466,
        0.02468050217788858,
        -0.08472644100853839,
        0.6522915094496748,
        0.2673168145472739,
    ];
    assert!(max_abs_diff(&sol.k, &kn_ref) < 1e-10, "K = {}", sol.k);
    assert!((sol.x[(0, 0)] - 2.7847470843148376).abs() < 1e-10);
}

/// A singular (nilpotent) A: x₁⁺ = x₂, x₂⁺ = u. By hand with Q = I, R = 1: X = diag(1, 2), K = 0
/// (scipy gives the same). Doubling needs no inverse of A.
#[test]
fn singular_a_is_handled() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let sol = dare(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)).unwrap();
    assert!(max_abs_diff(&sol.x, &[1.0, 0.0, 0.0, 2.0]) < 1e-13);
    assert!(sol.k.amax() < 1e-13);
}

/// x₁⁺ = 1.5 x₁ with no input: unstabilisable at λ = 1.5. And with Q blind to an integrator mode
/// (λ = 1 on the unit circle), undetectable.
#[test]
fn unstabilizable_and_undetectable_are_named() {
    let a = DMatrix::from_row_slice(2, 2, &[1.5, 0.0, 0.0, 0.5]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    match dare(&a, &b, &DMatrix::identity(2, 2), &DMatrix::identity(1, 1)) {
        Err(RiccatiError::NotStabilizable {
            eigenvalue,
            direction,
        }) => {
            assert!((eigenvalue.re - 1.5).abs() < 1e-12);
            assert!((direction.unwrap()[0].norm() - 1.0).abs() < 1e-12);
        }
        other => panic!("expected NotStabilizable, got {other:?}"),
    }
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.5]);
    let b = DMatrix::from_row_slice(2, 1, &[1.0, 1.0]);
    let q = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]);
    match dare(&a, &b, &q, &DMatrix::identity(1, 1)) {
        Err(RiccatiError::NotDetectable { eigenvalue, .. }) => {
            assert!((eigenvalue.re - 1.0).abs() < 1e-12);
        }
        other => panic!("expected NotDetectable, got {other:?}"),
    }
}

mod random {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Generic 4-state, 2-input discrete systems (possibly unstable, |λ| up to about 2): X satisfies the DARE
        /// (residual recomputed here), is symmetric, and A − BK is Schur stable.
        #[test]
        fn generic_systems_satisfy_the_equation(
            a_entries in prop::collection::vec(-1.0f64..1.0, 16),
            b_entries in prop::collection::vec(-1.0f64..1.0, 8),
            m_entries in prop::collection::vec(-1.0f64..1.0, 16),
            r_scale in 0.01f64..100.0,
        ) {
            let a = DMatrix::from_row_slice(4, 4, &a_entries);
            let b = DMatrix::from_row_slice(4, 2, &b_entries);
            let m = DMatrix::from_row_slice(4, 4, &m_entries);
            let q = m.transpose() * &m + DMatrix::identity(4, 4) * 0.1;
            let r = DMatrix::from_row_slice(2, 2, &[1.0, 0.3, 0.3, 2.0]) * r_scale;
            let sol = dare(&a, &b, &q, &r).unwrap();
            let x = &sol.x;
            let s = &r + b.transpose() * x * &b;
            let correction = a.transpose() * x * &b * s.try_inverse().unwrap() * b.transpose() * x * &a;
            let atxa = a.transpose() * x * &a;
            let res = &atxa - x - &correction + &q;
            let rel = res.norm() / (atxa.norm() + x.norm() + correction.norm() + q.norm());
            prop_assert!(rel < 1e-12, "relative residual {rel:e}");
            prop_assert!((x - x.transpose()).amax() <= 1e-14 * x.amax());
            let closed = &a - &b * &sol.k;
            prop_assert!(closed.complex_eigenvalues().iter().all(|l| l.norm() < 1.0));
        }
    }
}

/// `x⁺ = s·[1 0.1; 0 1] x + s·[0; 0.1] u` with `Q = s·I`, `R = s`: as `s` grows the optimal gain tends to the
/// deadbeat gain `[100, 20]` (`A − BK` nilpotent: trace `s(2 − 0.1 k₂) = 0`, determinant `s²(0.01 k₁ − 1) = 0`).
fn scaled_double_integrator(s: f64) -> [DMatrix<f64>; 4] {
    [
        DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]) * s,
        DMatrix::from_row_slice(2, 1, &[0.0, 0.1]) * s,
        DMatrix::identity(2, 2) * s,
        DMatrix::identity(1, 1) * s,
    ]
}

#[test]
fn a_fast_growing_open_loop_gives_the_deadbeat_gain_or_says_it_is_out_of_range() {
    // scipy 1.17's solve_discrete_are returns K = [100.00000074, 20.00000007] at s = 1e5 with a relative residual
    // of 73 (and a wrong sign of X); bgc's gain must be the deadbeat limit with its residual checked.
    let [a, b, q, r] = scaled_double_integrator(1e5);
    let sol = dare(&a, &b, &q, &r).expect("solvable at 1e5");
    for (k, want) in sol.k.iter().zip([100.0, 20.0]) {
        assert!((k - want).abs() <= 1e-7 * want, "K = {}", sol.k);
    }
    assert!(sol.relative_residual < 1e-8, "{}", sol.relative_residual);
    // Further out the doubling iterates grow past f64 (or past 1/ε, where `I + GH` loses its identity): a named
    // error, never a non-convergence with an infinite residual.
    for s in [1e15, 1e20, 1e25, 1e50, 1e100, 1e150, 1e200, 1e300] {
        let [a, b, q, r] = scaled_double_integrator(s);
        let err = dare(&a, &b, &q, &r).expect_err("out of range");
        assert!(
            matches!(err, RiccatiError::OutOfRange { .. }),
            "{s:e}: {err:?}"
        );
        assert!(err.to_string().contains("rescale"), "{err}");
    }
    // At 1e10 X meets the equation, but the near-deadbeat gain computed from it does not stabilise: said as an
    // ill-conditioned problem.
    let [a, b, q, r] = scaled_double_integrator(1e10);
    match dare(&a, &b, &q, &r) {
        Ok(sol) => {
            let cl = &a - &b * &sol.k;
            let radius = cl
                .complex_eigenvalues()
                .iter()
                .map(|l| l.norm())
                .fold(0.0, f64::max);
            assert!(
                radius < 1.0,
                "K = {} gives a spectral radius of {radius}",
                sol.k
            );
        }
        Err(err) => {
            assert!(
                matches!(err, RiccatiError::ClosedLoopUnstable { .. }),
                "1e10: {err:?}"
            );
            assert!(err.to_string().contains("ill-conditioned"), "{err}");
        }
    }
}

/// The same family shrinking: `X = s·I + O(s³)`, so `K = R⁻¹BᵀXA (1 + O(s²)) = [0.01 s⁴, 0.1 s²] (1 + O(s²))`
/// (the first entry from the `s³` term of `X`). Each entry is checked wherever f64 holds it; multiplying `BᵀXA`
/// before the solve underflowed at `s = 1e-150` (`K₂ = 1e-301` came out 0).
#[test]
fn a_slow_shrinking_open_loop_keeps_its_small_gain() {
    for s in [1e-5f64, 1e-20, 1e-50, 1e-100, 1e-150, 1e-154] {
        let [a, b, q, r] = scaled_double_integrator(s);
        let sol = dare(&a, &b, &q, &r).unwrap_or_else(|e| panic!("s = {s:e}: {e}"));
        for (k, want) in sol.k.iter().zip([0.01 * s.powi(4), 0.1 * s * s]) {
            if want > f64::MIN_POSITIVE {
                assert!((k - want).abs() <= 1e-9 * want, "s = {s:e}: K = {}", sol.k);
            } else {
                assert!(k.abs() <= f64::MIN_POSITIVE, "s = {s:e}: K = {}", sol.k);
            }
        }
    }
}

/// A state weight far below what stabilising the plant costs: `A = [1 0.1; 0.4 1.04]` has the eigenvalues
/// `1.02 ± √0.0404` (1.22100 unstable, 0.81900 stable, their product `det A = 1`). As `Q/R → 0` the gain tends to the
/// minimum-energy one, which mirrors the unstable eigenvalue into the unit circle: `A − BK` (`B = [0; 0.1]`) has the
/// double eigenvalue `μ = 1.02 − √0.0404`, so trace `2.04 − 0.1 k₂ = 2μ` and determinant `1 − 0.1 k₂ + 0.01 k₁ = μ²`
/// give `K = [8.08 − 4√0.0404, 20√0.0404]` by hand (scipy 1.17.1: `[7.27600995, 4.01995025]` at `Q = 1e-40 I`).
/// Before, `Q/R` below about 1e-15 was refused: the doubling iterates left f64.
#[test]
fn a_state_weight_far_below_the_cost_of_stabilising_gives_the_minimum_energy_gain() {
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.4, 1.04]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 0.1]);
    let root = 0.0404f64.sqrt();
    let k_ref = DMatrix::from_row_slice(1, 2, &[8.08 - 4.0 * root, 20.0 * root]);
    for ratio in [1e-16, 1e-40, 1e-100, 1e-200, 1e-300] {
        let weights = [
            (DMatrix::identity(2, 2) * ratio, DMatrix::identity(1, 1)),
            (DMatrix::identity(2, 2), DMatrix::identity(1, 1) / ratio),
        ];
        for (q, r) in &weights {
            let sol = dare(&a, &b, q, r).unwrap_or_else(|e| panic!("Q/R = {ratio:e}: {e}"));
            let err = (&sol.k - &k_ref).amax() / k_ref.amax();
            assert!(err < 1e-10, "Q/R = {ratio:e}: K = {}", sol.k);
        }
    }
}
