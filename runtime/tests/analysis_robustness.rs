//! Models whose entries are finite but whose products overflow, and hostile grid and phase inputs: every
//! analysis entry point answers with an error (or a finite number), never with `inf`, a panic or a hang.

use bgc_runtime::analysis::{
    AnalysisError, bandwidth, bode, dc_gain, frequency_response, logspace, peak_gain,
    siso_response, stability_margins, unwrap_degrees,
};
use bgc_runtime::statespace::StateSpace;
use nalgebra::dmatrix;

/// `G(s) = c b / (s + 1)` with `b = c = 1e300`: every entry is finite, `|G| = 1e600 / |jω + 1|` is not.
fn overflowing_lag() -> StateSpace {
    StateSpace::new(
        dmatrix![-1.0],
        dmatrix![1e300],
        dmatrix![1e300],
        dmatrix![0.0],
    )
    .unwrap()
}

#[test]
fn an_overflowing_response_is_an_error_at_every_entry_point() {
    let sys = overflowing_lag();
    let overflow = |r: Result<(), AnalysisError>| matches!(r, Err(AnalysisError::Overflow { .. }));
    assert!(overflow(frequency_response(&sys, &[1.0]).map(drop)));
    assert!(overflow(siso_response(&sys, 1.0).map(drop)));
    assert!(overflow(dc_gain(&sys).map(drop)));
    assert!(overflow(bode(&sys, 0, 0, &[0.1, 1.0]).map(drop)));
    assert!(overflow(stability_margins(&sys).map(drop)));
    assert!(overflow(peak_gain(&sys).map(drop)));
    assert!(overflow(bandwidth(&sys, -3.0).map(drop)));
}

/// The same loop scaled down to `b = c = 1e150` is representable: `|G(j1)| = 1e300 / √2` exactly as the
/// hand formula gives, so the check does not refuse large but finite responses.
#[test]
fn a_large_but_finite_response_is_still_computed() {
    let sys = StateSpace::new(
        dmatrix![-1.0],
        dmatrix![1e150],
        dmatrix![1e150],
        dmatrix![0.0],
    )
    .unwrap();
    let g = siso_response(&sys, 1.0).unwrap();
    assert!(
        (g.norm() / (1e300 / 2f64.sqrt()) - 1.0).abs() < 1e-14,
        "{g}"
    );
}

/// A phase sequence with a jump far beyond 360° used to loop forever subtracting 360 from a number that
/// 360 cannot change; an infinite phase did the same.
#[test]
fn unwrapping_huge_or_infinite_phases_terminates() {
    let out = unwrap_degrees(&[0.0, 1e300, 10.0]);
    assert_eq!(out.len(), 3);
    assert!(out.iter().all(|p| p.is_finite()));
    let out = unwrap_degrees(&[10.0, f64::INFINITY, 370.0, f64::NAN, 20.0]);
    assert_eq!(out[1], f64::INFINITY);
    assert!(out[3].is_nan());
    // The finite phases unwrap around the non-finite ones: 370 → 10, then 20 stays.
    assert_eq!([out[0], out[2], out[4]], [10.0, 10.0, 20.0]);
    // Ordinary unwrapping is unchanged: the jump of exactly 180° is kept, 181° is folded.
    assert_eq!(
        unwrap_degrees(&[170.0, -170.0, 10.0, 190.0, 371.0, -900.0]),
        vec![170.0, 190.0, 370.0, 550.0, 371.0, 540.0]
    );
}

#[test]
fn a_grid_too_long_to_allocate_is_refused() {
    for points in [usize::MAX, 1usize << 40, 10_000_001] {
        assert!(matches!(
            logspace(1.0, 10.0, points),
            Err(AnalysisError::BadGrid { .. })
        ));
    }
    assert_eq!(logspace(1.0, 100.0, 3).unwrap(), vec![1.0, 10.0, 100.0]);
}

proptest::proptest! {
    /// Any finite phases, however large: one output per input, and consecutive unwrapped phases differ by at
    /// most 180° plus the rounding of the offset.
    #[test]
    fn unwrapping_any_finite_phases_leaves_no_jump_above_180(
        phase in proptest::collection::vec(-1e12f64..1e12, 1..50),
    ) {
        let out = unwrap_degrees(&phase);
        proptest::prop_assert_eq!(out.len(), phase.len());
        for pair in out.windows(2) {
            let slack = 1e-3 * (1.0 + pair[0].abs().max(pair[1].abs()) * 1e-12);
            proptest::prop_assert!((pair[1] - pair[0]).abs() <= 180.0 + slack, "{:?}", pair);
        }
    }
}

/// A pole at `s = 0` (`z = 1`) makes the peak gain infinite. It lies below the search grid, whose points are all
/// finite, and `peak_gain` of `1/s` returned `Ok((1000, 0.001))`, the gain at the grid's lowest point.
#[test]
fn the_peak_gain_of_a_loop_with_an_integrator_is_a_pole_on_the_contour() {
    let integrator =
        StateSpace::new(dmatrix![0.0], dmatrix![1.0], dmatrix![1.0], dmatrix![0.0]).unwrap();
    let got = peak_gain(&integrator);
    assert_eq!(got, Err(AnalysisError::PoleOnContour { omega: 0.0 }));
    let summer = StateSpace::new_discrete(
        dmatrix![1.0],
        dmatrix![1.0],
        dmatrix![0.1],
        dmatrix![0.0],
        0.01,
    )
    .unwrap();
    assert_eq!(
        peak_gain(&summer),
        Err(AnalysisError::PoleOnContour { omega: 0.0 })
    );
    // A stable lag keeps its peak at ω = 0.
    let lag = StateSpace::new(dmatrix![-2.0], dmatrix![1.0], dmatrix![4.0], dmatrix![0.0]).unwrap();
    let (gain, omega) = peak_gain(&lag).unwrap();
    assert!(
        (gain - 2.0).abs() < 1e-14 && omega == 0.0,
        "{gain} at {omega}"
    );
}
