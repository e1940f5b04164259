//! Tests of the Kalman filter: models from state spaces, gains, the certificates of a step and its two
//! instruction sets.

use super::super::dense::symmetric_eigen;
use super::*;
use nalgebra::dmatrix;

#[test]
fn model_from_state_space_checks_shape_and_sampling() {
    let ss = StateSpace::new_discrete(
        dmatrix![1.0, 0.1; 0.0, 1.0],
        dmatrix![0.0; 0.1],
        dmatrix![1.0, 0.0],
        dmatrix![0.0],
        0.1,
    )
    .unwrap();
    let m = LinearDiscreteModel::<2, 1, 1>::from_state_space(&ss).unwrap();
    assert_eq!(m.a[(0, 1)], 0.1);
    assert_eq!(m.b[(1, 0)], 0.1);
    assert!(matches!(
        LinearDiscreteModel::<3, 1, 1>::from_state_space(&ss),
        Err(EstimationError::Shape {
            name: "A",
            rows: 2,
            expected_rows: 3,
            ..
        })
    ));
    let (a, b, c, d, _) = ss.into_parts();
    let cont = StateSpace::new(a, b, c, d).unwrap();
    assert_eq!(
        LinearDiscreteModel::<2, 1, 1>::from_state_space(&cont),
        Err(EstimationError::NotDiscrete)
    );
}

/// The benchmark's filter (7 states, 2 sensors, `Q` and `R` definite), on the portable code and on the
/// instruction set this processor has: the prediction leaves a certified eigenvalue floor that is below
/// the true smallest eigenvalue of `P⁻`, the update's certificate holds (no factorisation of `P` in the
/// step), and a new estimate drops the floor, so that the next update tests its result again.
#[test]
fn a_step_with_definite_noise_is_certified_and_a_new_estimate_is_tested_again() {
    let mut a = SMatrix::<f64, 7, 7>::identity();
    for i in 0..6 {
        a[(i, i + 1)] = 0.001;
    }
    a[(6, 0)] = -0.002;
    let model = LinearDiscreteModel {
        a,
        b: SMatrix::<f64, 7, 1>::from_fn(|i, _| 0.001 * (i + 1) as f64),
        c: SMatrix::<f64, 2, 7>::from_fn(|i, j| if j == 3 * i { 1.0 } else { 0.0 }),
        d: SMatrix::<f64, 2, 1>::zeros(),
    };
    let (q, r) = (SMatrix::identity() * 1e-4, SMatrix::identity() * 1e-2);
    for isa in [Isa::Portable, Isa::detect()] {
        let mut kf = KalmanFilter::new(model, q, r, SVector::zeros(), SMatrix::identity()).unwrap();
        kf.fixed.isa = isa;
        let (u, y) = (
            SVector::<f64, 1>::new(0.3),
            SVector::<f64, 2>::new(0.01, -0.02),
        );
        for _ in 0..50 {
            assert_eq!(kf.predict(&u), Ok(None));
            let floor = kf.eigenvalue_floor;
            let lowest = symmetric_eigen(&kf.p).unwrap().0.min();
            assert!(
                floor > 0.0 && floor <= lowest,
                "floor {floor:e}, λ_min {lowest:e}"
            );
            // The update's certificate for this step, from the quantities `update` computes, with the
            // arithmetic of the filter's instruction set (a fused multiply-add outside the fast copy is
            // slower and rounds the same).
            let (next, norms) = match isa {
                Isa::Portable => joseph_step::<Separate, 7, 1, 2>(&kf),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2Fma => joseph_step::<Fused, 7, 1, 2>(&kf),
            };
            assert!(kf.fixed.definite_update.holds(floor, &norms));
            let outcome = kf.update(&y, &u).unwrap();
            assert!(matches!(
                outcome,
                UpdateOutcome::Accepted { repair: None, .. }
            ));
            assert_eq!(*kf.covariance(), next, "{isa:?}");
            assert_eq!(kf.eigenvalue_floor, 0.0);
        }
        kf.predict(&u).unwrap();
        kf.set_state(SVector::zeros(), SMatrix::identity()).unwrap();
        assert_eq!(kf.eigenvalue_floor, 0.0);
    }
}

/// The portable code and the code for this processor's instruction set (fused multiply-adds, wider
/// vectors) compute the same filter: over 200 steps of a 7-state filter with 2 sensors and varying
/// measurements, estimates and covariances agree to a few units of rounding. (On a processor without
/// AVX2 and FMA both filters run the portable code and agree exactly.)
#[test]
fn the_portable_and_the_fast_code_agree_to_rounding() {
    let a = SMatrix::<f64, 7, 7>::from_fn(|i, j| {
        let base = if i == j { 0.98 } else { 0.0 };
        base + 0.01 * ((3 * i + 5 * j) % 7) as f64 / 7.0
    });
    let model = LinearDiscreteModel {
        a,
        b: SMatrix::<f64, 7, 1>::from_fn(|i, _| 0.01 * (i + 1) as f64),
        c: SMatrix::<f64, 2, 7>::from_fn(|i, j| ((i + 2 * j) % 3) as f64 - 0.5),
        d: SMatrix::<f64, 2, 1>::new(0.1, 0.0),
    };
    let q = SMatrix::<f64, 7, 7>::from_fn(|i, j| if i == j { 1e-3 } else { 1e-5 });
    let r = SMatrix::<f64, 2, 2>::new(1e-2, 2e-3, 2e-3, 3e-2);
    let start = |isa| {
        let mut kf = KalmanFilter::new(model, q, r, SVector::zeros(), SMatrix::identity()).unwrap();
        kf.fixed.isa = isa;
        kf
    };
    let (mut portable, mut fast) = (start(Isa::Portable), start(Isa::detect()));
    for step in 0..200 {
        let t = step as f64 * 0.05;
        let u = SVector::<f64, 1>::new(t.sin());
        let y = SVector::<f64, 2>::new((1.3 * t).cos(), 0.5 * (0.7 * t).sin());
        for kf in [&mut portable, &mut fast] {
            kf.predict(&u).unwrap();
            kf.update(&y, &u).unwrap();
        }
        let x_gap = (portable.state() - fast.state()).amax();
        let p_gap = (portable.covariance() - fast.covariance()).amax();
        assert!(
            x_gap <= 1e-12 * portable.state().amax().max(1.0),
            "step {step}: x differs by {x_gap:e}"
        );
        assert!(
            p_gap <= 1e-12 * portable.covariance().amax(),
            "step {step}: P differs by {p_gap:e}"
        );
    }
}

/// The Joseph covariance an optimal update of `kf` computes and the norms of its certificate.
fn joseph_step<M: MulAdd, const NX: usize, const NU: usize, const NY: usize>(
    kf: &KalmanFilter<NX, NU, NY>,
) -> (SMatrix<f64, NX, NX>, UpdateNorms) {
    let ct = &kf.fixed.ct;
    let pct = covariance_times_ct::<M, NX, NY>(&kf.p, ct);
    let s = innovation_covariance::<M, NX, NY>(&pct, ct, &kf.r);
    let k = InnovationFactor::new(cholesky_lower(&s).unwrap()).gain::<M, NX>(&pct);
    let mut next = SMatrix::zeros();
    let w = joseph::<M, NX, NY>(&kf.p, &k, &pct, &s, &mut next);
    let norms = UpdateNorms {
        trace_p: kf.p.trace(),
        pct: frobenius::<M, NX, NY>(&pct),
        s: frobenius::<M, NY, NY>(&s),
        k: frobenius::<M, NX, NY>(&k),
        w: frobenius::<M, NX, NY>(&w),
    };
    (next, norms)
}

/// A prediction whose covariance overflows (`A = 10²⁰⁰ I`, so `A P Aᵀ = 10⁴⁰⁰ I`) is not certified, even
/// with a definite `Q`: it is an error and the filter keeps its estimate.
#[test]
fn a_prediction_that_overflows_is_an_error_with_a_definite_q() {
    let model = LinearDiscreteModel {
        a: SMatrix::<f64, 2, 2>::identity() * 1e200,
        b: SMatrix::<f64, 2, 1>::zeros(),
        c: SMatrix::<f64, 1, 2>::new(1.0, 0.0),
        d: SMatrix::<f64, 1, 1>::zeros(),
    };
    let q = SMatrix::<f64, 2, 2>::identity() * 1e-4;
    let r = SMatrix::<f64, 1, 1>::new(1e-2);
    let mut kf = KalmanFilter::new(model, q, r, SVector::zeros(), SMatrix::identity()).unwrap();
    assert_eq!(
        kf.predict(&SVector::zeros()),
        Err(EstimationError::NonFiniteCovariance { filter: FILTER })
    );
    assert_eq!(*kf.covariance(), SMatrix::<f64, 2, 2>::identity());
}

/// `A` singular: a predictor gain cannot be turned back into a filter gain.
#[test]
fn filter_gain_from_predictor_needs_invertible_a() {
    let a = SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 4.0);
    let l = SMatrix::<f64, 2, 1>::new(0.1, 0.2);
    assert_eq!(
        filter_gain_from_predictor(&a, &l),
        Err(EstimationError::SingularMatrix { name: "A" })
    );
}
