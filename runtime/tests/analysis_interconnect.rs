//! Series, parallel, feedback and append against hand-computed transfer functions, and the loop broken at
//! the plant input of an observer-based controller against python-control.

use bgc_runtime::analysis::{
    AnalysisError, C64, FeedbackSign, append, feedback, loop_at_plant_input, observer_controller,
    parallel, series, siso_response, stability_margins, static_gain,
};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

/// k / (s + p), or with feedthrough `d`: k/(s+p) + d.
fn lag(k: f64, p: f64, d: f64) -> StateSpace {
    StateSpace::new(
        DMatrix::from_element(1, 1, -p),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::from_element(1, 1, k),
        DMatrix::from_element(1, 1, d),
    )
    .unwrap()
}

fn at(sys: &StateSpace, w: f64) -> C64 {
    siso_response(sys, w).unwrap()
}

const S: C64 = C64::new(0.0, 0.7);
const W: f64 = 0.7;

#[test]
fn series_is_the_product() {
    // 1/(s+1) then 2/(s+3): 2 / ((s+1)(s+3)).
    let g = series(&lag(1.0, 1.0, 0.0), &lag(2.0, 3.0, 0.0)).unwrap();
    let expected = C64::new(2.0, 0.0) / ((S + 1.0) * (S + 3.0));
    assert!((at(&g, W) - expected).norm() < 1e-15);
    assert_eq!(g.n_states(), 2);
}

#[test]
fn parallel_is_the_sum() {
    // 1/(s+1) + (2/(s+3) + 0.5).
    let g = parallel(&lag(1.0, 1.0, 0.0), &lag(2.0, 3.0, 0.5)).unwrap();
    let expected = C64::new(1.0, 0.0) / (S + 1.0) + C64::new(2.0, 0.0) / (S + 3.0) + 0.5;
    assert!((at(&g, W) - expected).norm() < 1e-15);
}

#[test]
fn negative_feedback_with_feedthrough() {
    // G = 1/(s+1) + 1 = (s+2)/(s+1), H = 0.5: G/(1 + 0.5 G) = (s+2) / (1.5 s + 2).
    let g = feedback(
        &lag(1.0, 1.0, 1.0),
        &static_gain(DMatrix::from_element(1, 1, 0.5), None).unwrap(),
        FeedbackSign::Negative,
    )
    .unwrap();
    let expected = (S + 2.0) / (S * 1.5 + 2.0);
    assert!((at(&g, W) - expected).norm() < 1e-15);
    // The closed-loop pole is at −4/3.
    assert!((g.a()[(0, 0)] + 4.0 / 3.0).abs() < 1e-15);
}

#[test]
fn positive_feedback_with_dynamics_in_the_return_path() {
    // G = 1/s, H = 3/(s+4), positive: G/(1 − G H) = (s+4) / (s(s+4) − 3).
    let integrator = lag(1.0, 0.0, 0.0);
    let g = feedback(&integrator, &lag(3.0, 4.0, 0.0), FeedbackSign::Positive).unwrap();
    let expected = (S + 4.0) / (S * (S + 4.0) - 3.0);
    assert!((at(&g, W) - expected).norm() < 1e-15);
}

#[test]
fn ill_posed_feedback_is_refused() {
    let one = static_gain(DMatrix::from_element(1, 1, 1.0), None).unwrap();
    assert_eq!(
        feedback(&one, &one, FeedbackSign::Positive),
        Err(AnalysisError::IllPosedFeedback)
    );
}

#[test]
fn append_is_block_diagonal_and_timebases_must_agree() {
    let g = append(&[&lag(1.0, 1.0, 0.0), &lag(2.0, 3.0, 0.0)]).unwrap();
    let r = bgc_runtime::analysis::frequency_response(&g, &[W]).unwrap();
    assert!((r[0][(0, 0)] - C64::new(1.0, 0.0) / (S + 1.0)).norm() < 1e-15);
    assert!((r[0][(1, 1)] - C64::new(2.0, 0.0) / (S + 3.0)).norm() < 1e-15);
    assert_eq!(r[0][(0, 1)], C64::new(0.0, 0.0));
    let discrete = static_gain(DMatrix::from_element(1, 1, 1.0), Some(0.1)).unwrap();
    assert!(matches!(
        series(&lag(1.0, 1.0, 0.0), &discrete),
        Err(AnalysisError::TimebaseMismatch { .. })
    ));
    assert!(matches!(
        series(&g, &lag(1.0, 1.0, 0.0)),
        Err(AnalysisError::SizeMismatch { .. })
    ));
}

fn double_integrator() -> (StateSpace, DMatrix<f64>, DMatrix<f64>) {
    let plant = StateSpace::new(
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        DMatrix::from_column_slice(2, 1, &[0.0, 1.0]),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        DMatrix::zeros(1, 1),
    )
    .unwrap();
    let k = DMatrix::from_row_slice(1, 2, &[1.0, 1.5]);
    let l = DMatrix::from_column_slice(2, 1, &[3.0, 2.0]);
    (plant, k, l)
}

#[test]
fn observer_loop_obeys_the_separation_principle() {
    // Closed loop poles = eig(A − BK) ∪ eig(A − LC):
    // s² + 1.5 s + 1 → −0.75 ± 0.6614j;  s² + 3 s + 2 → −1, −2.
    let (plant, k, l) = double_integrator();
    let ctrl = observer_controller(&plant, &k, &l).unwrap();
    let closed = feedback(&plant, &ctrl, FeedbackSign::Positive).unwrap();
    let mut poles: Vec<C64> = closed.a().complex_eigenvalues().iter().copied().collect();
    poles.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    let im = (1.0f64 - 0.75 * 0.75).sqrt();
    let expected = [
        C64::new(-2.0, 0.0),
        C64::new(-1.0, 0.0),
        C64::new(-0.75, -im),
        C64::new(-0.75, im),
    ];
    for (p, e) in poles.iter().zip(&expected) {
        assert!((p - e).norm() < 1e-9, "{p} vs {e}");
    }
}

#[test]
fn loop_at_plant_input_margins_match_python_control() {
    // import control, numpy as np
    // A = np.array([[0, 1], [0, 0.]]); B = np.array([[0], [1.]]); C = np.array([[1, 0.]])
    // K = np.array([[1, 1.5]]); Lg = np.array([[3], [2.]])
    // P = control.ss(A, B, C, 0); Ctl = control.ss(A - B@K - Lg@C, Lg, K, 0)
    // control.stability_margins(control.series(P, Ctl))
    // -> (4.499999999999892, 39.3585264200122, 0.5775733160137034,
    //     2.449489742783143, 0.8319468468044967, 1.2059770900000326)
    // (L_in = (6 s + 2) / (s^4 + 4.5 s^3 + 7.5 s^2))
    let (plant, k, l) = double_integrator();
    let ctrl = observer_controller(&plant, &k, &l).unwrap();
    let loop_in = loop_at_plant_input(&plant, &ctrl).unwrap();
    let expected = (S * 6.0 + 2.0) / (S.powu(4) + S.powu(3) * 4.5 + S.powu(2) * 7.5);
    assert!((at(&loop_in, W) - expected).norm() < 1e-13);
    let m = stability_margins(&loop_in).unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(m.gain_margin, 4.499999999999892) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 39.3585264200122) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.5775733160137034) < 1e-6);
    assert!(rel(m.phase_crossover.unwrap(), 2.449489742783143) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 0.8319468468044967) < 1e-6);
}
