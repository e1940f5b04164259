//! Matrix exponential, zero-order hold and Van Loan discretisation against scipy and hand calculations.
#![allow(clippy::excessive_precision)] // reference values are pasted from numpy at full precision

use bgc_runtime::linalg::{DiscretizeError, ExpmError, MatrixError, c2d_zoh, expm, van_loan};
use bgc_runtime::statespace::StateSpace;
use nalgebra::DMatrix;

fn m4() -> DMatrix<f64> {
    DMatrix::from_row_slice(
        4,
        4,
        &[
            -0.1, 0.02, 0.0, 0.3, 0.5, -0.4, 0.1, 0.0, 0.0, 0.2, 0.9, -0.5, 1.0, 0.0, 0.3, -1.2,
        ],
    )
}

/// ```python
/// import numpy as np, scipy.linalg as sl
/// M = np.array([[-0.1, 0.02, 0.0, 0.3], [0.5, -0.4, 0.1, 0.0], [0.0, 0.2, 0.9, -0.5], [1.0, 0.0, 0.3, -1.2]])
/// for s in [0.005, 0.01, 0.2, 0.5, 1.0, 3.0, 40.0]: print(sl.expm(M*s))
/// ```
/// ‖M‖₁ = 2, so the scales exercise the Padé degrees 3 (‖sM‖₁ = 0.01), 5 (0.02), 7 (0.4), 9 (1, 2) and 13 with
/// one (6) and five (80) squarings.
#[test]
fn expm_matches_scipy_across_pade_degrees() {
    let cases: [(f64, [f64; 4]); 7] = [
        // (scale, [E00, E12, E22, E33]) — a sample of entries from each reference matrix
        (
            0.005,
            [
                0.9995039911191224,
                0.0005006269586354266,
                1.0045085139067094,
                0.9940198281412862,
            ],
        ),
        (
            0.01,
            [
                9.9901592907229053e-01,
                1.0025156715419523e-03,
                1.0090341113409067e+00,
                9.8807912575882828e-01,
            ],
        ),
        (
            0.2,
            [
                0.9858669582574265,
                0.02112636449075365,
                1.1945185915565733,
                0.7889872228156543,
            ],
        ),
        (
            0.5,
            [
                0.9824142080737309,
                0.05826374986138211,
                1.5501268756443594,
                0.5587176288081164,
            ],
        ),
        (
            1.0,
            [
                1.0073641770956738,
                0.14195086667510873,
                2.3733867693881594,
                0.3172427355311793,
            ],
        ),
        (
            3.0,
            [
                1.2112633925921732,
                1.1978882740213421,
                12.68948405953771,
                -0.3211226411528591,
            ],
        ),
        (
            40.0,
            [
                -3.8312478351471587e+12,
                3.2122190677012547e+13,
                3.0568137761496138e+14,
                -1.4973322374238262e+13,
            ],
        ),
    ];
    for (s, reference) in cases {
        let e = expm(&(m4() * s)).unwrap();
        let got = [e[(0, 0)], e[(1, 2)], e[(2, 2)], e[(3, 3)]];
        let scale = e.amax();
        for (g, r) in got.iter().zip(reference) {
            assert!((g - r).abs() < 1e-13 * scale, "s = {s}: {g} vs {r}");
        }
    }
    // Full matrix at s = 1.
    let e1_ref = DMatrix::from_row_slice(
        4,
        4,
        &[
            1.0073641770956738,
            0.01900366135125575,
            0.04474903490889269,
            0.16747078455240821,
            0.40235635861615454,
            0.6851628760682638,
            0.14195086667510873,
            0.02220260036264858,
            -0.18191142566210064,
            0.2693546983171696,
            2.3733867693881594,
            -0.5176599831903094,
            0.5630849601857101,
            0.03230911532316672,
            0.3135053969207952,
            0.3172427355311793,
        ],
    );
    assert!((expm(&m4()).unwrap() - e1_ref).amax() < 1e-14);
}

#[test]
fn expm_identities_and_errors() {
    // exp(0) = I; exp of a rotation generator is the rotation.
    let z = expm(&DMatrix::zeros(3, 3)).unwrap();
    assert_eq!(z, DMatrix::identity(3, 3));
    let t = 2.0;
    let r = expm(&DMatrix::from_row_slice(2, 2, &[0.0, -t, t, 0.0])).unwrap();
    let r_ref = DMatrix::from_row_slice(2, 2, &[t.cos(), -t.sin(), t.sin(), t.cos()]);
    assert!((r - r_ref).amax() < 1e-15);
    assert!(matches!(
        expm(&DMatrix::from_element(2, 2, f64::NAN)),
        Err(ExpmError::Input(MatrixError::NonFinite { .. }))
    ));
    assert!(matches!(
        expm(&DMatrix::zeros(2, 3)),
        Err(ExpmError::Input(MatrixError::NotSquare { .. }))
    ));
    assert!(matches!(
        expm(&DMatrix::from_element(1, 1, 1000.0)),
        Err(ExpmError::Overflow { .. })
    ));
    // An error names an extreme number in a few characters (Display of 1e300 is 301 digits long).
    let message = expm(&DMatrix::from_element(1, 1, 1e300))
        .unwrap_err()
        .to_string();
    assert_eq!(message, "the exponential overflows (‖A‖₁ = 1e300)");
}

/// Lightly damped oscillator sampled at 50 ms:
/// ```python
/// import numpy as np, scipy.signal as ss
/// A = np.array([[0.0, 1.0], [-4.0, -0.4]]); B = np.array([[0.0], [1.0]]); C = np.array([[1.0, 0.0]])
/// ss.cont2discrete((A, B, C, np.zeros((1, 1))), 0.05, method='zoh')
/// ```
#[test]
fn c2d_zoh_matches_scipy() {
    let sys = StateSpace::new(
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]),
        DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        DMatrix::zeros(1, 1),
    )
    .unwrap();
    let d = c2d_zoh(&sys, 0.05).unwrap();
    let ad_ref = DMatrix::from_row_slice(
        2,
        2,
        &[
            0.9950372994536869,
            0.04942085299780529,
            -0.1976834119912212,
            0.9752689582545647,
        ],
    );
    let bd_ref = DMatrix::from_row_slice(2, 1, &[0.00124067513657828, 0.04942085299780529]);
    assert!((d.a() - ad_ref).amax() < 1e-15);
    assert!((d.b() - bd_ref).amax() < 1e-15);
    assert_eq!(d.c(), sys.c());
    assert_eq!(d.dt(), Some(0.05));
    assert!(matches!(
        c2d_zoh(&sys, -1.0),
        Err(DiscretizeError::Input(MatrixError::BadScalar { .. }))
    ));
    assert!(matches!(
        c2d_zoh(&d, 0.1),
        Err(DiscretizeError::AlreadyDiscrete { .. })
    ));
}

/// By hand: for the double integrator with acceleration noise of intensity q,
/// `Q_d = q [[Δt³/3, Δt²/2], [Δt²/2, Δt]]` and `A_d = [[1, Δt], [0, 1]]`; for the scalar `ẋ = −a x + w`,
/// `Q_d = q (1 − e^{−2aΔt}) / (2a)`.
#[test]
fn van_loan_matches_hand_computation() {
    let (q, dt) = (0.3, 0.02);
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let gqg = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, q]);
    let (ad, qd) = van_loan(&a, &gqg, dt).unwrap();
    let qd_ref = DMatrix::from_row_slice(
        2,
        2,
        &[
            q * dt.powi(3) / 3.0,
            q * dt * dt / 2.0,
            q * dt * dt / 2.0,
            q * dt,
        ],
    );
    assert!((ad - DMatrix::from_row_slice(2, 2, &[1.0, dt, 0.0, 1.0])).amax() < 1e-15);
    assert!((&qd - &qd_ref).amax() < 1e-14 * qd_ref.amax(), "Qd = {qd}");

    let (alpha, q, dt) = (3.0, 2.0, 0.1);
    let (ad, qd) = van_loan(
        &DMatrix::from_element(1, 1, -alpha),
        &DMatrix::from_element(1, 1, q),
        dt,
    )
    .unwrap();
    assert!((ad[(0, 0)] - (-alpha * dt).exp()).abs() < 1e-15);
    let qd_ref = q * (1.0 - (-2.0 * alpha * dt).exp()) / (2.0 * alpha);
    assert!((qd[(0, 0)] - qd_ref).abs() < 1e-15);

    let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
    assert!(matches!(
        van_loan(&a, &indefinite, dt),
        Err(DiscretizeError::Input(
            MatrixError::NotPositiveSemidefinite { .. }
        ))
    ));
}

/// Finite data whose product with the sample time leaves f64: the error names the product and the sample time,
/// not a non-finite entry of an `A` the caller never passed (as it did).
#[test]
fn a_sample_time_too_long_for_the_rates_is_named() {
    let sys = StateSpace::new(
        DMatrix::from_element(1, 1, -1.0),
        DMatrix::from_element(1, 1, 1e300),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
    )
    .expect("finite model");
    match c2d_zoh(&sys, 1e10) {
        Err(err @ DiscretizeError::Overflow { what, dt }) => {
            assert_eq!((what, dt), ("[A B]·dt", 1e10));
            assert!(err.to_string().contains("sample time is too long"), "{err}");
        }
        other => panic!("expected Overflow, got {other:?}"),
    }
    let a = DMatrix::from_element(1, 1, -1e300);
    match van_loan(&a, &DMatrix::from_element(1, 1, 1.0), 1e10) {
        Err(DiscretizeError::Overflow { what, .. }) => assert!(what.starts_with("[−A")),
        other => panic!("expected Overflow, got {other:?}"),
    }
}

/// A stable plant far faster than the sample time: `A dt = −1e301` is finite and so is its exponential (zero),
/// and `B_d = (1 − e^{A dt}) (−A)⁻¹ B = 1`. The exponential used to square the unscaled `A` first, which overflows
/// above about 1e154, and refused the plant as an overflow.
#[test]
fn a_stable_plant_far_faster_than_the_sample_time_discretises() {
    let a = DMatrix::from_element(1, 1, -1e300);
    assert_eq!(expm(&(&a * 10.0)).expect("e^(-1e301)")[(0, 0)], 0.0);
    let sys = StateSpace::new(
        a,
        DMatrix::from_element(1, 1, 1e300),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
    )
    .expect("finite model");
    let d = c2d_zoh(&sys, 10.0).expect("finite discretisation");
    assert_eq!(d.a()[(0, 0)], 0.0);
    assert!((d.b()[(0, 0)] - 1.0).abs() < 1e-12, "B_d = {}", d.b());
}
