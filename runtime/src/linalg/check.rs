//! Precondition checks shared by the solvers: shapes, finiteness, symmetry and definiteness.
//!
//! Every public solver validates its inputs with these functions before doing any arithmetic, so that bad input
//! is reported by name and position instead of propagating NaNs or panicking inside nalgebra.

use nalgebra::DMatrix;

/// Why an input matrix was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MatrixError {
    #[error("matrix {name} is {rows}x{cols}, expected {expected_rows}x{expected_cols}")]
    Shape {
        name: &'static str,
        rows: usize,
        cols: usize,
        expected_rows: usize,
        expected_cols: usize,
    },
    #[error("matrix {name} is {rows}x{cols}, expected a square matrix")]
    NotSquare {
        name: &'static str,
        rows: usize,
        cols: usize,
    },
    #[error("matrix {name} is empty")]
    Empty { name: &'static str },
    #[error("matrix {name} has a non-finite entry {value:?} at ({row}, {col})")]
    NonFinite {
        name: &'static str,
        row: usize,
        col: usize,
        value: f64,
    },
    #[error(
        "matrix {name} is not symmetric: entries ({row}, {col}) and ({col}, {row}) differ by {difference}"
    )]
    NotSymmetric {
        name: &'static str,
        row: usize,
        col: usize,
        difference: f64,
    },
    #[error(
        "matrix {name} is not positive definite: its smallest eigenvalue is {min_eigenvalue:?}"
    )]
    NotPositiveDefinite {
        name: &'static str,
        min_eigenvalue: f64,
    },
    #[error(
        "matrix {name} is not positive semidefinite: its smallest eigenvalue is {min_eigenvalue:?}"
    )]
    NotPositiveSemidefinite {
        name: &'static str,
        min_eigenvalue: f64,
    },
    #[error("{what} is not a positive finite number: {value:?}")]
    BadScalar { what: &'static str, value: f64 },
}

/// Refuses an empty matrix or one with a NaN or infinite entry.
pub fn finite(name: &'static str, m: &DMatrix<f64>) -> Result<(), MatrixError> {
    if m.is_empty() {
        return Err(MatrixError::Empty { name });
    }
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let value = m[(i, j)];
            if !value.is_finite() {
                return Err(MatrixError::NonFinite {
                    name,
                    row: i,
                    col: j,
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Refuses a non-square matrix (and checks finiteness); returns the size.
pub fn square(name: &'static str, m: &DMatrix<f64>) -> Result<usize, MatrixError> {
    if m.nrows() != m.ncols() {
        return Err(MatrixError::NotSquare {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
        });
    }
    finite(name, m)?;
    Ok(m.nrows())
}

/// Refuses a matrix whose shape is not `rows x cols` (and checks finiteness).
pub fn shape(
    name: &'static str,
    m: &DMatrix<f64>,
    rows: usize,
    cols: usize,
) -> Result<(), MatrixError> {
    if m.nrows() != rows || m.ncols() != cols {
        return Err(MatrixError::Shape {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            expected_rows: rows,
            expected_cols: cols,
        });
    }
    finite(name, m)
}

/// Refuses a matrix that is not symmetric to a relative tolerance of `1e-10` of its largest entry; this admits
/// weights that were assembled with rounding error but not a transposed or mistyped matrix.
pub fn symmetric(name: &'static str, m: &DMatrix<f64>) -> Result<(), MatrixError> {
    let scale = m.amax();
    let tolerance = 1e-10 * scale;
    for j in 0..m.ncols() {
        for i in 0..j {
            let difference = (m[(i, j)] - m[(j, i)]).abs();
            if difference > tolerance {
                return Err(MatrixError::NotSymmetric {
                    name,
                    row: i,
                    col: j,
                    difference,
                });
            }
        }
    }
    Ok(())
}

/// The smallest eigenvalue of the symmetric part of `m`.
fn min_symmetric_eigenvalue(m: &DMatrix<f64>) -> f64 {
    let sym = (m + m.transpose()) * 0.5;
    match nalgebra::SymmetricEigen::try_new(sym, f64::EPSILON, 10_000) {
        Some(eig) => eig
            .eigenvalues
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
        None => f64::NAN,
    }
}

/// Refuses a symmetric matrix that is not positive definite. Eigenvalues below `1e-14` times the largest are
/// treated as zero, so a numerically singular weight is refused too.
pub fn positive_definite(name: &'static str, m: &DMatrix<f64>) -> Result<(), MatrixError> {
    symmetric(name, m)?;
    let min_eigenvalue = min_symmetric_eigenvalue(m);
    if min_eigenvalue.is_finite() && min_eigenvalue > 1e-14 * m.amax() {
        Ok(())
    } else {
        Err(MatrixError::NotPositiveDefinite {
            name,
            min_eigenvalue,
        })
    }
}

/// Refuses a symmetric matrix with an eigenvalue below `-1e-12` times its largest entry.
pub fn positive_semidefinite(name: &'static str, m: &DMatrix<f64>) -> Result<(), MatrixError> {
    symmetric(name, m)?;
    let min_eigenvalue = min_symmetric_eigenvalue(m);
    if min_eigenvalue.is_finite() && min_eigenvalue >= -1e-12 * m.amax() {
        Ok(())
    } else {
        Err(MatrixError::NotPositiveSemidefinite {
            name,
            min_eigenvalue,
        })
    }
}

/// Refuses a scalar that is not positive and finite (a sample time, for instance).
pub fn positive_scalar(what: &'static str, value: f64) -> Result<(), MatrixError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MatrixError::BadScalar { what, value })
    }
}

/// The singular value decomposition of `m`, or `None` when it has no entries, a non-finite entry, or the iteration
/// does not converge in `max_iterations` (at least one). nalgebra's own entry points panic on an empty matrix and when a singular
/// value comes out NaN (which a non-finite entry causes), so every SVD of the crate goes through here.
pub(crate) fn svd<C: nalgebra::ComplexField<RealField = f64>>(
    m: DMatrix<C>,
    compute_u: bool,
    compute_v: bool,
    max_iterations: usize,
) -> Option<nalgebra::SVD<C, nalgebra::Dyn, nalgebra::Dyn>> {
    if m.is_empty() || max_iterations == 0 || !m.iter().all(|v| v.clone().abs().is_finite()) {
        return None;
    }
    let mut svd =
        nalgebra::SVD::try_new_unordered(m, compute_u, compute_v, f64::EPSILON, max_iterations)?;
    if !svd.singular_values.iter().all(|s| s.is_finite()) {
        return None;
    }
    svd.sort_by_singular_values();
    Some(svd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetry_tolerates_rounding_but_not_mistakes() {
        let rounding = DMatrix::from_row_slice(2, 2, &[1e12, 1.0 + 1e-6, 1.0, 1.0]);
        assert!(symmetric("Q", &rounding).is_ok());
        let mistake = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 0.0, 1.0]);
        assert_eq!(
            symmetric("Q", &mistake),
            Err(MatrixError::NotSymmetric {
                name: "Q",
                row: 0,
                col: 1,
                difference: 2.0
            })
        );
    }

    /// [[1, 2], [2, 1]] has eigenvalues 3 and −1; [[1, 1], [1, 1]] has 2 and 0.
    #[test]
    fn definiteness() {
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        match positive_semidefinite("Q", &indefinite) {
            Err(MatrixError::NotPositiveSemidefinite { min_eigenvalue, .. }) => {
                assert!((min_eigenvalue + 1.0).abs() < 1e-12)
            }
            other => panic!("{other:?}"),
        }
        let singular = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        assert!(positive_semidefinite("Q", &singular).is_ok());
        assert!(matches!(
            positive_definite("R", &singular),
            Err(MatrixError::NotPositiveDefinite { name: "R", .. })
        ));
        assert!(positive_definite("R", &DMatrix::from_element(1, 1, 1e12)).is_ok());
    }

    #[test]
    fn shapes_and_values() {
        assert_eq!(
            square("A", &DMatrix::zeros(0, 0)),
            Err(MatrixError::Empty { name: "A" })
        );
        assert!(matches!(
            shape("B", &DMatrix::zeros(3, 1), 2, 1),
            Err(MatrixError::Shape {
                name: "B",
                rows: 3,
                cols: 1,
                expected_rows: 2,
                expected_cols: 1
            })
        ));
        assert!(matches!(
            positive_scalar("sample time", f64::NAN),
            Err(MatrixError::BadScalar { .. })
        ));
    }

    /// nalgebra's SVD panics when a singular value comes out NaN; the guard returns `None` instead, and the
    /// singular values of a finite matrix come sorted: `diag(3, 4)` has 4 and 3.
    #[test]
    fn svd_refuses_non_finite_and_empty_matrices() {
        for bad in [f64::NAN, f64::INFINITY] {
            let m = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, bad, 4.0, 5.0, 6.0]);
            assert!(svd(m, true, true, 100).is_none(), "{bad}");
        }
        assert!(svd(DMatrix::<f64>::zeros(0, 0), false, false, 100).is_none());
        let m = DMatrix::from_row_slice(2, 2, &[3.0, 0.0, 0.0, 4.0]);
        let found = svd(m, false, false, 100).expect("finite");
        assert_eq!(found.singular_values.as_slice(), &[4.0, 3.0]);
    }
}
