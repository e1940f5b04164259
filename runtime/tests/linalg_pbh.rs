//! PBH tests, stabilisability, detectability and the Kalman rank helpers on systems with known modes.

use bgc_runtime::linalg::{
    Domain, controllability_matrix, controllability_rank, is_detectable, is_stabilizable,
    observability_rank, uncontrollable_modes, unobservable_modes,
};
use nalgebra::{Complex, DMatrix};

/// A = diag(−1, 2, −3) rotated by a Householder reflection H, C = [1 0 1] H: the mode λ = 2 (direction H e₂)
/// is unobservable by construction, the others are observable.
#[test]
fn known_unobservable_real_mode() {
    let v = nalgebra::dvector![1.0, -1.0, 2.0];
    let h: DMatrix<f64> = DMatrix::identity(3, 3) - &v * v.transpose() * (2.0 / v.norm_squared());
    let a = &h * DMatrix::from_diagonal(&nalgebra::dvector![-1.0, 2.0, -3.0]) * &h;
    let c = DMatrix::from_row_slice(1, 3, &[1.0, 0.0, 1.0]) * &h;
    let modes = unobservable_modes(&a, &c).unwrap();
    assert_eq!(modes.len(), 1);
    let mode = &modes[0];
    assert!((mode.eigenvalue - Complex::new(2.0, 0.0)).norm() < 1e-12);
    // The direction is ±H e₂ (up to a complex phase): |⟨d, H e₂⟩| = 1.
    let he2 = h.column(1).map(|x| Complex::new(x, 0.0));
    assert!((mode.direction.dotc(&he2).norm() - 1.0).abs() < 1e-12);
    assert!(!is_detectable(&a, &c, Domain::Continuous).unwrap());
    assert_eq!(observability_rank(&a, &c, 1e-10).unwrap(), 2);
    // Observing state 2 of the diagonal coordinates as well makes it detectable.
    let c2 = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 1.0, 0.0, 1.0, 0.0]) * &h;
    assert!(unobservable_modes(&a, &c2).unwrap().is_empty());
    assert!(is_detectable(&a, &c2, Domain::Continuous).unwrap());
    assert_eq!(observability_rank(&a, &c2, 1e-10).unwrap(), 3);
}

/// An undamped oscillator (λ = ±i) next to a stable mode, measured only on the stable mode: the oscillator is
/// unobservable and, lying on the imaginary axis, undetectable; in discrete time with |λ| = 0.5 for the pair it
/// would be detectable.
#[test]
fn unobservable_complex_pair() {
    let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
    let c = DMatrix::from_row_slice(1, 3, &[0.0, 0.0, 1.0]);
    let modes = unobservable_modes(&a, &c).unwrap();
    assert_eq!(modes.len(), 1, "one of each conjugate pair is reported");
    let mode = &modes[0];
    assert!((mode.eigenvalue.re).abs() < 1e-12 && (mode.eigenvalue.im - 1.0).abs() < 1e-12);
    // A v = λ v and C v = 0.
    let ac = a.map(|x| Complex::new(x, 0.0));
    let residual = &ac * &mode.direction - &mode.direction * mode.eigenvalue;
    assert!(residual.norm() < 1e-12);
    assert!(mode.direction[2].norm() < 1e-12);
    assert!(!is_detectable(&a, &c, Domain::Continuous).unwrap());
    let a_slow = DMatrix::from_row_slice(3, 3, &[0.0, 0.5, 0.0, -0.5, 0.0, 0.0, 0.0, 0.0, 0.9]);
    assert!(is_detectable(&a_slow, &c, Domain::Discrete).unwrap());
}

/// Two identical integrators driven by one input: the mode λ = 0 has an uncontrollable direction (1, −1)/√2.
#[test]
fn uncontrollable_mode_and_ranks() {
    let a = DMatrix::<f64>::zeros(2, 2);
    let b = DMatrix::from_row_slice(2, 1, &[1.0, 1.0]);
    let modes = uncontrollable_modes(&a, &b).unwrap();
    assert!(!modes.is_empty());
    let w = &modes[0].direction;
    // wᴴ B = 0 and |w₀| = |w₁| = 1/√2.
    assert!((w[0] + w[1]).norm() < 1e-12);
    assert!((w[0].norm() - 0.5f64.sqrt()).abs() < 1e-12);
    assert!(!is_stabilizable(&a, &b, Domain::Continuous).unwrap());
    assert_eq!(controllability_rank(&a, &b, 1e-10).unwrap(), 1);
    // The double integrator is controllable: [B AB] = [[0, 1], [1, 0]].
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    assert_eq!(
        controllability_matrix(&a, &b).unwrap(),
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 1.0, 0.0])
    );
    assert!(uncontrollable_modes(&a, &b).unwrap().is_empty());
    assert!(is_stabilizable(&a, &b, Domain::Discrete).unwrap());
}

/// The stiff back-support plant (stiffness/inertia ratios of 3·10⁸) with motor-torque input is controllable
/// and, measured by motor velocity and human-side torque (C' of the paper, Sec. 4), observable: the rank
/// decisions must not be fooled by the scaling.
#[test]
fn back_support_plant_is_controllable_and_observable() {
    let (jm, jg, rg, kg) = (3.06e-4, 0.40e-4, 160.0, 2.64e4);
    let (jsi, jse, ks) = (1e-4, 1.19e-3, 3.38e4);
    let (bg, dg, keh) = (0.65, 6.0, 1125.0);
    let j = jm + jg;
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(6, 6, &[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0,
        -kg / (j * rg * rg), -(bg + dg) / (j * rg * rg), kg / (j * rg), dg / (j * rg), 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
        kg / (jsi * rg), dg / (jsi * rg), -(kg + ks) / jsi, -dg / jsi, ks / jsi, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        0.0, 0.0, ks / jse, 0.0, -(keh + ks) / jse, 0.0,
    ]);
    let b = DMatrix::from_row_slice(6, 1, &[0.0, 1.0 / j, 0.0, 0.0, 0.0, 0.0]);
    let c = DMatrix::from_row_slice(
        2,
        6,
        &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, keh, 0.0],
    );
    assert!(uncontrollable_modes(&a, &b).unwrap().is_empty());
    assert!(unobservable_modes(&a, &c).unwrap().is_empty());
}

/// A NaN rank tolerance compared false with every singular value and gave rank 0 for the identity; a
/// non-square "quasi-triangular" matrix made `diagonal_blocks` index out of range.
#[test]
fn a_nan_rank_tolerance_and_a_non_square_schur_factor_are_errors() {
    use bgc_runtime::linalg::pbh::numerical_rank;
    use bgc_runtime::linalg::schur::diagonal_blocks;
    let i2 = DMatrix::<f64>::identity(2, 2);
    for tol in [f64::NAN, -1e-10, f64::INFINITY] {
        assert!(numerical_rank(&i2, tol).is_err(), "{tol}");
    }
    assert_eq!(numerical_rank(&i2, 1e-10), Ok(2));
    use bgc_runtime::linalg::SchurError;
    let not_square = |rows, cols| Err(SchurError::NotSquare { rows, cols });
    assert_eq!(
        diagonal_blocks(&DMatrix::from_element(3, 1, 1.0)),
        not_square(3, 1)
    );
    assert_eq!(
        diagonal_blocks(&DMatrix::from_element(1, 3, 1.0)),
        not_square(1, 3)
    );
    // Two 2x2 blocks that overlap (non-zero subdiagonal entries at rows 1 and 2).
    let overlapping = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 3.0, 1.0, 2.0, 0.0, 3.0, 1.0]);
    assert_eq!(
        diagonal_blocks(&overlapping),
        Err(SchurError::NotQuasiTriangular { row: 1 })
    );
}

/// The QR iteration of a matrix with a NaN or infinite entry returned NaN "eigenvalues" and a NaN factor as if
/// they were a decomposition; both now name the entry.
#[test]
fn schur_and_eigenvalues_of_a_non_finite_matrix_name_the_entry() {
    use bgc_runtime::linalg::SchurError;
    use bgc_runtime::linalg::eigenvalues;
    use bgc_runtime::linalg::schur::real_schur;
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut a = DMatrix::<f64>::identity(3, 3);
        a[(2, 1)] = bad;
        let want = SchurError::NonFinite { row: 2, col: 1 };
        assert_eq!(eigenvalues(&a), Err(want), "{bad}");
        assert_eq!(real_schur(&a).err(), Some(want), "{bad}");
    }
    let rect = DMatrix::<f64>::zeros(2, 3);
    assert_eq!(
        eigenvalues(&rect),
        Err(SchurError::NotSquare { rows: 2, cols: 3 })
    );
}

/// Scaling `A` and `B` by the same factor moves every eigenvalue by that factor and changes no PBH margin (the
/// test balances `A` and scales `B` to `A`'s norm). At 1e200 the norms of `A` overflowed, the scaled `B` became
/// NaN and the SVD panicked; at 1e-200 they underflowed.
#[test]
fn margins_do_not_depend_on_the_magnitude_of_the_data() {
    use bgc_runtime::linalg::pbh::controllability_margins;
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 0.1]);
    let reference = controllability_margins(&a, &b).expect("unit scale");
    assert_eq!(reference.len(), 2);
    for s in [1e-300, 1e-200, 1e-100, 1e100, 1e200, 1e300] {
        let modes = controllability_margins(&(&a * s), &(&b * s)).expect("any finite scale");
        assert_eq!(modes.len(), reference.len(), "{s:e}");
        for (m, r) in modes.iter().zip(&reference) {
            assert!(
                (m.margin - r.margin).abs() <= 1e-12 * r.margin,
                "{s:e}: {m:?}"
            );
            assert!(
                (m.eigenvalue / s - r.eigenvalue).norm() <= 1e-12,
                "{s:e}: {m:?}"
            );
        }
        let stabilizable = is_stabilizable(&(&a * s), &(&b * s), Domain::Continuous);
        assert_eq!(stabilizable, Ok(true), "{s:e}");
    }
    // B alone in other units, down to a subnormal magnitude (whose norm made the scale of B infinite).
    for s in [1e-310, 1e-300, 1e-150, 1e150, 1e300] {
        let modes = controllability_margins(&a, &(&b * s)).expect("any finite scale of B");
        for (m, r) in modes.iter().zip(&reference) {
            assert!(
                (m.margin - r.margin).abs() <= 1e-12 * r.margin,
                "B·{s:e}: {m:?}"
            );
        }
    }
}

/// A matrix of subnormal entries has subnormal eigenvalues, not a failed decomposition: its scale to unit size
/// is kept where the reciprocal is finite (nalgebra divides by multiplying with it; 2⁻¹⁰²⁸ gave inf · 0).
#[test]
fn eigenvalues_of_a_subnormal_matrix_are_found() {
    use bgc_runtime::linalg::eigenvalues;
    let a = DMatrix::from_row_slice(2, 2, &[1e-310, 0.0, 0.0, -2e-310]);
    let mut found: Vec<f64> = eigenvalues(&a)
        .expect("subnormal but finite")
        .iter()
        .map(|l| l.re)
        .collect();
    found.sort_by(f64::total_cmp);
    assert!(
        (found[0] + 2e-310).abs() <= 1e-322 && (found[1] - 1e-310).abs() <= 1e-322,
        "{found:?}"
    );
}

/// Finite entries near the top of f64 whose eigenvalues exceed it: an error, never an infinite eigenvalue.
#[test]
fn eigenvalues_beyond_f64_are_an_error() {
    use bgc_runtime::linalg::SchurError;
    use bgc_runtime::linalg::eigenvalues;
    use bgc_runtime::linalg::schur::real_schur;
    // [[M, M], [M, M]] has the eigenvalue 2M.
    let a = DMatrix::from_element(2, 2, f64::MAX);
    assert_eq!(eigenvalues(&a), Err(SchurError::OutOfRange { n: 2 }));
    assert_eq!(real_schur(&a).err(), Some(SchurError::OutOfRange { n: 2 }));
}

/// A model without states (a static gain, `StateSpace` of a divider) has a 0×0 `A`: its eigenvalues are none, and
/// its Schur factors are empty (the PBH tests refuse it by name). `eigenvalues` panicked inside nalgebra ("Matrix index
/// out of bounds").
#[test]
fn a_matrix_without_states_has_no_eigenvalues() {
    use bgc_runtime::linalg::eigenvalues;
    use bgc_runtime::linalg::schur::real_schur;
    let empty = DMatrix::<f64>::zeros(0, 0);
    assert_eq!(eigenvalues(&empty), Ok(Vec::new()));
    let (u, t) = real_schur(&empty).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((u.shape(), t.shape()), ((0, 0), (0, 0)));
    let b = DMatrix::<f64>::zeros(0, 2);
    let refused = uncontrollable_modes(&empty, &b).map(|m| m.len());
    assert!(
        refused.as_ref().is_err_and(|e| e.to_string().contains("A")),
        "{refused:?}"
    );
}
