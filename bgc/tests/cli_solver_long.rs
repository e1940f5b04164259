//! Long runs with the implicit solvers: the linear oscillator of `bgc/tests/corpus/oscillator.bg` driven by
//! `sin(t)` over 1000 s. diffsol counts the Newton failures it recovers from over the whole run and gave up after
//! 50 (BDF at t ≈ 599, ESDIRK34 at t ≈ 118); every method now runs to the end and reaches the steady state.
//!
//! Reference: `m q'' + d q' + k q = sin t` (m = 2 kg, d = 4 N s/m, k = 800 N/m) has the steady state
//! `q = A sin(t − φ)`, `p = m A cos(t − φ)` with `A = 1/√((k − m)² + d²)`, `φ = atan2(d, k − m)`; the transient
//! decays as `exp(−d t / 2m)`, gone by t = 1000. In Python: `A = 1/math.hypot(798, 4)`, `phi = math.atan2(4, 798)`,
//! `A*math.sin(1000 - phi)` = 0.001032631445368177, `2*A*math.cos(1000 - phi)` = 0.0014198235640907244.

use crate::cli_support;

use cli_support::{bgc, corpus};

const AMPLITUDE: f64 = 0.001_253_117_089_600_964_7;
const Q_AT_1000: f64 = 0.001_032_631_445_368_177;
const P_AT_1000: f64 = 0.001_419_823_564_090_724_4;

#[test]
fn every_solver_runs_the_forced_oscillator_for_1000_seconds() {
    let path = corpus("oscillator.bg");
    for solver in ["bdf", "esdirk34", "tr_bdf2", "tsit45"] {
        let (code, out, err) = bgc(&[
            "simulate", &path, "--t-end", "1000", "--input", "F=sin(t)", "--solver", solver,
        ]);
        assert_eq!(code, 0, "{solver}: {err}");
        let last: Vec<f64> = out
            .lines()
            .last()
            .unwrap_or_default()
            .split(',')
            .map(|v| v.parse().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(last.first(), Some(&1000.0), "{solver}");
        let (p, q) = (last.get(1).copied(), last.get(2).copied());
        let (p, q) = (p.unwrap_or(f64::NAN), q.unwrap_or(f64::NAN));
        assert!(
            (q - Q_AT_1000).abs() <= 1e-4 * AMPLITUDE,
            "{solver}: q = {q}"
        );
        assert!(
            (p - P_AT_1000).abs() <= 1e-4 * 2.0 * AMPLITUDE,
            "{solver}: p = {p}"
        );
    }
}

/// A stiff, tiny oscillator (k = 1e12 N/m, m = 1e-6 kg) under the default tolerances: the absolute tolerance
/// 1e-9 is far above its states (1e-12 m), so the run loses 46 % of the energy balance. bgc exits 0 as before but
/// says so, with the figure; a well-resolved run says nothing.
#[test]
fn an_energy_balance_that_drifts_is_reported_with_its_figure() {
    let path = corpus("oscillator.bg");
    let stiff = [
        "simulate", &path, "--t-end", "1", "--param", "k=1e12", "--param", "m=1e-6", "--input",
        "F=1",
    ];
    let (code, _, err) = bgc(&stiff);
    assert_eq!(code, 0, "{err}");
    let figure: f64 = err
        .split("energy + dissipated - supplied changed by ")
        .nth(1)
        .and_then(|rest| rest.split(", ").nth(1))
        .and_then(|pct| pct.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN);
    assert!(figure > 10.0 && figure <= 100.0, "{err}");
    assert!(err.contains("give a smaller --rtol"), "{err}");
    for args in [
        vec!["simulate", &path, "--t-end", "3", "--input", "F=1"],
        vec!["simulate", &path, "--t-end", "1000", "--input", "F=sin(t)"],
    ] {
        let (code, _, err) = bgc(&args);
        assert_eq!(code, 0, "{err}");
        assert!(!err.contains("energy balance"), "{args:?}: {err}");
    }
}
