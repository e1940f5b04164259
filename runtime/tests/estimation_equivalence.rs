//! Filters that must agree: the UKF, augmented UKF and KF on linear models; the square-root UKF and the UKF;
//! the augmented UKF against a direct numpy transcription of Wan and van der Merwe's Algorithm 3.1.

// Reference values are pasted as numpy printed them (17 significant digits).
#![allow(clippy::excessive_precision)]

use bgc_runtime::estimation::srukf::SquareRootUkf;
use bgc_runtime::estimation::ukf_augmented::AugmentedUkf;
use bgc_runtime::estimation::{
    KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter,
};
use nalgebra::{
    Matrix1, Matrix2, Matrix2x1, Matrix3, Matrix3x1, SMatrix, Vector1, Vector2, Vector3,
};

fn max_err<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>, b: &SMatrix<f64, R, C>) -> f64 {
    (a - b).amax()
}

fn linear() -> LinearDiscreteModel<3, 1, 2> {
    LinearDiscreteModel {
        a: Matrix3::new(1.0, 0.1, 0.0, -0.2, 0.95, 0.1, 0.0, 0.05, 0.9),
        b: Matrix3x1::new(0.0, 0.1, 0.05),
        c: SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.0, 0.0, 1.0, 1.0),
        d: SMatrix::<f64, 2, 1>::new(0.0, 0.1),
    }
}

fn inputs(k: usize) -> (Vector1<f64>, Vector2<f64>) {
    let t = k as f64;
    (
        Vector1::new((0.3 * t).sin()),
        Vector2::new(0.2 * (0.2 * t).cos(), -0.1 + 0.05 * t.sin()),
    )
}

#[test]
fn ukf_on_a_linear_model_equals_the_kalman_filter() {
    let m = linear();
    let q = Matrix3::new(1e-3, 1e-4, 0.0, 1e-4, 2e-3, 0.0, 0.0, 0.0, 5e-4);
    let r = Matrix2::new(0.02, 0.001, 0.001, 0.01);
    let x0 = Vector3::new(0.5, -0.3, 0.1);
    let p0 = Matrix3::new(1.0, 0.2, 0.0, 0.2, 0.5, 0.1, 0.0, 0.1, 0.3);
    let mut kf = KalmanFilter::new(m, q, r, x0, p0).unwrap();
    for alpha in [1e-3, 0.5, 1.0] {
        kf.set_state(x0, p0).unwrap();
        let pts = SigmaPoints::<3, 7>::new(alpha, 2.0, 0.0).unwrap();
        let mut ukf = UnscentedKalmanFilter::<3, 1, 2, 7>::new(pts, q, r, x0, p0).unwrap();
        for k in 0..30 {
            let (u, y) = inputs(k);
            kf.predict(&u).unwrap();
            ukf.predict(&u, |x, u| m.a * x + m.b * u).unwrap();
            kf.update(&y, &u).unwrap();
            ukf.update(&y, &u, |x, u| m.c * x + m.d * u).unwrap();
        }
        // α = 1e-3 puts weights of order 10⁶ on the points, costing about six digits.
        let tol = if alpha < 0.01 { 1e-8 } else { 1e-12 };
        assert!(max_err(kf.state(), ukf.state()) < tol, "alpha {alpha}");
        assert!(
            max_err(kf.covariance(), ukf.covariance()) < tol,
            "alpha {alpha}"
        );
    }
}

fn fx(x: &Vector3<f64>, u: &Vector1<f64>) -> Vector3<f64> {
    Vector3::new(
        x[0] + 0.1 * x[1],
        x[1] + 0.1 * (-3.0 * x[0].sin() - 0.2 * x[1] + u[0]),
        0.9 * x[2] + 0.05 * x[0] * x[0],
    )
}

fn hx(x: &Vector3<f64>, _u: &Vector1<f64>) -> Vector2<f64> {
    Vector2::new(x[0].sin() + x[2], x[1] * x[2])
}

#[test]
fn square_root_ukf_equals_ukf() {
    let q = Matrix3::from_diagonal(&Vector3::new(1e-3, 2e-3, 1e-4));
    let r = Matrix2::new(0.01, 0.002, 0.002, 0.02);
    let x0 = Vector3::new(0.6, 0.0, 0.4);
    let p0 = Matrix3::new(0.3, 0.05, 0.0, 0.05, 0.2, 0.01, 0.0, 0.01, 0.1);
    // With α = 1, W₀⁽ᶜ⁾ = 2 > 0 (pure Givens updates); with α = 0.5, W₀⁽ᶜ⁾ < 0 (a downdate every step).
    for (alpha, tol) in [(1.0, 1e-12), (0.5, 1e-12), (1e-2, 1e-7)] {
        let pts = SigmaPoints::<3, 7>::new(alpha, 2.0, 0.0).unwrap();
        let mut ukf = UnscentedKalmanFilter::<3, 1, 2, 7>::new(pts, q, r, x0, p0).unwrap();
        let mut sr = SquareRootUkf::<3, 1, 2, 7>::new(pts, q, r, x0, p0).unwrap();
        for k in 0..40 {
            let u = Vector1::new((0.2 * k as f64).cos());
            let truth_like = Vector2::new((0.1 * k as f64).sin(), 0.05);
            ukf.predict(&u, fx).unwrap();
            sr.predict(&u, fx).unwrap();
            let a = ukf.update(&truth_like, &u, hx).unwrap();
            let b = sr.update(&truth_like, &u, hx).unwrap();
            assert!(a.is_accepted() && b.is_accepted());
        }
        let ex = max_err(ukf.state(), sr.state());
        let ep = max_err(ukf.covariance(), &sr.covariance());
        assert!(ex < tol && ep < tol, "alpha {alpha}: x {ex:e}, P {ep:e}");
        let ei = max_err(ukf.innovation_covariance(), &sr.innovation_covariance());
        assert!(ei < tol, "alpha {alpha}: S {ei:e}");
        let f = sr.covariance_factor();
        assert!(
            f[(0, 1)] == 0.0 && f[(0, 2)] == 0.0 && f[(1, 2)] == 0.0,
            "factor is lower triangular"
        );
    }
}

/// `x' = A x + B u + G v`, `y = C x + n`: the augmented UKF must equal the KF with `Q_kf = G Q Gᵀ`.
#[test]
fn augmented_ukf_on_a_linear_model_equals_the_kalman_filter() {
    let a = Matrix2::new(1.0, 0.1, -0.3, 0.97);
    let b = Matrix2x1::new(0.0, 0.1);
    let g = Matrix2x1::new(0.05, 1.0);
    let c = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
    let q = Matrix1::new(0.02);
    let r = Matrix1::new(0.05);
    let model = LinearDiscreteModel {
        a,
        b,
        c,
        d: Matrix1::zeros(),
    };
    let x0 = Vector2::new(1.0, 0.0);
    let p0 = Matrix2::new(0.5, 0.0, 0.0, 0.5);
    let mut kf = KalmanFilter::new(model, g * q * g.transpose(), r, x0, p0).unwrap();
    let pts = SigmaPoints::<4, 9>::new(0.8, 2.0, 0.0).unwrap();
    let mut aug = AugmentedUkf::<2, 1, 1, 1, 1, 4, 9>::new(pts, q, r, x0, p0).unwrap();
    for k in 0..25 {
        let u = Vector1::new(if k % 5 == 0 { 1.0 } else { 0.0 });
        let y = Vector1::new((0.4 * k as f64).cos());
        kf.predict(&u).unwrap();
        aug.predict(&u, |x, u, v| a * x + b * u + g * v).unwrap();
        kf.update(&y, &u).unwrap();
        aug.update(&y, &u, |x, _u, n| c * x + n).unwrap();
    }
    assert!(max_err(kf.state(), aug.state()) < 1e-12);
    assert!(max_err(kf.covariance(), aug.covariance()) < 1e-12);
}

/// Reference: a direct numpy transcription of Wan and van der Merwe's augmented UKF (Algorithm 3.1):
/// ```python
/// nx, nv, nn = 2, 1, 1; L = nx + nv + nn; alpha, beta, kappa = 0.7, 2.0, 0.0
/// lam = alpha**2 * (L + kappa) - L
/// Wm = np.full(2*L+1, 0.5/(L+lam)); Wc = Wm.copy()
/// Wm[0] = lam/(L+lam); Wc[0] = lam/(L+lam) + 1 - alpha**2 + beta
/// def f(x, u, v): return np.array([x[0] + 0.1*x[1], x[1] + 0.1*(-2.0*np.sin(x[0]) + u) * (1.0 + v[0])])
/// def h(x, u, n): return np.array([x[0] * np.exp(n[0])])
/// x = np.array([0.3, -0.1]); P = np.array([[0.2, 0.02], [0.02, 0.1]]); Q = [[0.05]]; R = [[0.01]]
/// u = 0.5; y = np.array([0.27])
/// xa = np.concatenate([x, np.zeros(nv+nn)]); Pa = blkdiag(P, Q, R)
/// S = np.linalg.cholesky((L+lam)*Pa)
/// chi = np.column_stack([xa] + [xa + S[:,i] for i in range(L)] + [xa - S[:,i] for i in range(L)])
/// X = np.column_stack([f(chi[:2,i], u, chi[2:3,i]) for i in range(2*L+1)]); xm = X @ Wm
/// Pm = sum(Wc[i]*np.outer(X[:,i]-xm, X[:,i]-xm) for i in range(2*L+1))
/// Y = np.column_stack([h(X[:,i], u, chi[3:4,i]) for i in range(2*L+1)]); ym = Y @ Wm
/// Pyy = sum(Wc[i]*np.outer(Y[:,i]-ym, Y[:,i]-ym) ...); Pxy = sum(Wc[i]*np.outer(X[:,i]-xm, Y[:,i]-ym) ...)
/// K = Pxy @ inv(Pyy); print(xm, Pm, xm + K @ (y - ym), Pm - K @ Pyy @ K.T)
/// ```
#[test]
fn augmented_ukf_with_multiplicative_noise_matches_numpy_transcription() {
    let pts = SigmaPoints::<4, 9>::new(0.7, 2.0, 0.0).unwrap();
    let mut aug = AugmentedUkf::<2, 1, 1, 1, 1, 4, 9>::new(
        pts,
        Matrix1::new(0.05),
        Matrix1::new(0.01),
        Vector2::new(0.3, -0.1),
        Matrix2::new(0.2, 0.02, 0.02, 0.1),
    )
    .unwrap();
    let u = Vector1::new(0.5);
    aug.predict(&u, |x, u, v| {
        Vector2::new(
            x[0] + 0.1 * x[1],
            x[1] + 0.1 * (-2.0 * x[0].sin() + u[0]) * (1.0 + v[0]),
        )
    })
    .unwrap();
    assert!(
        max_err(
            aug.state(),
            &Vector2::new(0.2899999999999999, -0.10338420516062988)
        ) < 1e-12
    );
    let p_prior = Matrix2::new(
        0.20500000000000002,
        -0.00612297950869157,
        -0.00612297950869157,
        0.09936039808131067,
    );
    assert!(max_err(aug.covariance(), &p_prior) < 1e-12);
    let out = aug
        .update(&Vector1::new(0.27), &u, |x, _u, n| {
            Vector1::new(x[0] * n[0].exp())
        })
        .unwrap();
    assert!(out.is_accepted());
    assert!(
        max_err(
            aug.state(),
            &Vector2::new(0.26863660900238107, -0.10274742651734714)
        ) < 1e-12
    );
    let p_post = Matrix2::new(
        8.5028699543684971e-04,
        -3.7888556225462201e-05,
        -3.7888556225461334e-05,
        9.9179019761670525e-02,
    );
    assert!(max_err(aug.covariance(), &p_post) < 1e-12);
}
