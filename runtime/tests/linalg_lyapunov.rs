//! Lyapunov equations against scipy, including 2x2 Schur blocks (complex eigenvalue pairs).
#![allow(clippy::excessive_precision)] // reference values are pasted from numpy at full precision

use bgc_runtime::linalg::{LyapunovError, MatrixError, dlyap, lyap};
use nalgebra::DMatrix;

fn a4() -> DMatrix<f64> {
    DMatrix::from_row_slice(
        4,
        4,
        &[
            -1.0, 2.0, 0.0, 0.5, -3.0, -1.0, 0.2, 0.0, 0.0, 0.4, -0.5, 1.5, 0.1, 0.0, -2.0, -0.7,
        ],
    )
}

fn q4() -> DMatrix<f64> {
    DMatrix::from_row_slice(
        4,
        4,
        &[
            2.0, 0.5, 0.0, 0.1, 0.5, 1.0, 0.2, 0.0, 0.0, 0.2, 3.0, 0.4, 0.1, 0.0, 0.4, 1.5,
        ],
    )
}

/// ```python
/// import numpy as np, scipy.linalg as sl
/// A = np.array([[-1.0, 2.0, 0.0, 0.5], [-3.0, -1.0, 0.2, 0.0], [0.0, 0.4, -0.5, 1.5], [0.1, 0.0, -2.0, -0.7]])
/// Q = np.array([[2.0, 0.5, 0.0, 0.1], [0.5, 1.0, 0.2, 0.0], [0.0, 0.2, 3.0, 0.4], [0.1, 0.0, 0.4, 1.5]])
/// sl.solve_continuous_lyapunov(A, -Q)   # scipy solves A X + X Aᵀ = Q
/// sl.solve_discrete_lyapunov(A / 4.0, Q)
/// ```
/// A has two complex pairs (−0.98 ± 2.47i, −0.62 ± 1.66i), so only 2x2 Schur blocks are exercised.
#[test]
fn continuous_and_discrete_match_scipy() {
    let xc_ref = DMatrix::from_row_slice(
        4,
        4,
        &[
            0.8081842098451331,
            -0.13567696631979248,
            0.08470733331111968,
            0.15907628496943602,
            -0.13567696631979234,
            0.9196456103768023,
            0.06307355708712412,
            -0.40606798104003344,
            0.08470733331111967,
            0.06307355708712412,
            1.949880314866868,
            -0.366859510267612,
            0.15907628496943593,
            -0.40606798104003344,
            -0.36685951026761204,
            2.1423237843316683,
        ],
    );
    let xc = lyap(&a4(), &q4()).unwrap();
    assert!((&xc - &xc_ref).amax() < 1e-13, "X = {xc}");

    let xd_ref = DMatrix::from_row_slice(
        4,
        4,
        &[
            2.8193970575048257,
            0.5040406790441794,
            0.23627830882175102,
            0.01993409582725487,
            0.5040406790441797,
            2.947432695191519,
            0.09854886335749637,
            -0.04213149944828306,
            0.23627830882175097,
            0.09854886335749641,
            3.3906587998346005,
            0.38199988234424287,
            0.01993409582725487,
            -0.04213149944828311,
            0.38199988234424315,
            2.48633957082739,
        ],
    );
    let xd = dlyap(&(a4() / 4.0), &q4()).unwrap();
    assert!((&xd - &xd_ref).amax() < 1e-13, "X = {xd}");
}

/// Real eigenvalues only (1x1 blocks): for diagonal A = diag(a), X_ij = −Q_ij / (a_i + a_j) (continuous) and
/// Q_ij / (1 − a_i a_j) (discrete), by hand; rotated by an orthogonal matrix to make A full.
#[test]
fn diagonalisable_real_case_matches_closed_form() {
    let d = [-1.0, -2.0, -5.0];
    let dd = [0.5, -0.3, 0.8];
    let q = DMatrix::from_row_slice(3, 3, &[1.0, 0.2, 0.3, 0.2, 2.0, 0.1, 0.3, 0.1, 3.0]);
    // A Householder reflection H = I − 2vvᵀ/vᵀv is orthogonal and symmetric.
    let v = nalgebra::dvector![1.0, 2.0, -1.0];
    let h = DMatrix::identity(3, 3) - &v * v.transpose() * (2.0 / v.norm_squared());
    let xc_diag = DMatrix::from_fn(3, 3, |i, j| -q[(i, j)] / (d[i] + d[j]));
    let xd_diag = DMatrix::from_fn(3, 3, |i, j| q[(i, j)] / (1.0 - dd[i] * dd[j]));
    let ac = &h * DMatrix::from_diagonal(&nalgebra::dvector![d[0], d[1], d[2]]) * &h;
    let ad = &h * DMatrix::from_diagonal(&nalgebra::dvector![dd[0], dd[1], dd[2]]) * &h;
    let qh = &h * &q * &h;
    let xc = lyap(&ac, &qh).unwrap();
    let xd = dlyap(&ad, &qh).unwrap();
    let xc_ref: DMatrix<f64> = &h * xc_diag * &h;
    let xd_ref: DMatrix<f64> = &h * xd_diag * &h;
    assert!((&xc - &xc_ref).amax() < 1e-13);
    assert!((&xd - &xd_ref).amax() < 1e-13);
    // X is linear in Q: Q of any size gives X of that size, where the squares of its entries leave f64 (1e160) or
    // vanish in it (1e-160). Before, dlyap's residual overflowed there and the solution was refused.
    for s in [1e-300, 1e-160, 1e160, 1e300] {
        let qs = &qh * s;
        let xc = lyap(&ac, &qs).unwrap_or_else(|e| panic!("Q * {s:e}: {e}"));
        let xd = dlyap(&ad, &qs).unwrap_or_else(|e| panic!("Q * {s:e}: {e}"));
        assert!((&xc / s - &xc_ref).amax() < 1e-13, "Q * {s:e}: {xc}");
        assert!((&xd / s - &xd_ref).amax() < 1e-13, "Q * {s:e}: {xd}");
    }
    // A solution beyond f64 is an error that says so: X = Q / (1 − 0.99²) ≈ 50 Q.
    let err = dlyap(
        &(DMatrix::<f64>::identity(2, 2) * 0.99),
        &(DMatrix::<f64>::identity(2, 2) * 1e307),
    )
    .expect_err("X ≈ 5e308");
    assert_eq!(err, LyapunovError::Overflow);
}

#[test]
fn errors() {
    let q = DMatrix::<f64>::identity(2, 2);
    // λ = ±1: λ₁ + λ₂ = 0, no unique solution.
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
    assert!(matches!(
        lyap(&a, &q),
        Err(LyapunovError::NoUniqueSolution { .. })
    ));
    // The eigenvalues in the message are in scientific notation (1e160 was printed with 161 digits).
    let err = lyap(&(&a * 1e160), &q).expect_err("λ₁ + λ₂ = 0 at any scale");
    assert!(err.to_string().contains("1.0000e160"), "{err}");
    // λ = 2, 0.5: λ₁λ₂ = 1.
    let a = DMatrix::from_row_slice(2, 2, &[2.0, 0.0, 0.0, 0.5]);
    assert!(matches!(
        dlyap(&a, &q),
        Err(LyapunovError::NoUniqueSolution { .. })
    ));
    // No order limit: A = −I, Q = I at 300 states gives X = I/2 by hand.
    let big = DMatrix::<f64>::identity(300, 300) * -1.0;
    let qb = DMatrix::<f64>::identity(300, 300);
    let xb = lyap(&big, &qb).unwrap();
    assert!((xb - qb * 0.5).amax() < 1e-15);
    let mut qn = q.clone();
    qn[(0, 0)] = f64::INFINITY;
    assert!(matches!(
        lyap(&(-DMatrix::<f64>::identity(2, 2)), &qn),
        Err(LyapunovError::Input(MatrixError::NonFinite {
            name: "Q",
            ..
        }))
    ));
}

/// `(sA) X + X (sA)ᵀ + sQ = 0` has the `X` of `s = 1` (a change of the unit of time). From about 1e154 on, the
/// norm of `A` overflowed and every pair of eigenvalues passed for `λᵢ + λⱼ = 0`.
#[test]
fn a_change_of_the_unit_of_time_keeps_the_lyapunov_solution() {
    let a = DMatrix::from_row_slice(3, 3, &[-1.0, 0.1, 0.0, 0.0, -1.0, 0.2, -0.3, 0.0, -0.5]);
    let q = DMatrix::<f64>::identity(3, 3);
    let x_ref = lyap(&a, &q).expect("unit scale");
    for s in [1e-300, 1e-150, 1e160, 1e200, 1e300] {
        let x = lyap(&(&a * s), &(&q * s)).unwrap_or_else(|e| panic!("{s:e}: {e}"));
        assert!((&x - &x_ref).amax() <= 1e-12 * x_ref.amax(), "{s:e}: {x}");
    }
}
