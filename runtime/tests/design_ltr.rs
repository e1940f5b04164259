//! Loop transfer recovery at the plant input against python-control 0.10.2, and the recovery property.
//!
//! The plant `(s + 2) / (s² + s − 3)` is unstable (pole at 1.30) and minimum phase (zero at −2); the LQR has
//! `Q = CᵀC`, `R = 1`; the real process noise enters on the first state only (not along `B`), so the plain
//! Kalman filter (`q = 0`) erodes the LQR's margins. Reference script:
//! ```python
//! import numpy as np, control as ct
//! A = np.array([[0.0, 1.0], [3.0, -1.0]]); B = np.array([[0.0], [1.0]]); C = np.array([[2.0, 1.0]])
//! G = np.array([[1.0], [0.0]]); Qn = np.array([[1.0]]); Rn = np.array([[1.0]])
//! K, _, _ = ct.lqr(A, B, C.T @ C, np.array([[1.0]]))     # [[6.605551275463972 2.9001413501215465]]
//! gm, pm, sm, wpc, wgc, wms = ct.stability_margins(ct.ss(A, B, K, 0))
//! print(gm, pm, wgc, np.deg2rad(pm) / wgc)  # 0.4541634565979932 63.47896765237388 2.575372471185769 0.43019679820945883
//! for q in [0.0, 1e2, 1e4, 1e6, 1e8]:
//!     L, _, _ = ct.lqe(A, np.hstack([G, B]), C, np.diag([Qn[0, 0], q]), Rn)
//!     ctrl = ct.ss(A - B @ K - L @ C, L, -K, 0)
//!     loop = -ct.series(ct.ss(A, B, C, 0), ctrl)
//!     gm, pm, sm, wpc, wgc, wms = ct.stability_margins(loop)
//!     print(q, L.ravel(), gm, pm, wgc, np.deg2rad(pm) / wgc, sm)
//! ```

use bgc_runtime::design::lqr;
use bgc_runtime::design::{
    LtrError, ObserverNoise, recovery_lqe, recovery_sweep, state_feedback_margins,
};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

struct Case {
    plant: StateSpace,
    k: DMatrix<f64>,
    g: DMatrix<f64>,
    qn: DMatrix<f64>,
    rn: DMatrix<f64>,
}

fn case() -> Case {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 3.0, -1.0]);
    let b = DMatrix::from_column_slice(2, 1, &[0.0, 1.0]);
    let c = DMatrix::from_row_slice(1, 2, &[2.0, 1.0]);
    let k = lqr(&a, &b, &(c.transpose() * &c), &DMatrix::identity(1, 1))
        .unwrap()
        .k;
    Case {
        plant: StateSpace::new(a, b, c, DMatrix::zeros(1, 1)).unwrap(),
        k,
        g: DMatrix::from_column_slice(2, 1, &[1.0, 0.0]),
        qn: DMatrix::identity(1, 1),
        rn: DMatrix::identity(1, 1),
    }
}

impl Case {
    fn noise(&self) -> ObserverNoise<'_> {
        ObserverNoise {
            g: &self.g,
            qn: &self.qn,
            rn: &self.rn,
        }
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// One point of the python-control sweep.
struct Reference {
    q: f64,
    l: [f64; 2],
    gain_margin: f64,
    phase_margin: f64,
    gain_crossover: f64,
    delay_margin: f64,
    stability_margin: f64,
}

/// The printout of the script, one entry per `q`.
const REFERENCE: [Reference; 5] = [
    Reference {
        q: 0.0,
        l: [1.3100477802791621, 1.140356496724742],
        gain_margin: 0.6189165574350902,
        phase_margin: 34.8906563795139,
        gain_crossover: 1.5620631093691426,
        delay_margin: 0.38984137603148195,
        stability_margin: 0.5966105096096586,
    },
    Reference {
        q: 1e2,
        l: [1.1211039120533084, 9.113573547866565],
        gain_margin: 0.5145199401869112,
        phase_margin: 49.76646819255731,
        gain_crossover: 2.1446072821386872,
        delay_margin: 0.4050106209575888,
        stability_margin: 0.8228880850598893,
    },
    Reference {
        q: 1e4,
        l: [1.0147002881870153, 99.00574025211867],
        gain_margin: 0.4612421518615461,
        phase_margin: 61.59337264037043,
        gain_crossover: 2.5236544095081017,
        delay_margin: 0.42597240966594646,
        stability_margin: 0.9740614751060045,
    },
    Reference {
        q: 1e6,
        l: [1.0014970001976222, 999.0005074904748],
        gain_margin: 0.4548813009971224,
        phase_margin: 63.28421601283395,
        gain_crossover: 2.5701500483498534,
        delay_margin: 0.4297484244845621,
        stability_margin: 0.9971835243875086,
    },
    Reference {
        q: 1e8,
        l: [1.000149970000153, 9999.000050074968],
        gain_margin: 0.4542353398474707,
        phase_margin: 63.45942986643959,
        gain_crossover: 2.5748497989862114,
        delay_margin: 0.4301516900301832,
        stability_margin: 0.9997124721091964,
    },
];

#[test]
fn recovery_sweep_matches_python_control() {
    let c = case();
    assert!(rel(c.k[(0, 0)], 6.605551275463972) < 1e-9, "{}", c.k);
    assert!(rel(c.k[(0, 1)], 2.9001413501215465) < 1e-9, "{}", c.k);
    let weights: Vec<f64> = REFERENCE.iter().map(|r| r.q).collect();
    let sweep = recovery_sweep(&c.plant, &c.k, c.noise(), &weights).unwrap();
    assert_eq!(sweep.len(), REFERENCE.len());
    for (point, r) in sweep.iter().zip(&REFERENCE) {
        let q = r.q;
        let m = &point.margins;
        assert_eq!(point.q, q);
        for (got, want) in point.observer.l.iter().zip(r.l) {
            assert!(rel(*got, want) < 1e-8, "q = {q}: L = {}", point.observer.l);
        }
        // The open loop is unstable: the reported gain margin is the allowed gain reduction.
        assert!(rel(m.gain_margin, r.gain_margin) < 1e-6, "q = {q}: {m:?}");
        assert_eq!(m.gain_reduction_margin, Some(m.gain_margin));
        assert!(rel(m.phase_margin, r.phase_margin) < 1e-6, "q = {q}: {m:?}");
        assert!(
            rel(m.gain_crossover.unwrap(), r.gain_crossover) < 1e-6,
            "q = {q}: {m:?}"
        );
        assert!(rel(m.delay_margin, r.delay_margin) < 1e-6, "q = {q}: {m:?}");
        assert!(
            rel(m.stability_margin, r.stability_margin) < 1e-5,
            "q = {q}: {m:?}"
        );
    }
}

#[test]
fn margins_tend_to_the_lqr_loop_as_q_grows() {
    let c = case();
    let target = state_feedback_margins(&c.plant, &c.k).unwrap();
    assert!(
        rel(target.gain_margin, 0.4541634565979932) < 1e-6,
        "{target:?}"
    );
    assert!(
        rel(target.phase_margin, 63.47896765237388) < 1e-6,
        "{target:?}"
    );
    assert!(
        rel(target.delay_margin, 0.43019679820945883) < 1e-6,
        "{target:?}"
    );
    // Kalman's inequality for the LQR: |1 + K (jωI − A)⁻¹ B| ≥ 1 at every ω (Anderson & Moore, Sec. 5.4).
    assert!(target.stability_margin >= 1.0 - 1e-9, "{target:?}");

    let weights = [0.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
    let sweep = recovery_sweep(&c.plant, &c.k, c.noise(), &weights).unwrap();
    let gap = |m: &bgc_runtime::analysis::StabilityMargins| {
        (
            (m.phase_margin - target.phase_margin).abs(),
            (m.gain_margin.ln() - target.gain_margin.ln()).abs(),
            (m.stability_margin - target.stability_margin).abs(),
        )
    };
    for pair in sweep.windows(2) {
        let (before, after) = (gap(&pair[0].margins), gap(&pair[1].margins));
        assert!(after.0 < before.0, "phase gap grew at q = {}", pair[1].q);
        assert!(after.1 < before.1, "gain gap grew at q = {}", pair[1].q);
        assert!(after.2 < before.2, "|1 + L| gap grew at q = {}", pair[1].q);
    }
    let last = &sweep[sweep.len() - 1].margins;
    assert!(gap(last).0 < 0.01, "{last:?}");
    assert!(gap(last).1 < 1e-3, "{last:?}");
    // The plain filter is far off: the recovery is what closes the gap.
    assert!(gap(&sweep[0].margins).0 > 25.0);
}

#[test]
fn bad_weights_and_discrete_plants_are_refused() {
    let c = case();
    for q in [-1.0, f64::NAN, f64::INFINITY] {
        match recovery_lqe(&c.plant, c.noise(), q) {
            Err(LtrError::BadWeight { q: got }) => assert!(got.is_nan() || got == q),
            other => panic!("q = {q}: {other:?}"),
        }
    }
    let sampled = StateSpace::new_discrete(
        c.plant.a().clone(),
        c.plant.b().clone(),
        c.plant.c().clone(),
        c.plant.d().clone(),
        0.01,
    )
    .unwrap();
    assert!(matches!(
        recovery_lqe(&sampled, c.noise(), 1.0),
        Err(LtrError::Discrete { dt }) if dt == 0.01
    ));
    // A noise input matrix of the wrong size is the Kalman design's shape error, with the weight named.
    let g = DMatrix::zeros(3, 1);
    let bad = ObserverNoise { g: &g, ..c.noise() };
    let err = recovery_lqe(&c.plant, bad, 1.0).unwrap_err();
    assert!(
        matches!(err, LtrError::Kalman { q, .. } if q == 1.0),
        "{err:?}"
    );
    assert!(err.to_string().contains("q = 1"), "{err}");
}
