//! Level crossings and peak gain against closed forms.

use bgc_runtime::analysis::{first_level_crossing, peak_gain, static_gain};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

fn siso(a: &[f64], b: &[f64], c: &[f64], d: f64) -> StateSpace {
    let n = b.len();
    StateSpace::new(
        DMatrix::from_row_slice(n, n, a),
        DMatrix::from_column_slice(n, 1, b),
        DMatrix::from_row_slice(1, n, c),
        DMatrix::from_element(1, 1, d),
    )
    .unwrap()
}

#[test]
fn sensitivity_of_an_integrator_loop_rises_through_minus_3_db() {
    // L = k/s, S = s/(s + k) = 1 − k/(s + k); |S| = ω/√(ω² + k²) = c at ω = k c / √(1 − c²), c = 10^(−3/20).
    let k = 5.0;
    let s = siso(&[-k], &[1.0], &[-k], 1.0);
    let c = 10f64.powf(-3.0 / 20.0);
    let expected = k * c / (1.0 - c * c).sqrt();
    let x = first_level_crossing(&s, -3.0).unwrap().unwrap();
    assert!(x.rising);
    assert!(
        (x.frequency - expected).abs() < 1e-9 * expected,
        "{x:?} vs {expected}"
    );
}

#[test]
fn lag_falls_through_minus_20_db_at_sqrt_99() {
    // |1/(jω + 1)| = 0.1 at ω = √99.
    let lag = siso(&[-1.0], &[1.0], &[1.0], 0.0);
    let x = first_level_crossing(&lag, -20.0).unwrap().unwrap();
    assert!(!x.rising);
    assert!((x.frequency - 99f64.sqrt()).abs() < 1e-9);
    // A static gain of 1 never crosses −20 dB.
    let one = static_gain(DMatrix::from_element(1, 1, 1.0), None).unwrap();
    assert_eq!(first_level_crossing(&one, -20.0).unwrap(), None);
}

#[test]
fn resonance_peak_matches_closed_form() {
    // ω_n² / (s² + 2ζω_n s + ω_n²): peak 1 / (2ζ√(1 − ζ²)) at ω_n √(1 − 2ζ²).
    let (wn, zeta) = (3.0, 0.1);
    let sys = siso(
        &[0.0, 1.0, -wn * wn, -2.0 * zeta * wn],
        &[0.0, 1.0],
        &[wn * wn, 0.0],
        0.0,
    );
    let (gain, freq) = peak_gain(&sys).unwrap();
    let expected_gain = 1.0 / (2.0 * zeta * (1.0 - zeta * zeta).sqrt());
    let expected_freq = wn * (1.0 - 2.0 * zeta * zeta).sqrt();
    assert!(
        (gain - expected_gain).abs() < 1e-10 * expected_gain,
        "{gain}"
    );
    assert!((freq - expected_freq).abs() < 1e-5, "{freq}");
    // A lag peaks at DC.
    let (g0, w0) = peak_gain(&siso(&[-2.0], &[1.0], &[4.0], 0.0)).unwrap();
    assert_eq!((g0, w0), (2.0, 0.0));
}
