//! Corner cases of the estimators' arithmetic: a singular innovation covariance that rounding leaves a tiny
//! positive number, sigma-point weights that cancel away the digits of a covariance, and finite inputs too
//! large for the arithmetic of a step. Each is an error that leaves the filter as it was, never an accepted
//! update with a meaningless NIS.

use bgc_runtime::estimation::angle::AngleKalmanFilter;
use bgc_runtime::estimation::fusion::{ErrorVariance, WeightedFusion, minimum_variance_weights};
use bgc_runtime::estimation::health::FilterHealth;
use bgc_runtime::estimation::srukf::SquareRootUkf;
use bgc_runtime::estimation::ukf_augmented::AugmentedUkf;
use bgc_runtime::estimation::{
    EstimationError, KalmanFilter, LinearDiscreteModel, SigmaPoints, UnscentedKalmanFilter,
};
use nalgebra::{Matrix1, Matrix2, SMatrix, SVector, Vector1, Vector2};

type U0 = SVector<f64, 0>;

fn constant_velocity(x: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(x[0] + 0.1 * x[1], x[1])
}

/// `R = 0` and a measurement that does not depend on the state: `S` is exactly zero, but with `α < 1` the
/// weights' cancellation leaves rounding residue of order 1e-30 that the Cholesky factor accepted, which gave
/// NIS ≈ 1e19–1e29 and moved the state. Now `S` is compared with its own rounding estimate. (filterpy 1.4.5
/// with these points, `R = 0` and `hx = lambda x: np.array([2.0])` computes S = 8.1e-28 at α = 0.1, 1.3e-23
/// at 1e-2 and 5.4e-20 at 1e-3, and raises "Singular matrix" at α = 0.5.)
#[test]
fn a_state_independent_noise_free_measurement_is_a_singular_innovation() {
    let ignore_state = |_: &Vector2<f64>, _: &U0| Vector1::new(2.0);
    for alpha in [0.9, 0.5, 0.1, 1e-2, 1e-3] {
        let pts = SigmaPoints::<2, 5>::new(alpha, 2.0, 0.0).unwrap();
        let (q, r) = (Matrix2::identity() * 1e-3, Matrix1::zeros());
        let (x0, p0) = (Vector2::new(0.3, -0.7), Matrix2::new(1.0, 0.2, 0.2, 0.5));
        let mut ukf = UnscentedKalmanFilter::<2, 0, 1, 5>::new(pts, q, r, x0, p0).unwrap();
        let before = (*ukf.state(), *ukf.covariance());
        let out = ukf.update(&Vector1::new(2.5), &U0::zeros(), ignore_state);
        assert!(
            matches!(out, Err(EstimationError::SingularInnovation { .. })),
            "UKF alpha {alpha}: {out:?}"
        );
        assert_eq!((*ukf.state(), *ukf.covariance()), before);

        let mut sr = SquareRootUkf::<2, 0, 1, 5>::new(pts, q, r, x0, p0).unwrap();
        let before = (*sr.state(), sr.covariance());
        let out = sr.update(&Vector1::new(2.5), &U0::zeros(), ignore_state);
        assert!(
            matches!(out, Err(EstimationError::SingularInnovation { .. })),
            "SR-UKF alpha {alpha}: {out:?}"
        );
        assert_eq!((*sr.state(), sr.covariance()), before);

        // Non-additive noise: a measurement that ignores both the state and its noise.
        let apts = SigmaPoints::<4, 9>::new(alpha, 2.0, 0.0).unwrap();
        let mut aug = AugmentedUkf::<2, 0, 1, 1, 1, 4, 9>::new(
            apts,
            Matrix1::new(1e-3),
            Matrix1::new(1e-2),
            x0,
            p0,
        )
        .unwrap();
        let out = aug.update(&Vector1::new(2.5), &U0::zeros(), |_, _, _| {
            Vector1::new(2.0)
        });
        assert!(
            matches!(out, Err(EstimationError::SingularInnovation { .. })),
            "augmented UKF alpha {alpha}: {out:?}"
        );
    }
}

/// The same measurement with a little noise (`R = 1e-4`) is a valid update: the state cannot move (no
/// correlation with the measurement) and NIS = e²/R = 0.25/1e-4 = 2500 by hand.
#[test]
fn a_state_independent_noisy_measurement_is_still_accepted() {
    let pts = SigmaPoints::<2, 5>::new(1e-3, 2.0, 0.0).unwrap();
    let x0 = Vector2::new(0.3, -0.7);
    let mut ukf = UnscentedKalmanFilter::<2, 0, 1, 5>::new(
        pts,
        Matrix2::identity() * 1e-3,
        Matrix1::new(1e-4),
        x0,
        Matrix2::identity(),
    )
    .unwrap();
    let out = ukf
        .update(&Vector1::new(2.5), &U0::zeros(), |_, _| Vector1::new(2.0))
        .unwrap();
    match out {
        bgc_runtime::estimation::UpdateOutcome::Accepted { nis, .. } => {
            assert!((nis / 2500.0 - 1.0).abs() < 1e-9, "{nis}")
        }
        other => panic!("{other:?}"),
    }
    assert!((ukf.state() - x0).amax() < 1e-12);
}

/// A 2,000-step linear run of the UKF against the exact Kalman filter (for a linear model the UKF's moments
/// are exact, so the two must agree to rounding). With α = 1e-3 they do; with α = 1e-6 and 1e-7 the mean
/// weights (W₀ ≈ −1/α², Σ|W| ≈ 2/α²) cancel away the covariance's digits (errors of 9e-4 and 6.7 before) and
/// the first predict is refused with the reason; α = 1e-8, whose mean has no digit left at all (covariance
/// error 1.6e8 before), is refused when the weights are built.
///
/// filterpy 1.4.5 on the same run (same model, noise and initial estimate; its own random measurements)
/// shows that the loss is in the weights, not in this implementation: the worst relative covariance error is
/// `FILTERPY_ERROR_1E3` = 1.4e-10 at α = 1e-3 and 0.24 at α = 1e-6, and α = 1e-7 fails its Cholesky:
/// ```python
/// F = np.array([[1.0, 0.1], [0.0, 1.0]]); H = np.array([[1.0, 0.0]])
/// Q = np.diag([1e-4, 1e-3]); R = np.array([[1e-2]])
/// kf = KalmanFilter(2, 1); kf.F, kf.H, kf.Q, kf.R = F, H, Q, R; kf.x = np.array([1.0, 0.5]); kf.P = np.eye(2)
/// pts = MerweScaledSigmaPoints(2, alpha=alpha, beta=2.0, kappa=0.0)
/// ukf = UnscentedKalmanFilter(2, 1, 0.1, hx=lambda x: x[:1], fx=lambda x, dt: F @ x, points=pts)
/// ukf.Q, ukf.R = Q, R; ukf.x = np.array([1.0, 0.5]); ukf.P = np.eye(2); rng = np.random.default_rng(3)
/// for k in range(2000):
///     y = np.array([1.0 + 0.05 * k + rng.normal(0, 0.1)])
///     kf.predict(); kf.update(y); ukf.predict(); ukf.update(y)
///     worst = max(worst, np.abs(ukf.P - kf.P).max() / np.abs(kf.P).max())
/// ```
#[test]
fn sigma_weights_that_cancel_the_covariance_are_refused_with_the_reason() {
    let run = |alpha: f64| -> Result<f64, EstimationError> {
        let pts = SigmaPoints::<2, 5>::new(alpha, 2.0, 0.0)?;
        let q = Matrix2::new(1e-4, 0.0, 0.0, 1e-3);
        let r = Matrix1::new(1e-2);
        let (x0, p0) = (Vector2::new(1.0, 0.5), Matrix2::identity());
        let model = LinearDiscreteModel {
            a: Matrix2::new(1.0, 0.1, 0.0, 1.0),
            b: SMatrix::<f64, 2, 0>::zeros(),
            c: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
            d: SMatrix::<f64, 1, 0>::zeros(),
        };
        let mut kf = KalmanFilter::new(model, q, r, x0, p0)?;
        let mut ukf = UnscentedKalmanFilter::<2, 0, 1, 5>::new(pts, q, r, x0, p0)?;
        let mut rng = bgc_runtime::noise::Rng::new(3);
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let y = Vector1::new(1.0 + 0.05 * k as f64 + rng.gaussian(0.0, 0.1));
            kf.predict(&U0::zeros())?;
            kf.update(&y, &U0::zeros())?;
            ukf.predict(&U0::zeros(), |x, _| constant_velocity(x))?;
            ukf.update(&y, &U0::zeros(), |x, _| Vector1::new(x[0]))?;
            let err = (ukf.covariance() - kf.covariance()).amax() / kf.covariance().amax();
            worst = worst.max(err);
        }
        Ok(worst)
    };
    const FILTERPY_ERROR_1E3: f64 = 1.3846131774825247e-10;
    let worst = run(1e-3).unwrap();
    assert!(
        worst < 100.0 * FILTERPY_ERROR_1E3,
        "alpha 1e-3: relative covariance error {worst:e}"
    );
    for alpha in [1e-6, 1e-7] {
        match run(alpha) {
            Err(EstimationError::PrecisionLoss {
                relative_error,
                amplification,
                ..
            }) => {
                assert!(relative_error > 1e-4);
                // Σ|W⁽ᵐ⁾| = |λ|/(L+λ) + 2L/(2(L+λ)) = (2 − α²)/α² for κ = 0, L = 2. The weights themselves
                // are computed as filterpy does, from λ = α²L − L, which costs 2ε/α² of relative accuracy.
                let expected = (2.0 - alpha * alpha) / (alpha * alpha);
                assert!(
                    (amplification / expected - 1.0).abs() < 1e-3,
                    "{amplification} vs {expected}"
                );
            }
            other => panic!("alpha {alpha}: {other:?}"),
        }
    }
    assert!(matches!(
        SigmaPoints::<2, 5>::new(1e-8, 2.0, 0.0),
        Err(EstimationError::InvalidSetting { name: "alpha", .. })
    ));
}

/// Finite inputs whose arithmetic overflows: a gyro rate of 1e308 (before: accepted with NIS = inf and an
/// angle of 2.9e304), a measurement of 1e308 on a state of −1e308 (innovation inf), a state pushed past
/// f64::MAX by its input. Each is an error and the filter keeps its estimate.
#[test]
fn finite_inputs_that_overflow_a_step_are_errors_and_change_nothing() {
    let mut angle =
        AngleKalmanFilter::new(0.01, 1e-6, 1e-8, 1e-3, 0.2, 0.0, Matrix2::identity()).unwrap();
    for rate in [1e308, -1e308, 1e200] {
        let out = angle.step(rate, 0.2);
        assert!(
            matches!(out, Err(EstimationError::Overflow { .. })),
            "{rate}: {out:?}"
        );
        assert_eq!((angle.angle(), angle.bias()), (0.2, 0.0));
    }
    assert!(angle.step(0.0, 0.2).unwrap().is_accepted());

    let model = LinearDiscreteModel {
        a: Matrix1::new(1.0),
        b: Matrix1::new(1.0),
        c: Matrix1::new(1.0),
        d: Matrix1::zeros(),
    };
    let mut kf = KalmanFilter::new(
        model,
        Matrix1::new(1.0),
        Matrix1::new(1.0),
        Vector1::new(-1e308),
        Matrix1::new(1.0),
    )
    .unwrap();
    let u = Vector1::new(0.0);
    assert!(matches!(
        kf.update(&Vector1::new(1e308), &u),
        Err(EstimationError::Overflow { .. })
    ));
    assert!(matches!(
        kf.predict(&Vector1::new(-1e308)),
        Err(EstimationError::Overflow { .. })
    ));
    assert_eq!(kf.state()[0], -1e308);

    // The UKF and SR-UKF: a measurement of 1e308 whose squared innovation overflows the NIS.
    let pts = SigmaPoints::<1, 3>::new(1.0, 2.0, 0.0).unwrap();
    let one = Matrix1::new(1.0);
    let mut ukf =
        UnscentedKalmanFilter::<1, 0, 1, 3>::new(pts, one, one, Vector1::new(0.5), one).unwrap();
    let out = ukf.update(&Vector1::new(1e308), &U0::zeros(), |x, _| *x);
    assert!(
        matches!(out, Err(EstimationError::Overflow { .. })),
        "{out:?}"
    );
    assert_eq!(ukf.state()[0], 0.5);
    let mut sr = SquareRootUkf::<1, 0, 1, 3>::new(pts, one, one, Vector1::new(0.5), one).unwrap();
    let out = sr.update(&Vector1::new(1e308), &U0::zeros(), |x, _| *x);
    assert!(
        matches!(out, Err(EstimationError::Overflow { .. })),
        "{out:?}"
    );
    assert_eq!(sr.state()[0], 0.5);
}

/// Minimum-variance fusion at the edges of the f64 range, against Eq. 27 by hand: variances (1e-300, 4e-300)
/// give W = (0.8, 0.2) and σ² = 0.8e-300 (before: 1/σ² was fine, but (2e-308, 2e-308) overflowed the sum of
/// reciprocals); readings of 1e308 fuse to 1e308 (before: inf); subnormal variances (1e-310) are refused
/// (before: NaN with weights (0, 0)).
#[test]
fn fusion_of_extreme_variances_and_readings() {
    let w = minimum_variance_weights(&Vector2::new(1e-300, 4e-300)).unwrap();
    assert!((w - Vector2::new(0.8, 0.2)).amax() < 1e-15, "{w}");
    let w = minimum_variance_weights(&nalgebra::Vector5::repeat(2.3e-308)).unwrap();
    assert!(
        (w.sum() - 1.0).abs() < 1e-15 && (w[0] - 0.2).abs() < 1e-15,
        "{w}"
    );

    let f = WeightedFusion::new(Vector2::new(1e-300, 4e-300)).unwrap();
    let r = f.fuse(&Vector2::new(1e308, 1e308)).unwrap();
    assert!((r.value / 1e308 - 1.0).abs() < 1e-15, "{}", r.value);
    assert!((r.variance / 0.8e-300 - 1.0).abs() < 1e-15);
    let r = f.fuse(&Vector2::new(1.7e308, -1.7e308)).unwrap();
    assert!((r.value / (0.6 * 1.7e308) - 1.0).abs() < 1e-15);

    for bad in [1e-310, 5e-324, 0.0, -1.0, f64::INFINITY, f64::NAN] {
        assert!(
            matches!(
                WeightedFusion::new(Vector2::new(bad, 1.0)),
                Err(EstimationError::InvalidSetting { .. })
            ),
            "{bad}"
        );
    }

    // Eq. 28 with an error whose square overflows: the sample is skipped and reported.
    let mut ev = ErrorVariance::new();
    assert!(ev.push(1.0, 0.0) && ev.push(-1.0, 0.0));
    assert!(!ev.push(1e200, 0.0));
    assert_eq!((ev.count(), ev.variance()), (2, Some(2.0)));
}

/// The health monitor refuses an innovation whose square overflows its sums (before: the statistics became
/// inf and stayed so).
#[test]
fn health_statistics_refuse_overflowing_values() {
    let mut h = FilterHealth::<1, 1, 2>::new();
    h.record_innovation(&Vector1::new(0.5), &Matrix1::new(1.0))
        .unwrap();
    assert!(
        h.record_innovation(&Vector1::new(1e200), &Matrix1::new(1.0))
            .is_err()
    );
    assert!(
        h.record_state_error(&Vector1::new(1e308), &Matrix1::new(1.0))
            .is_ok()
    );
    assert!(
        h.record_state_error(&Vector1::new(1e308), &Matrix1::new(1.0))
            .is_err()
    );
    assert_eq!(h.innovation_count(), 1);
    assert_eq!(h.mean_nis(), Some(0.25));
    assert_eq!(h.state_error_mean()[0], 1e308);
}

proptest::proptest! {
    /// Fusion over the whole range of normal variances and finite readings: weights sum to one, the fused
    /// value lies between the smallest and largest reading (a convex combination), the variance is below the
    /// smallest sensor variance.
    #[test]
    fn fusion_is_a_convex_combination_over_the_f64_range(
        v_exp in proptest::array::uniform3(-307.0f64..307.0),
        z_exp in proptest::array::uniform3(-300.0f64..308.0),
        signs in proptest::array::uniform3(proptest::bool::ANY),
    ) {
        let v = nalgebra::Vector3::from_fn(|i, _| 10f64.powf(v_exp[i]));
        let z = nalgebra::Vector3::from_fn(|i, _| {
            let m = 10f64.powf(z_exp[i]).min(f64::MAX / 2.0);
            if signs[i] { m } else { -m }
        });
        let w = minimum_variance_weights(&v).unwrap();
        proptest::prop_assert!((w.sum() - 1.0).abs() < 1e-14);
        let r = WeightedFusion::new(v).unwrap().fuse(&z).unwrap();
        let (lo, hi) = (z.min(), z.max());
        let slack = 1e-14 * lo.abs().max(hi.abs());
        proptest::prop_assert!(r.value >= lo - slack && r.value <= hi + slack, "{} not in [{lo}, {hi}]", r.value);
        proptest::prop_assert!(r.variance <= v.min() * (1.0 + 1e-15));
    }
}

/// An undetectable unstable mode (`A = diag(1.1, 0.5)`, `C = [0 1]`): the Riccati recursion diverges, its `P`
/// growing by 1.21 per step. The relative change was measured in Frobenius norms, and the norm of a `P` with
/// entries of 1e154 overflows to infinity, so the change read as 0 and the recursion returned `Ok` with
/// `P₀₀ = 1.4e154` and a gain that ignores the unstable state. The pair is now refused before the recursion,
/// naming the mode.
#[test]
fn steady_state_gain_of_an_undetectable_mode_is_an_error() {
    use bgc_runtime::estimation::kalman::steady_state_gain;
    let a = Matrix2::new(1.1, 0.0, 0.0, 0.5);
    let c = nalgebra::Matrix1x2::new(0.0, 1.0);
    let q = Matrix2::identity() * 1e-3;
    let r = Matrix1::new(1e-2);
    for max_iterations in [100, 10_000, 100_000] {
        let got = steady_state_gain(&a, &c, &q, &r, 1e-12, max_iterations);
        assert!(
            got == Err(EstimationError::NotDetectable { re: 1.1, im: 0.0 }),
            "{max_iterations}: {got:?}"
        );
    }
}

/// The same measure of change on a detectable problem in large units (`Q`, `R` scaled by 1e160, so `P` is too):
/// the Frobenius norm of `P` overflowed while that of the change did not, so the change read as 0 long before
/// convergence and the recursion stopped early, its gain and `P` off by more than 1e-10 relative. The largest
/// entries do not overflow: `P` is 1e160 times that of the unit problem and the gain is the same.
#[test]
fn steady_state_gain_in_large_units_converges_to_the_scaled_solution() {
    use bgc_runtime::estimation::kalman::steady_state_gain;
    let a = Matrix2::new(1.0, 0.1, 0.0, 1.0);
    let c = nalgebra::Matrix1x2::new(1.0, 0.0);
    let (q, r) = (Matrix2::identity() * 1e-3, Matrix1::new(1e-2));
    let unit = steady_state_gain(&a, &c, &q, &r, 1e-13, 10_000).unwrap();
    let big = steady_state_gain(&a, &c, &(q * 1e160), &(r * 1e160), 1e-13, 10_000).unwrap();
    let gain_error = (big.filter_gain - unit.filter_gain).amax() / unit.filter_gain.amax();
    let p_error = (big.predicted_covariance / 1e160 - unit.predicted_covariance).amax()
        / unit.predicted_covariance.amax();
    assert!(
        gain_error < 1e-10 && p_error < 1e-10,
        "{gain_error:e} {p_error:e}"
    );
}
