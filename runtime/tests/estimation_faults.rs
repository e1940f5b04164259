//! Bad data never reaches the state, singular problems are errors, broken covariances are repaired.

use bgc_runtime::estimation::srukf::SquareRootUkf;
use bgc_runtime::estimation::{
    EstimationError, FaultPolicy, KalmanFilter, LinearDiscreteModel, RejectReason, SigmaPoints,
    UnscentedKalmanFilter, UpdateOutcome,
};
use nalgebra::{Matrix1, Matrix2, SMatrix, SVector, Vector1, Vector2};

fn kf() -> KalmanFilter<2, 1, 1> {
    let model = LinearDiscreteModel {
        a: Matrix2::new(1.0, 0.1, 0.0, 1.0),
        b: SMatrix::<f64, 2, 1>::new(0.0, 0.1),
        c: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
        d: Matrix1::zeros(),
    };
    KalmanFilter::new(
        model,
        Matrix2::identity() * 1e-3,
        Matrix1::new(0.01),
        Vector2::new(0.0, 1.0),
        Matrix2::identity(),
    )
    .unwrap()
}

#[test]
fn nan_and_infinite_measurements_are_rejected_and_the_prediction_kept() {
    let mut f = kf();
    let u = Vector1::new(0.0);
    f.predict(&u).unwrap();
    let (x, p) = (*f.state(), *f.covariance());
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let out = f.update(&Vector1::new(bad), &u).unwrap();
        assert_eq!(
            out,
            UpdateOutcome::Rejected {
                reason: RejectReason::NonFiniteMeasurement { index: 0 }
            }
        );
        assert_eq!((*f.state(), *f.covariance()), (x, p));
    }
    // A non-finite input is an error and changes nothing either.
    assert_eq!(
        f.predict(&Vector1::new(f64::NAN)),
        Err(EstimationError::NonFiniteInput { index: 0 })
    );
    assert_eq!((*f.state(), *f.covariance()), (x, p));
}

/// With the gate at chi2.ppf(0.999, 1) = 10.83 a 1000σ outlier is rejected and reported with its NIS; a
/// normal measurement afterwards is accepted.
#[test]
fn huge_outlier_is_gated_out_with_its_nis() {
    let mut f = kf();
    f.set_fault_policy(FaultPolicy {
        nis_gate: Some(10.83),
        ..FaultPolicy::default()
    })
    .unwrap();
    let u = Vector1::new(0.0);
    f.predict(&u).unwrap();
    let (x, p) = (*f.state(), *f.covariance());
    // Predicted y = 0.1; S = P⁻₁₁ + R = (1 + 0.01 + 0.001) + 0.01 = 1.021.
    let out = f.update(&Vector1::new(1000.0), &u).unwrap();
    match out {
        UpdateOutcome::Rejected {
            reason: RejectReason::Outlier { nis, gate },
        } => {
            let expected = (1000.0f64 - 0.1).powi(2) / 1.021;
            assert!((nis / expected - 1.0).abs() < 1e-12, "nis {nis}");
            assert_eq!(gate, 10.83);
        }
        other => panic!("expected an outlier rejection, got {other:?}"),
    }
    assert_eq!((*f.state(), *f.covariance()), (x, p));
    assert!(f.update(&Vector1::new(0.3), &u).unwrap().is_accepted());
}

/// Two copies of the same noise-free sensor: `S = C P Cᵀ + 0` is singular. That is an error, not a panic,
/// and the filter is unchanged.
#[test]
fn singular_innovation_covariance_is_an_error() {
    let model = LinearDiscreteModel {
        a: Matrix2::identity(),
        b: SMatrix::<f64, 2, 1>::zeros(),
        c: SMatrix::<f64, 2, 2>::new(1.0, 0.0, 1.0, 0.0),
        d: SMatrix::<f64, 2, 1>::zeros(),
    };
    let mut f = KalmanFilter::new(
        model,
        Matrix2::zeros(),
        Matrix2::zeros(),
        Vector2::new(1.0, 2.0),
        Matrix2::identity(),
    )
    .unwrap();
    let u = Vector1::new(0.0);
    let err = f.update(&Vector2::new(1.1, 1.1), &u).unwrap_err();
    assert!(
        matches!(err, EstimationError::SingularInnovation { .. }),
        "{err:?}"
    );
    assert_eq!(*f.state(), Vector2::new(1.0, 2.0));

    // The same for the UKF and the square-root UKF.
    let pts = SigmaPoints::<2, 5>::new(1.0, 2.0, 0.0).unwrap();
    let h = |x: &Vector2<f64>, _u: &Vector1<f64>| Vector2::new(x[0], x[0]);
    let mut ukf = UnscentedKalmanFilter::<2, 1, 2, 5>::new(
        pts,
        Matrix2::zeros(),
        Matrix2::zeros(),
        Vector2::new(1.0, 2.0),
        Matrix2::identity(),
    )
    .unwrap();
    assert!(matches!(
        ukf.update(&Vector2::new(1.1, 1.1), &u, h),
        Err(EstimationError::SingularInnovation { .. })
    ));
    assert_eq!(*ukf.state(), Vector2::new(1.0, 2.0));
    let mut sr = SquareRootUkf::<2, 1, 2, 5>::new(
        pts,
        Matrix2::zeros(),
        Matrix2::zeros(),
        Vector2::new(1.0, 2.0),
        Matrix2::identity(),
    )
    .unwrap();
    assert!(matches!(
        sr.update(&Vector2::new(1.1, 1.1), &u, h),
        Err(EstimationError::SingularInnovation { .. })
    ));
    assert_eq!(*sr.state(), Vector2::new(1.0, 2.0));
}

/// For `f(x) = x²` in one dimension the unscented covariance of the propagated points is exactly
/// `β + α² κ` (for `x̂ = 0`, `P = 1`: `P = W₀ᶜ (0 − 1)² + 2 (γ² − 1)² / (2 γ²)` with `W₀ᶜ = (γ² − 1)/γ² + 1 − α² + β`
/// simplifies to `β + γ² − α²`, `γ² = α² (1 + κ)`). With `β = −1` and `Q = 0.5` the predicted "covariance" is
/// `−0.5`: the filter must floor it and report the repair.
#[test]
fn covariance_that_loses_definiteness_is_repaired_and_reported() {
    let pts = SigmaPoints::<1, 3>::new(1.0, -1.0, 0.0).unwrap();
    let mut ukf = UnscentedKalmanFilter::<1, 0, 1, 3>::new(
        pts,
        Matrix1::new(0.5),
        Matrix1::new(0.1),
        SVector::<f64, 1>::new(0.0),
        Matrix1::new(1.0),
    )
    .unwrap();
    ukf.set_fault_policy(FaultPolicy {
        eigen_floor: 1e-6,
        ..FaultPolicy::default()
    })
    .unwrap();
    let u = SVector::<f64, 0>::zeros();
    let repair = ukf
        .predict(&u, |x, _| SVector::<f64, 1>::new(x[0] * x[0]))
        .unwrap()
        .expect("the covariance must be reported as repaired");
    assert!((repair.min_eigenvalue + 0.5).abs() < 1e-12, "{repair:?}");
    assert_eq!(repair.floor, 1e-6);
    assert!((ukf.covariance()[(0, 0)] - 1e-6).abs() < 1e-18);
    // Mean of x² under N(0, 1) is 1.
    assert!((ukf.state()[0] - 1.0).abs() < 1e-12);
}

/// The Kalman filter's time update skips the factorisation of `P⁻` only where `Q` alone keeps it definite. Here
/// `Q = 10⁻²⁰ I` is positive definite but far below the rounding of `A P Aᵀ = [[2, 2], [2, 2]]` (singular, exact in
/// floating point), so the computed `P⁻` is singular: the filter must still find it and report the repair. With
/// `Q = 10⁻³ I` the same step needs none and gives `A P Aᵀ + Q` exactly.
#[test]
fn kalman_prediction_that_rounds_to_singular_is_repaired_and_a_definite_one_is_not() {
    let model = LinearDiscreteModel {
        a: Matrix2::new(1.0, 1.0, 1.0, 1.0),
        b: SMatrix::<f64, 2, 1>::zeros(),
        c: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
        d: Matrix1::zeros(),
    };
    let filter = |q: f64| {
        let mut kf = KalmanFilter::new(
            model,
            Matrix2::identity() * q,
            Matrix1::new(0.01),
            Vector2::zeros(),
            Matrix2::identity(),
        )
        .unwrap();
        kf.set_fault_policy(FaultPolicy {
            eigen_floor: 1e-9,
            ..FaultPolicy::default()
        })
        .unwrap();
        kf
    };
    let u = Vector1::zeros();
    let mut tiny = filter(1e-20);
    let repair = tiny
        .predict(&u)
        .unwrap()
        .expect("a prediction that rounds to singular must be repaired");
    assert!(repair.min_eigenvalue.abs() < 1e-14, "{repair:?}");
    assert_eq!(repair.floor, 1e-9);
    // The eigenvalues 0 and 4 become 1e-9 and 4: [[2, 2], [2, 2]] + 1e-9/2 [[1, -1], [-1, 1]].
    let p = tiny.covariance();
    assert!((p[(0, 0)] - (2.0 + 0.5e-9)).abs() < 1e-14, "{p}");
    assert!((p[(0, 1)] - (2.0 - 0.5e-9)).abs() < 1e-14, "{p}");

    let mut definite = filter(1e-3);
    assert_eq!(definite.predict(&u).unwrap(), None);
    assert_eq!(*definite.covariance(), Matrix2::new(2.001, 2.0, 2.0, 2.001));
}

/// A process function that returns NaN is an error naming the sigma point; the filter stays as it was.
#[test]
fn non_finite_model_output_is_an_error_and_changes_nothing() {
    let pts = SigmaPoints::<2, 5>::new(1.0, 2.0, 0.0).unwrap();
    let mut ukf = UnscentedKalmanFilter::<2, 1, 1, 5>::new(
        pts,
        Matrix2::identity() * 1e-3,
        Matrix1::new(0.1),
        Vector2::new(1.0, 0.0),
        Matrix2::identity(),
    )
    .unwrap();
    let u = Vector1::new(0.0);
    // ln(x0) is NaN at the sigma point x0 = 1 − √2 < 0 (point 3 = x̂ − γ S₁).
    let err = ukf
        .predict(&u, |x, _| Vector2::new(x[0].ln(), x[1]))
        .unwrap_err();
    assert_eq!(
        err,
        EstimationError::NonFiniteModelOutput {
            function: "process function",
            sigma_point: 3
        }
    );
    assert_eq!(*ukf.state(), Vector2::new(1.0, 0.0));
    assert_eq!(*ukf.covariance(), Matrix2::identity());
}

#[test]
fn constructors_refuse_invalid_settings() {
    assert!(SigmaPoints::<2, 5>::new(0.0, 2.0, 0.0).is_err());
    assert!(SigmaPoints::<2, 5>::new(1.0, f64::NAN, 0.0).is_err());
    // L + λ = α² (L + κ) = 0 for κ = −L.
    assert!(SigmaPoints::<2, 5>::new(1.0, 2.0, -2.0).is_err());
    let pts = SigmaPoints::<2, 5>::new(1.0, 2.0, 0.0).unwrap();
    let indefinite = Matrix2::new(1.0, 2.0, 2.0, 1.0);
    let r = UnscentedKalmanFilter::<2, 1, 1, 5>::new(
        pts,
        indefinite,
        Matrix1::new(0.1),
        Vector2::zeros(),
        Matrix2::identity(),
    );
    assert!(matches!(
        r,
        Err(EstimationError::NotPositiveDefinite { name: "Q", .. })
    ));
    let mut f = kf();
    assert!(
        f.set_fault_policy(FaultPolicy {
            nis_gate: Some(f64::NAN),
            ..FaultPolicy::default()
        })
        .is_err()
    );
    assert!(
        f.set_state(Vector2::new(f64::NAN, 0.0), Matrix2::identity())
            .is_err()
    );
}
