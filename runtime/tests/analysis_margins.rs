//! Stability margins and bandwidth against python-control 0.10.2.

use bgc_runtime::analysis::{
    AnalysisError, FeedbackSign, bandwidth, feedback, stability_margins, static_gain,
};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

/// Controllable canonical form of `num(s) / den(s)` (monic `den`, `deg num < deg den`), coefficients in
/// descending powers.
fn tf(num: &[f64], den: &[f64]) -> StateSpace {
    let n = den.len() - 1;
    let mut a = DMatrix::zeros(n, n);
    for j in 0..n {
        a[(0, j)] = -den[j + 1] / den[0];
    }
    for i in 1..n {
        a[(i, i - 1)] = 1.0;
    }
    let mut b = DMatrix::zeros(n, 1);
    b[(0, 0)] = 1.0;
    let mut c = DMatrix::zeros(1, n);
    for (k, &v) in num.iter().rev().enumerate() {
        c[(0, n - 1 - k)] = v / den[0];
    }
    StateSpace::new(a, b, c, DMatrix::zeros(1, 1)).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn margins_of_type_one_third_order_loop_match_python_control() {
    // import control, numpy as np
    // L = control.tf([2], [1, 3, 2, 0])
    // gm, pm, sm, wpc, wgc, wms = control.stability_margins(L)
    // -> (2.9999999999999996, 32.61309704777443, 0.4324672140868271,
    //     1.414213562373095, 0.7493682758222622, 0.9252900062100639)
    // pm * np.pi / 180 / wgc -> 0.7595810246057341
    let m = stability_margins(&tf(&[2.0], &[1.0, 3.0, 2.0, 0.0])).unwrap();
    assert!(rel(m.gain_margin, 2.9999999999999996) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 32.61309704777443) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.4324672140868271) < 1e-6, "{m:?}");
    // python-control's wpc, 1.414213562373095, is √2.
    assert!(rel(m.phase_crossover.unwrap(), std::f64::consts::SQRT_2) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 0.7493682758222622) < 1e-6);
    assert!(rel(m.stability_margin_frequency.unwrap(), 0.9252900062100639) < 1e-4);
    assert!(rel(m.delay_margin, 0.7595810246057341) < 1e-6, "{m:?}");
    // Hand check: L(j√2) = −1/3 exactly, so GM = 3 at ω = √2.
    assert!((m.phase_crossover.unwrap() - 2f64.sqrt()).abs() < 1e-12);
    assert_eq!(m.gain_increase_margin, Some(m.gain_margin));
    assert_eq!(m.gain_reduction_margin, None);
}

#[test]
fn conditionally_stable_loop_reports_gain_reduction_margin() {
    // L = control.tf([1, 2, 1], [1, 0.1, 0, 0])          # (s+1)^2 / (s^2 (s+0.1))
    // control.stability_margins(L, returnall=True)
    // -> gm [0.39999999999999986], pm [25.21936079389738], sm [0.4180272816092455],
    //    wpc [0.8944271909999159], wgc [1.4634862345668866], wms [1.3658474112084331]
    // Closed-loop poles -0.2557±1.2781j, -0.5886: stable, yet the gain can only be *reduced* by 0.4.
    let m = stability_margins(&tf(&[1.0, 2.0, 1.0], &[1.0, 0.1, 0.0, 0.0])).unwrap();
    assert!(rel(m.gain_margin, 0.39999999999999986) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 25.21936079389738) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.4180272816092455) < 1e-6, "{m:?}");
    assert!(rel(m.phase_crossover.unwrap(), 0.8944271909999159) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 1.4634862345668866) < 1e-6);
    assert_eq!(m.gain_reduction_margin, Some(m.gain_margin));
    assert_eq!(m.gain_increase_margin, None);
    assert_eq!(m.all_gain_margins.len(), 1);
}

#[test]
fn unstable_loop_has_negative_phase_margin() {
    // L = control.tf([1, 1], [1, 0.5, 0, 0]); control.stability_margins(L)
    // -> (inf, -17.778778686091556, 0.30237259350562207, nan, 1.1080643243973851, 1.1405435396956929)
    let m = stability_margins(&tf(&[1.0, 1.0], &[1.0, 0.5, 0.0, 0.0])).unwrap();
    assert_eq!(m.gain_margin, f64::INFINITY);
    assert_eq!(m.phase_crossover, None);
    assert!(rel(m.phase_margin, -17.778778686091556) < 1e-6, "{m:?}");
    assert!(rel(m.gain_crossover.unwrap(), 1.1080643243973851) < 1e-6);
    assert!(rel(m.stability_margin, 0.30237259350562207) < 1e-6);
    // Delay needed to go once more round: (360 − 17.78)° / ω_gc.
    let expected = (360.0 - 17.778778686091556f64).to_radians() / 1.1080643243973851;
    assert!(rel(m.delay_margin, expected) < 1e-6);
}

#[test]
fn discrete_loop_margins_match_python_control() {
    // Ld = control.c2d(control.ss(control.tf([2], [1, 3, 2, 0])), 0.1, "zoh")
    // control.stability_margins(Ld, method="poly")
    // -> (2.6157711327524815, 30.47395500613368, 0.4032916786762017,
    //     1.3186348706792617, 0.7492500020505105, 0.9113772936293036)
    let a = DMatrix::from_row_slice(
        3,
        3,
        &[
            0.7326240881200041,
            -0.17221332991595545,
            0.0,
            0.08610666495797771,
            0.9909440829939373,
            0.0,
            0.0045279585030313565,
            0.09969054046707176,
            1.0,
        ],
    );
    let b = DMatrix::from_column_slice(
        3,
        1,
        &[
            0.08610666495797772,
            0.004527958503031356,
            0.00015472976646410845,
        ],
    );
    let c = DMatrix::from_row_slice(1, 3, &[0.0, 0.0, 2.0]);
    let sys = StateSpace::new_discrete(a, b, c, DMatrix::zeros(1, 1), 0.1).unwrap();
    let m = stability_margins(&sys).unwrap();
    assert!(rel(m.gain_margin, 2.6157711327524815) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 30.47395500613368) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.4032916786762017) < 1e-6, "{m:?}");
    assert!(rel(m.phase_crossover.unwrap(), 1.3186348706792617) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 0.7492500020505105) < 1e-6);
}

#[test]
fn closed_loop_bandwidth_matches_python_control() {
    // T = control.feedback(control.tf([2], [1, 3, 2, 0]), 1); control.bandwidth(T) -> 1.2619964667617574
    let l = tf(&[2.0], &[1.0, 3.0, 2.0, 0.0]);
    let one = static_gain(DMatrix::from_element(1, 1, 1.0), None).unwrap();
    let t = feedback(&l, &one, FeedbackSign::Negative).unwrap();
    let bw = bandwidth(&t, -3.0).unwrap().unwrap();
    assert!(rel(bw, 1.2619964667617574) < 1e-6, "{bw}");
}

#[test]
fn first_order_lag_bandwidth_is_its_corner() {
    // 1/(τs + 1) is −3.0103 dB at 1/τ; at exactly −3 dB the frequency is sqrt(10^0.3 − 1)/τ.
    let tau = 0.25;
    let lag = tf(&[1.0 / tau], &[1.0, 1.0 / tau]);
    let bw = bandwidth(&lag, -3.0).unwrap().unwrap();
    let expected = (10f64.powf(0.3) - 1.0).sqrt() / tau;
    assert!(rel(bw, expected) < 1e-9, "{bw} vs {expected}");
}

#[test]
fn bandwidth_of_integrator_is_refused() {
    let integrator = tf(&[1.0], &[1.0, 0.0]);
    assert_eq!(
        bandwidth(&integrator, -3.0),
        Err(AnalysisError::InfiniteDcGain)
    );
}

#[test]
fn margins_need_a_siso_loop() {
    let mimo = static_gain(DMatrix::identity(2, 2), None).unwrap();
    assert!(matches!(
        stability_margins(&mimo),
        Err(AnalysisError::NotSiso {
            inputs: 2,
            outputs: 2,
            ..
        })
    ));
}

#[test]
fn static_crossing_at_zero_frequency_and_lead_loop() {
    // control.stability_margins(control.tf([-0.5], [1, 1])) -> (2.0, inf, inf, 0.0, nan, nan)
    let m = stability_margins(&tf(&[-0.5], &[1.0, 1.0])).unwrap();
    assert_eq!(m.gain_margin, 2.0);
    assert_eq!(m.phase_crossover, Some(0.0));
    assert_eq!(m.phase_margin, f64::INFINITY);
    assert_eq!(m.delay_margin, f64::INFINITY);
    // control.stability_margins(control.tf([3, 0.5], [1, 2, 1]))
    // -> (inf, 128.07461366165205, inf, nan, 2.6251028535207204, nan)
    let m = stability_margins(&tf(&[3.0, 0.5], &[1.0, 2.0, 1.0])).unwrap();
    assert_eq!(m.gain_margin, f64::INFINITY);
    assert!(rel(m.phase_margin, 128.07461366165205) < 1e-6, "{m:?}");
    assert!(rel(m.gain_crossover.unwrap(), 2.6251028535207204) < 1e-6);
}

#[test]
fn margins_of_a_third_order_loop_with_a_pade_delay_match_python_control() {
    // L(s) = 20 / ((s+1)(s+2)(s+3)) · pade(0.1 s, 2): a 0.1 s dead time by its second-order Padé approximant.
    // num, den = control.pade(0.1, 2)                      # (s² − 60 s + 1200) / (s² + 60 s + 1200)
    // L = control.tf([20], np.polymul([1, 1], np.polymul([1, 2], [1, 3]))) * control.tf(num, den)
    // gm, pm, sm, wpc, wgc, wms = control.stability_margins(L)
    // -> (1.926681922958983, 33.93084700248076, 0.365060587701181,
    //     2.6819191479231526, 1.8382084255998228, 2.251526846838493)
    // np.deg2rad(pm) / wgc -> 0.3221642279169167
    let num = [20.0, -1200.0, 24000.0];
    let den = [1.0, 66.0, 1571.0, 7866.0, 13560.0, 7200.0];
    let m = stability_margins(&tf(&num, &den)).unwrap();
    assert!(rel(m.gain_margin, 1.926681922958983) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 33.93084700248076) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.365060587701181) < 1e-6, "{m:?}");
    assert!(rel(m.phase_crossover.unwrap(), 2.6819191479231526) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 1.8382084255998228) < 1e-6);
    assert!(rel(m.stability_margin_frequency.unwrap(), 2.251526846838493) < 1e-4);
    assert!(rel(m.delay_margin, 0.3221642279169167) < 1e-6, "{m:?}");
}

#[test]
fn margins_of_a_discrete_loop_with_two_samples_of_delay_match_python_control() {
    // L(z) = 0.2 / (z² (z − 0.9)), T = 0.05 s:
    // L = control.tf([0.2], [1, -0.9, 0, 0], 0.05); control.stability_margins(L)
    // -> (3.232928049865329, 93.67369066570518, 0.6609814857310075,
    //     13.735563974603346, 3.6565743348818955, 11.267428787710632)
    // np.deg2rad(pm) / wgc -> 0.4471163922513395 (s)
    let a = DMatrix::from_row_slice(3, 3, &[0.9, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let b = DMatrix::from_row_slice(3, 1, &[1.0, 0.0, 0.0]);
    let c = DMatrix::from_row_slice(1, 3, &[0.0, 0.0, 0.2]);
    let sys = StateSpace::new_discrete(a, b, c, DMatrix::zeros(1, 1), 0.05).unwrap();
    let m = stability_margins(&sys).unwrap();
    assert!(rel(m.gain_margin, 3.232928049865329) < 1e-6, "{m:?}");
    assert!(rel(m.phase_margin, 93.67369066570518) < 1e-6, "{m:?}");
    assert!(rel(m.stability_margin, 0.6609814857310075) < 1e-6, "{m:?}");
    assert!(rel(m.phase_crossover.unwrap(), 13.735563974603346) < 1e-6);
    assert!(rel(m.gain_crossover.unwrap(), 3.6565743348818955) < 1e-6);
    assert!(rel(m.stability_margin_frequency.unwrap(), 11.267428787710632) < 1e-4);
    assert!(rel(m.delay_margin, 0.4471163922513395) < 1e-6, "{m:?}");
}
