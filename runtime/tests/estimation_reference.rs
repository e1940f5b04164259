//! Estimators against filterpy and scipy.

// Reference values are pasted as numpy printed them (17 significant digits).
#![allow(clippy::excessive_precision)]

use bgc_runtime::estimation::kalman::steady_state_gain;
use bgc_runtime::estimation::{
    KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter, UpdateOutcome,
};
use nalgebra::{
    Matrix1, Matrix2, Matrix2x3, Matrix3, Matrix3x1, Matrix3x2, SMatrix, Vector1, Vector2, Vector3,
};

fn assert_close<const R: usize, const C: usize>(
    what: &str,
    got: &SMatrix<f64, R, C>,
    want: &SMatrix<f64, R, C>,
    tol: f64,
) {
    let err = (got - want).amax();
    assert!(
        err <= tol,
        "{what}: max error {err:e} > {tol:e}\n got {got}\n want {want}"
    );
}

fn fx(x: &Vector3<f64>, u: &Vector1<f64>) -> Vector3<f64> {
    let dt = 0.1;
    Vector3::new(
        x[0] + dt * x[1],
        x[1] + dt * (-x[0].sin() - 0.3 * x[1] + u[0]),
        0.95 * x[2] + 0.1 * x[0] * x[1],
    )
}

fn hx(x: &Vector3<f64>, _u: &Vector1<f64>) -> Vector2<f64> {
    Vector2::new(x[0] + 0.5 * x[2] * x[2], x[1].sin())
}

/// ```python
/// import numpy as np
/// from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
/// def fx(x, dt, u=0.0):
///     return np.array([x[0] + dt * x[1],
///                      x[1] + dt * (-np.sin(x[0]) - 0.3 * x[1] + u),
///                      0.95 * x[2] + 0.1 * x[0] * x[1]])
/// def hx(x):
///     return np.array([x[0] + 0.5 * x[2] ** 2, np.sin(x[1])])
/// pts = MerweScaledSigmaPoints(3, alpha=0.5, beta=2.0, kappa=0.0)
/// ukf = UnscentedKalmanFilter(dim_x=3, dim_z=2, dt=0.1, hx=hx, fx=fx, points=pts)
/// ukf.x = np.array([0.4, -0.2, 1.0])
/// ukf.P = np.array([[0.5, 0.1, 0.0], [0.1, 0.3, 0.05], [0.0, 0.05, 0.2]])
/// ukf.Q = np.diag([1e-3, 2e-3, 5e-4]); ukf.R = np.diag([0.01, 0.02])
/// print(pts.sigma_points(ukf.x, ukf.P), pts.Wm, pts.Wc)
/// ukf.predict(u=0.7); print(ukf.x, ukf.P)
/// ukf.update(np.array([0.9, -0.1])); print(ukf.x, ukf.P, ukf.y, ukf.S)
/// ```
#[test]
fn ukf_sigma_points_weights_and_one_step_match_filterpy() {
    let points = SigmaPoints::<3, 7>::new(0.5, 2.0, 0.0).unwrap();
    let x0 = Vector3::new(0.4, -0.2, 1.0);
    let p0 = Matrix3::new(0.5, 0.1, 0.0, 0.1, 0.3, 0.05, 0.0, 0.05, 0.2);

    let sigmas = points.generate(&x0, &p0).unwrap();
    // filterpy rows are sigma points; here they are columns.
    let want = SMatrix::<f64, 7, 3>::from_row_slice(&[
        0.4,
        -0.2,
        1.0, //
        1.0123724356957946,
        -0.07752551286084107,
        1.0, //
        0.4,
        0.2582575694955839,
        1.0818317088384972, //
        0.4,
        -0.2,
        1.378554581835396, //
        -0.21237243569579445,
        -0.32247448713915894,
        1.0, //
        0.4,
        -0.6582575694955839,
        0.9181682911615028, //
        0.4,
        -0.2,
        0.6214454181646041,
    ])
    .transpose();
    assert_close("sigma points", &sigmas, &want, 1e-15);
    let two_thirds = 0.6666666666666666;
    let wm = SMatrix::<f64, 7, 1>::from_column_slice(&[
        -3.0, two_thirds, two_thirds, two_thirds, two_thirds, two_thirds, two_thirds,
    ]);
    let mut wc = wm;
    wc[0] = -0.25;
    assert_close("Wm", points.mean_weights(), &wm, 1e-15);
    assert_close("Wc", points.covariance_weights(), &wc, 1e-15);

    let q = Matrix3::from_diagonal(&Vector3::new(1e-3, 2e-3, 5e-4));
    let r = Matrix2::from_diagonal(&Vector2::new(0.01, 0.02));
    let mut ukf = UnscentedKalmanFilter::<3, 1, 2, 7>::new(points, q, r, x0, p0).unwrap();
    let u = Vector1::new(0.7);
    assert_eq!(ukf.predict(&u, fx).unwrap(), None);
    assert_close(
        "x prior",
        ukf.state(),
        &Vector3::new(0.3799999999999999, -0.15350683119970962, 0.9520000000000002),
        1e-12,
    );
    let p_prior = Matrix3::new(
        5.2399999999999991e-01,
        8.2007212385176442e-02,
        -2.5000000000003920e-04,
        8.2007212385176442e-02,
        2.7145735617632244e-01,
        5.6529613753600404e-02,
        -2.5000000000003887e-04,
        5.6529613753600397e-02,
        1.8557000000000010e-01,
    );
    assert_close("P prior", ukf.covariance(), &p_prior, 1e-12);

    let out = ukf.update(&Vector2::new(0.9, -0.1), &u, hx).unwrap();
    assert!(matches!(out, UpdateOutcome::Accepted { repair: None, .. }));
    assert_close(
        "x post",
        ukf.state(),
        &Vector3::new(0.3585175618543927, -0.12258209550454638, 0.9488587393706135),
        1e-12,
    );
    let p_post = Matrix3::new(
        0.1430121562404848,
        0.00035268776238429,
        -0.12665028149842242,
        0.00035268776238429,
        0.02108664159668872,
        0.00331355230711395,
        -0.12665028149842242,
        0.00331355230711395,
        0.14070318958259914,
    );
    assert_close("P post", ukf.covariance(), &p_post, 1e-12);
    assert_close(
        "innovation",
        ukf.innovation(),
        &Vector2::new(-0.02593699999999977, 0.03246943879558659),
        1e-12,
    );
    let s = Matrix2::new(
        0.7224258351442746,
        0.13580088238068905,
        0.13580088238068905,
        0.27017196693647627,
    );
    assert_close("S", ukf.innovation_covariance(), &s, 1e-12);
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

fn wrapped_residual(a: &Vector1<f64>, b: &Vector1<f64>) -> Vector1<f64> {
    Vector1::new(wrap(a[0] - b[0]))
}

/// A bearing measurement across ±π with a wrapping residual, and α = 1e-3 (weights of order 10⁶):
/// ```python
/// def wrap(a): return (a + np.pi) % (2 * np.pi) - np.pi
/// def fx(x, dt): return np.array([x[0] + dt * x[1], x[1], x[2]])
/// def hx(x): return np.array([np.arctan2(x[2], x[0])])
/// pts = MerweScaledSigmaPoints(3, alpha=1e-3, beta=2.0, kappa=0.0)
/// ukf = UnscentedKalmanFilter(dim_x=3, dim_z=1, dt=0.1, hx=hx, fx=fx, points=pts,
///                             residual_z=lambda a, b: wrap(a - b))
/// ukf.x = np.array([-1.0, 0.1, 0.05]); ukf.P = np.diag([0.01, 0.01, 0.001])
/// ukf.Q = np.eye(3) * 1e-4; ukf.R = np.array([[1e-3]])
/// ukf.predict(); ukf.update(np.array([-3.13])); print(pts.Wm, pts.Wc, ukf.x, ukf.P, ukf.y)
/// ```
/// The weights of order 10⁶ cancel in the sums, which costs about six digits, so the state and covariance
/// are compared to 1e-9 here.
#[test]
fn ukf_with_angle_residual_and_tiny_alpha_matches_filterpy() {
    let points = SigmaPoints::<3, 7>::new(1e-3, 2.0, 0.0).unwrap();
    assert!((points.mean_weights()[0] / -999999.0000082518 - 1.0).abs() < 1e-12);
    assert!((points.covariance_weights()[0] / -999996.0000092518 - 1.0).abs() < 1e-12);
    assert!((points.mean_weights()[1] / 166666.66666804196 - 1.0).abs() < 1e-12);
    let mut ukf = UnscentedKalmanFilter::<3, 0, 1, 7>::new(
        points,
        Matrix3::identity() * 1e-4,
        Matrix1::new(1e-3),
        Vector3::new(-1.0, 0.1, 0.05),
        Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.001)),
    )
    .unwrap()
    .with_measurement_functions(
        bgc_runtime::estimation::sigma::weighted_mean::<1, 7>,
        wrapped_residual,
    );
    let u = nalgebra::SVector::<f64, 0>::zeros();
    ukf.predict(&u, |x, _| Vector3::new(x[0] + 0.1 * x[1], x[1], x[2]))
        .unwrap();
    let out = ukf
        .update(&Vector1::new(-3.13), &u, |x, _| {
            Vector1::new(x[2].atan2(x[0]))
        })
        .unwrap();
    assert!(out.is_accepted());
    assert!((ukf.innovation()[0] - 0.06252137200535213).abs() < 1e-9);
    assert_close(
        "x post",
        ukf.state(),
        &Vector3::new(-1.005139205305513, 0.09851576419428301, 0.01767334499526255),
        1e-9,
    );
    let p_post = Matrix3::new(
        1.0074319468450514e-02,
        9.8767837925760392e-04,
        -2.6836489104820570e-04,
        9.8767837925760392e-04,
        1.0098791997966953e-02,
        -2.6310283436039908e-05,
        -2.6836489104820565e-04,
        -2.6310283436039905e-05,
        5.2696204525605700e-04,
    );
    assert_close("P post", ukf.covariance(), &p_post, 1e-9);
}

fn kf_model() -> LinearDiscreteModel<3, 1, 2> {
    let dt = 0.05;
    LinearDiscreteModel {
        a: Matrix3::new(1.0, dt, 0.0, -0.4 * dt, 1.0 - 0.1 * dt, dt, 0.0, 0.0, 0.98),
        b: Matrix3x1::new(0.0, dt, 0.02),
        c: Matrix2x3::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        d: SMatrix::<f64, 2, 1>::zeros(),
    }
}

fn kf_noise() -> (Matrix3<f64>, Matrix2<f64>) {
    (
        Matrix3::new(1e-4, 2e-5, 0.0, 2e-5, 4e-4, 0.0, 0.0, 0.0, 1e-4),
        Matrix2::new(0.01, 0.002, 0.002, 0.04),
    )
}

/// ```python
/// import numpy as np, scipy.linalg as sl
/// from filterpy.kalman import KalmanFilter
/// dt = 0.05
/// F = np.array([[1, dt, 0], [-0.4 * dt, 1 - 0.1 * dt, dt], [0, 0, 0.98]])
/// B = np.array([[0.0], [dt], [0.02]]); H = np.array([[1.0, 0, 0], [0, 0, 1.0]])
/// Q = np.array([[1e-4, 2e-5, 0], [2e-5, 4e-4, 0], [0, 0, 1e-4]]); R = np.array([[0.01, 0.002], [0.002, 0.04]])
/// kf = KalmanFilter(dim_x=3, dim_z=2, dim_u=1); kf.F, kf.B, kf.H, kf.Q, kf.R = F, B, H, Q, R
/// kf.x = np.array([0.1, 0.0, -0.2]); kf.P = np.diag([1.0, 0.5, 0.25])
/// us = [0.5, -0.2, 1.0, 0.0, 0.3]
/// zs = [[0.12, -0.15], [0.2, -0.1], [0.15, -0.3], [0.31, -0.05], [0.28, -0.2]]
/// for u, z in zip(us, zs):
///     kf.predict(u=np.array([u])); kf.update(np.array(z))
/// print(kf.x, kf.P, kf.K)
/// P = sl.solve_discrete_are(F.T, H.T, Q, R); K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
/// ```
#[test]
fn kalman_filter_matches_filterpy_over_five_steps() {
    let (q, r) = kf_noise();
    let mut kf = KalmanFilter::new(
        kf_model(),
        q,
        r,
        Vector3::new(0.1, 0.0, -0.2),
        Matrix3::from_diagonal(&Vector3::new(1.0, 0.5, 0.25)),
    )
    .unwrap();
    let us = [0.5, -0.2, 1.0, 0.0, 0.3];
    let zs = [
        [0.12, -0.15],
        [0.2, -0.1],
        [0.15, -0.3],
        [0.31, -0.05],
        [0.28, -0.2],
    ];
    for (u, z) in us.iter().zip(zs) {
        let u = Vector1::new(*u);
        kf.predict(&u).unwrap();
        assert!(
            kf.update(&Vector2::new(z[0], z[1]), &u)
                .unwrap()
                .is_accepted()
        );
    }
    assert_close(
        "x",
        kf.state(),
        &Vector3::new(0.2615218133596225, 0.48681803805447493, -0.1405768216927113),
        1e-12,
    );
    let p = Matrix3::new(
        0.00422095091034946,
        0.0213423787433458,
        0.00042508529309572,
        0.0213423787433458,
        0.217063275769649,
        0.00128064556497406,
        0.00042508529309572,
        0.00128064556497406,
        0.00723845522871973,
    );
    assert_close("P", kf.covariance(), &p, 1e-12);
    let k = Matrix3x2::new(
        0.42421178239340185,
        -0.01058345679227706,
        2.1493279257673827,
        -0.07545025716401765,
        0.00638005370300353,
        0.18064237803284297,
    );
    assert_close("K", kf.gain(), &k, 1e-12);
}

/// The steady-state gain by Riccati iteration against `scipy.linalg.solve_discrete_are` (same snippet).
#[test]
fn steady_state_gain_matches_scipy_dare() {
    let m = kf_model();
    let (q, r) = kf_noise();
    let ss = steady_state_gain(&m.a, &m.c, &q, &r, 1e-14, 100_000).unwrap();
    let p = Matrix3::new(
        0.00183248308056364,
        0.00198984292612587,
        0.00020880035636345,
        0.00198984292612587,
        0.00671972798630058,
        0.00069045124978704,
        0.00020880035636345,
        0.00069045124978704,
        0.00137659709359251,
    );
    let k = Matrix3x2::new(
        0.15547617731178826,
        -0.00325342074855409,
        0.16671414338366555,
        0.00778732455309308,
        0.01155088738534908,
        0.03265332541396111,
    );
    assert_close("DARE P", &ss.predicted_covariance, &p, 1e-12);
    assert_close("steady K", &ss.filter_gain, &k, 1e-11);
    assert_close("predictor gain", &ss.predictor_gain, &(m.a * k), 1e-11);

    // A fixed-gain filter started at the steady-state covariance stays there and agrees with the
    // time-varying filter started at the same covariance.
    let x0 = Vector3::new(0.1, 0.0, -0.2);
    let p0 = ss.filtered_covariance;
    let mut fixed = KalmanFilter::with_fixed_gain(m, q, r, ss.filter_gain, x0, p0).unwrap();
    let mut tv = KalmanFilter::new(m, q, r, x0, p0).unwrap();
    for k in 0..20 {
        let u = Vector1::new((k as f64 * 0.3).sin());
        let y = Vector2::new(0.1 * k as f64, -0.05);
        fixed.predict(&u).unwrap();
        tv.predict(&u).unwrap();
        fixed.update(&y, &u).unwrap();
        tv.update(&y, &u).unwrap();
    }
    assert_close("fixed vs time-varying x", fixed.state(), tv.state(), 1e-10);
    assert_close("fixed P stays steady", fixed.covariance(), &p0, 1e-10);

    // Filter gain back from the predictor gain (A is invertible here).
    let back =
        bgc_runtime::estimation::kalman::filter_gain_from_predictor(&m.a, &ss.predictor_gain)
            .unwrap();
    assert_close("K from L", &back, &ss.filter_gain, 1e-12);
}
