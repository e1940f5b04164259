//! The back-support bench record (`bgc_workspace::back_support::identification::bench_record`): the lab test's
//! held chirp command with the trunk held, and measurements whose noise stays within the paper's bounds.

use bgc_workspace::back_support::identification::{
    BenchConfig, ENCODER_BOUND, TORQUE_SENSOR_BOUND, bench_record,
};

#[test]
fn bench_record_holds_the_chirp_and_bounded_noise() {
    let cfg = BenchConfig::paper();
    let a = bench_record(&cfg).expect("the bench simulates");
    assert_eq!(a.times.len(), cfg.samples + 1);
    assert_eq!(a.outputs, [0, 1]);
    // The trunk is held and the torque command is the chirp at each sample time (f0 t + ½ rate t²).
    let duration = cfg.sample_time * cfg.samples as f64;
    for (t, u) in a.times.iter().zip(&a.inputs).take(cfg.samples) {
        let phase = cfg.f0 * t + 0.5 * (cfg.f1 - cfg.f0) / duration * t * t;
        let want = cfg.amplitude * (2.0 * std::f64::consts::PI * phase).sin();
        assert!((u[0] - want).abs() < 1e-12 && u[1] == 0.0, "t = {t}: {u:?}");
    }
    // Another noise seed changes the measurements by at most twice each bound.
    let other = bench_record(&BenchConfig {
        seed: cfg.seed + 1,
        ..cfg.clone()
    })
    .expect("simulates");
    let mut largest = [0.0f64; 2];
    for (x, y) in a.measured.iter().zip(&other.measured) {
        for c in 0..2 {
            largest[c] = largest[c].max((x[c] - y[c]).abs());
        }
    }
    assert!(
        largest[0] <= 2.0 * ENCODER_BOUND && largest[1] <= 2.0 * TORQUE_SENSOR_BOUND,
        "{largest:?}"
    );
    // Uniform noise fills most of that range over a thousand samples.
    assert!(
        largest[0] > ENCODER_BOUND && largest[1] > TORQUE_SENSOR_BOUND,
        "{largest:?}"
    );
}
