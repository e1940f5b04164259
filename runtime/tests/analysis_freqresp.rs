//! Frequency response and Bode data against closed forms.

use bgc_runtime::analysis::{
    AnalysisError, C64, bode, frequency_response, logspace, siso_response,
};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

fn first_order_lag(gain: f64, tau: f64) -> StateSpace {
    // ẋ = −x/τ + u/τ, y = K x  →  K / (τ s + 1)
    StateSpace::new(
        DMatrix::from_element(1, 1, -1.0 / tau),
        DMatrix::from_element(1, 1, 1.0 / tau),
        DMatrix::from_element(1, 1, gain),
        DMatrix::zeros(1, 1),
    )
    .unwrap()
}

#[test]
fn bode_of_first_order_lag_matches_closed_form() {
    let (k, tau) = (4.0, 0.05);
    let grid = logspace(0.1, 1e4, 301).unwrap();
    let b = bode(&first_order_lag(k, tau), 0, 0, &grid).unwrap();
    for (i, w) in grid.iter().enumerate() {
        let wt = w * tau;
        let mag = 20.0 * (k / (1.0 + wt * wt).sqrt()).log10();
        let phase = -wt.atan().to_degrees();
        assert!(
            (b.magnitude_db[i] - mag).abs() < 1e-10,
            "{} {}",
            b.magnitude_db[i],
            mag
        );
        assert!((b.phase_deg[i] - phase).abs() < 1e-10);
    }
    // The corner: −3.0103 dB and −45° at ω = 1/τ.
    let corner = bode(&first_order_lag(1.0, tau), 0, 0, &[1.0 / tau]).unwrap();
    assert!((corner.magnitude_db[0] + 10.0 * 2f64.log10()).abs() < 1e-12);
    assert!((corner.phase_deg[0] + 45.0).abs() < 1e-12);
}

#[test]
fn phase_of_triple_lag_is_unwrapped_past_minus_180() {
    // 1/(s+1)^3 as a chain: phase −3 atan(ω), reaching −270° without a jump.
    let a = DMatrix::from_row_slice(3, 3, &[-1.0, 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, -1.0]);
    let b = DMatrix::from_column_slice(3, 1, &[1.0, 0.0, 0.0]);
    let c = DMatrix::from_row_slice(1, 3, &[0.0, 0.0, 1.0]);
    let sys = StateSpace::new(a, b, c, DMatrix::zeros(1, 1)).unwrap();
    let grid = logspace(1e-2, 1e3, 200).unwrap();
    let bd = bode(&sys, 0, 0, &grid).unwrap();
    for (w, p) in grid.iter().zip(&bd.phase_deg) {
        assert!((p + 3.0 * w.atan().to_degrees()).abs() < 1e-9, "ω={w}: {p}");
    }
    assert!(*bd.phase_deg.last().unwrap() < -260.0);
}

#[test]
fn discrete_first_order_response_matches_closed_form() {
    // x[k+1] = a x[k] + (1−a) u[k], y = x  →  G(z) = (1−a)/(z − a), z = e^{jωT}.
    let (a, dt) = (0.8, 0.01);
    let sys = StateSpace::new_discrete(
        DMatrix::from_element(1, 1, a),
        DMatrix::from_element(1, 1, 1.0 - a),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
        dt,
    )
    .unwrap();
    for &w in &[0.0, 1.0, 50.0, 314.0] {
        let z = C64::from_polar(1.0, w * dt);
        let expected = C64::new(1.0 - a, 0.0) / (z - a);
        let got = siso_response(&sys, w).unwrap();
        assert!((got - expected).norm() < 1e-14, "ω={w}");
    }
    assert!(matches!(
        siso_response(&sys, 400.0),
        Err(AnalysisError::AboveNyquist { .. })
    ));
}

#[test]
fn mimo_response_has_one_matrix_per_frequency() {
    // Two decoupled lags 1/(s+1) and 3/(s+2): G(j) = diag(1/(1+j), 3/(2+j)).
    let sys = StateSpace::new(
        DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 0.0, -2.0]),
        DMatrix::identity(2, 2),
        DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 3.0]),
        DMatrix::zeros(2, 2),
    )
    .unwrap();
    let g = frequency_response(&sys, &[1.0]).unwrap();
    let j = C64::new(0.0, 1.0);
    assert!((g[0][(0, 0)] - C64::new(1.0, 0.0) / (j + 1.0)).norm() < 1e-15);
    assert!((g[0][(1, 1)] - C64::new(3.0, 0.0) / (j + 2.0)).norm() < 1e-15);
    assert_eq!(g[0][(0, 1)], C64::new(0.0, 0.0));
}

#[test]
fn pole_on_the_axis_and_bad_input_are_errors() {
    let integrator = StateSpace::new(
        DMatrix::zeros(1, 1),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
    )
    .unwrap();
    assert_eq!(
        siso_response(&integrator, 0.0),
        Err(AnalysisError::PoleOnContour { omega: 0.0 })
    );
    assert!(matches!(
        siso_response(&integrator, f64::NAN),
        Err(AnalysisError::BadFrequency { .. })
    ));
    assert!(matches!(
        bode(&integrator, 1, 0, &[1.0]),
        Err(AnalysisError::NoSuchChannel { .. })
    ));
    assert!(matches!(
        logspace(1.0, 0.5, 10),
        Err(AnalysisError::BadGrid { .. })
    ));
}
