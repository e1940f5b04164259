//! A Kalman filter that matches the system it observes must pass the health checks of paper 000, Table 7:
//! zero-mean, white innovations with mean NIS equal to the number of measurements, and state errors inside the
//! 1σ bound on about 68 % of the steps. A mistuned filter must fail them.

use bgc_runtime::estimation::health::FilterHealth;
use bgc_runtime::estimation::{KalmanFilter, LinearDiscreteModel};
use bgc_runtime::noise::Rng;
use nalgebra::{Matrix2, SMatrix, Vector1, Vector2};

const STEPS: usize = 20_000;

fn run(r_filter: f64) -> FilterHealth<2, 2, 5> {
    let model = LinearDiscreteModel {
        a: Matrix2::new(1.0, 0.1, -0.05, 0.98),
        b: SMatrix::<f64, 2, 1>::new(0.0, 0.1),
        c: Matrix2::identity(),
        d: SMatrix::<f64, 2, 1>::zeros(),
    };
    let (qs, rs) = (0.05, 0.2); // true noise standard deviations
    let q = Matrix2::identity() * (qs * qs);
    let mut kf = KalmanFilter::new(
        model,
        q,
        Matrix2::identity() * r_filter,
        Vector2::zeros(),
        Matrix2::identity(),
    )
    .unwrap();
    let mut rng = Rng::new(2024);
    let mut x = Vector2::new(0.0, 0.0);
    let mut health = FilterHealth::new();
    for k in 0..STEPS {
        let u = Vector1::new((0.01 * k as f64).sin());
        x = model.a * x + model.b * u + Vector2::new(rng.gaussian(0.0, qs), rng.gaussian(0.0, qs));
        let y = x + Vector2::new(rng.gaussian(0.0, rs), rng.gaussian(0.0, rs));
        kf.predict(&u).unwrap();
        kf.update(&y, &u).unwrap();
        if k >= 100 {
            health
                .record_innovation(kf.innovation(), kf.innovation_covariance())
                .unwrap();
            health
                .record_state_error(&(x - kf.state()), kf.covariance())
                .unwrap();
        }
    }
    health
}

#[test]
fn consistent_filter_passes_the_health_checks() {
    let h = run(0.2 * 0.2).report();
    // NIS ~ χ²(2): mean 2, variance 4, so the mean over n steps has standard error 2/√n ≈ 0.014.
    let nis = h.mean_nis.unwrap();
    assert!((nis - 2.0).abs() < 0.06, "mean NIS {nis}");
    // Innovation standard deviation is about 0.22, so the mean's standard error is about 0.0016.
    assert!(h.innovation_mean.amax() < 0.007, "{}", h.innovation_mean);
    // White innovations: each ρ(l) has standard error 1/√n ≈ 0.007.
    assert!(
        h.mean_innovation_autocorrelation.amax() < 0.02,
        "{}",
        h.mean_innovation_autocorrelation
    );
    // Gaussian errors exceed 1σ with probability 0.3173.
    for f in h.fraction_outside_one_sigma.iter() {
        assert!((f - 0.3173).abs() < 0.02, "fraction outside 1σ {f}");
    }
}

#[test]
fn filter_that_trusts_its_sensor_too_much_fails_them() {
    // R assumed 100 times too small: the NIS is far above 2 and the errors leave the (too narrow) bounds.
    let h = run(0.02 * 0.02).report();
    assert!(h.mean_nis.unwrap() > 20.0, "mean NIS {:?}", h.mean_nis);
    for f in h.fraction_outside_one_sigma.iter() {
        assert!(*f > 0.6, "fraction outside 1σ {f}");
    }
}
